"""Fitting a device to measured sweeps, the twin of the ``endstop fit`` command.

* :func:`sweep_data`: one measured sweep (frequencies, values, their standard deviations, the
  stated acceleration, and optionally the measured onset and jump);
* :func:`fit`: the free parameters (dotted paths with ranges) fitted by a global search (a
  design of starts ranked by a plain stepped sweep, the best refined by Levenberg-Marquardt on
  the branches of periodic orbits the sweeps follow), with standard errors, 95 % intervals,
  correlations and a warning for each combination the data do not determine (the method is the library's ``endstop::fit``,
  described in the book chapter "Fit your measurements").
"""

from . import _native


def sweep_data(freq_hz, value, accel_rms_g, *, direction="up", quantity="v1_rms_v",
               sigma=None, onset=None, jump=None, grid_hz=None, label="sweep"):
    """One measured sweep: ``value`` (``quantity`` ``"v1_rms_v"`` in V or ``"p_total_w"`` in
    W) at ``freq_hz`` (in sweep order), at ``accel_rms_g`` (g rms), ``direction`` ``"up"`` or
    ``"down"``. ``sigma``: the values' standard deviations (None: unknown, estimated from the
    residuals). ``onset``, ``jump``: ``(freq_hz, sigma_hz)`` of the measured impact onset and
    jump. ``grid_hz``: the simulated sweep's frequencies (default: ``freq_hz``)."""
    return {
        "label": label,
        "direction": direction,
        "quantity": quantity,
        "accel_rms_g": float(accel_rms_g),
        "freq_hz": [float(f) for f in freq_hz],
        "value": [float(v) for v in value],
        "sigma": None if sigma is None else [float(s) for s in sigma],
        "onset": onset,
        "jump": jump,
        "grid_hz": None if grid_hz is None else [float(f) for f in grid_hz],
    }


def fit(device, sweeps, free):
    """Fits ``free`` (a dict ``{path: (lo, hi)}``, e.g. ``{"stops.both.gap_m": (7e-6, 1e-5)}``;
    ``"drive.accel_scale"`` is a factor on every sweep's acceleration) of ``device`` to
    ``sweeps`` (a list of :func:`sweep_data` dicts); the device's values are one start of the
    design among the others. A device with an interface circuit is refused (``ValueError``
    naming it): the fit models a transducer on its resistive load.

    Returns a dict: ``params`` (one dict per free parameter: ``path``, ``start``, ``value``,
    ``std_err``, ``interval`` (95 %), ``range``), ``correlation``, ``warnings`` (strings),
    ``uncertainty`` (the method, in words), ``device`` (the fitted :class:`endstop.Device`),
    ``ssr``, ``dof``, ``reduced_chi2`` (chi-square per degree of freedom, beside every
    interval), ``chi2_p``, ``model`` (in words), ``headline`` (None, or what must be read
    first: a value at an end of its range, an improbable chi-square, no convergence),
    ``starts_tried``, ``starts_refined``, ``starts`` (one dict per start: ``origin``,
    ``values``, ``design_ssr``, ``design_cut`` (True when its sweep was stopped once past
    the starts kept: ``design_ssr`` is then a lower bound), ``refined_ssr``,
    ``refined_values``, ``settled``, ``reported``), ``singular_ratio``,
    ``evaluations``, ``converged`` and ``residuals``
    (arrays ``freq_hz``, ``measured``, ``model``, ``sigma`` and lists ``dataset``, ``what``).
    A bad path or range raises :class:`endstop.ParamError` naming the field; bad data raise
    ``ValueError``."""
    return _native.fit(device, list(sweeps), [(p, float(lo), float(hi)) for p, (lo, hi) in free.items()])
