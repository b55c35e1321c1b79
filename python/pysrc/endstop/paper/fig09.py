"""Figure 9: prototype 1 at its measured resonance (1220 Hz), amplitude continuations from 0.5
to 5.5 g rms at 20, 30 and 40 V, for the published and the calibrated parameter set, each
repeated with halved numerics.

:func:`run` returns a dict:

* ``sets``: one dict per parameter set (``set``, ``device``, ``curves``: one per bias with
  ``bias_v``, ``sweep`` (``accel_rms_g``, ``p1_w``, ``v1_rms_v``, ... as arrays, ``onset_g``)
  and ``halved``);
* ``numbers``: the figure's numbers under the keys of its ``summary.json``
  (``published_20v_onset_g``, ``calibrated_40v_p1_at_5p5g_w``, ``calibrated_gap_m``, ...);
* ``claims``: the claim values the scorecard scores (claim, quantity, set, ours, note).
"""

from .. import _native


def run(published=None, calibrated=None):
    """Runs Figure 9. ``published``: prototype 1 (default: the published file);
    ``calibrated``: its calibrated set (default: computed by :func:`calibrate`, as the
    repository's calibration job does)."""
    return _native.paper_fig09_run(published, calibrated)


def calibrate(published=None):
    """The calibration of prototype 1 (end-stop gap fitted to the measured kink of Figure 8):
    ``device`` (the calibrated set), ``fitted_gap_m``, ``achieved_onset_hz``, ..."""
    return _native.paper_calibrate_prototype1(published)


__all__ = ["run", "calibrate"]
