"""Figure 13: prototype 2 at 10 V, up-sweeps from 600 to 850 Hz at 0.12 g (linear law) and
0.31 g (linear and Hertz laws), published parameters, each repeated with halved numerics.

:func:`run` returns a dict:

* ``curves``: one dict per curve (``label``, ``key``, ``accel_rms_g``, ``law``,
  ``bim_n_s_per_m``; ``in_range``: the steps of 600-850 Hz as arrays; ``sweep``: the whole
  report with ``onset_hz``, ``jump_hz``, ...; ``halved``: the repetition);
* ``numbers``: the figure's numbers under the keys of its ``summary.json``
  (``0p31g_linear_bim0p4_jump_hz``, ...);
* ``claims``: the claim values the scorecard scores (claim, quantity, set, ours, note);
* ``device``: prototype 2 at 10 V.
"""

from .. import _native


def run(device=None):
    """Runs Figure 13 on ``device`` (default: the published prototype 2; the bias is set to
    10 V here). About 10 s on two cores."""
    return _native.paper_fig13_run(device)


__all__ = ["run"]
