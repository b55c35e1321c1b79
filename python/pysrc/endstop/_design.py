"""The designer's inverse question, the twin of the ``endstop design`` command: which values of
a device's parameters within ranges, and which interface circuit, deliver the most DC power
under a sine (the worst over a band of frequencies), within the limits the device survives.
The problem is built and solved by the library's ``endstop::design`` (the book chapter "Design
your harvester"), as the command builds and solves it."""

import os

import numpy as np

from . import _native


def design(device, ranges, freqs_hz, accel_rms_g, *, interfaces=None,
           max_impact_speed_m_s=None, max_contact_force_n=None, max_displacement_m=None,
           max_impacts_per_s=None, samples=32, seed=0):
    """Searches ``ranges`` of ``device`` (an :class:`endstop.Device` or the path of a device
    file) for the design of most DC power.

    * ``ranges``: a list of ``(path, lo, hi)`` or ``(path, lo, hi, "log" | "linear")``, the
      command's ``--range PATH=LO..HI[:log|:linear]`` (without a spacing, logarithmic for a
      positive range of a decade or more); ``path`` is a key of the device file, or
      ``"load.resistance_ohm"`` for the load of whichever interface.
    * ``freqs_hz``: a frequency, or increasing frequencies (a band, e.g.
      ``numpy.linspace(118, 122, 5)``) whose worst is the objective; ``accel_rms_g``: the RMS
      acceleration (g).
    * ``interfaces``: the circuits to choose among, each a name (``"resistive"``, or the key of
      the device's own interface) or a dict in a device file's ``[interface]`` form (the
      command's ``--interfaces`` tables); ``None``: the device's own interface.
    * ``max_impact_speed_m_s``, ``max_contact_force_n``, ``max_displacement_m``,
      ``max_impacts_per_s``: the limits (``None``: not limited).
    * ``samples``: points of the search's scrambled Sobol sample per interface; ``seed``: its
      scramble (the command's ``--samples`` and ``--seed``).

    Returns a dict: ``best`` (``verdict`` ``"optimum"``, or ``"infeasible"`` when no design
    tried meets every limit and this is the least violating; ``interface``, ``params`` (path
    to value), ``unit``, ``feasible``, ``violation``, ``power_w``, ``worst_freq_hz``,
    ``best_power_w``, ``impact_speed_m_s``, ``contact_force_n``, ``displacement_m``,
    ``impacts_per_s``, ``margins`` (per limit given, ``1 - value / limit``: negative beyond
    it), ``error``); ``per_interface`` (the same per interface, ``None`` where no design of it
    could be evaluated); ``designs`` (every design evaluated, in order: numpy arrays
    ``interface_index``, one per range path, ``evaluated``, ``feasible``, ``violation``,
    ``power_w``, ``worst_freq_hz``, ``impact_speed_m_s``, ``contact_force_n``,
    ``displacement_m``, ``impacts_per_s`` (NaN where not evaluated), and lists ``interface``,
    ``error``); ``interfaces``, ``ranges``, ``samples``, ``seed``, ``polish_starts``,
    ``max_iters``, ``budget`` (the most evaluations the search may make), ``evaluations``, and
    ``settings``, what repeats the run besides the device (as the command's ``summary.json``
    records it): ``freqs_hz``, ``accel_rms_g``, ``limits``, ``search`` (``samples``,
    ``polish_starts``, ``max_iters``, ``simplex_size``, ``sd_tolerance``, ``seed``) and
    ``steady`` (the steady state's ``rtol``, ``transient_periods``, ``max_newton``, ``tol``,
    ``jacobian``, ``max_map_periods``).

    A range or interface that does not fit the device raises :class:`endstop.ParamError`
    naming the field; a malformed problem (no range, bad frequencies or limits) ``ValueError``;
    a problem no design of which could be evaluated :class:`endstop.SolverError`. The GIL is
    released while the search runs."""
    if isinstance(device, (str, os.PathLike)):
        device = _native.Device.from_toml(device)
    freqs = [float(f) for f in np.atleast_1d(np.asarray(freqs_hz, dtype=float))]
    return _native.design(
        device, list(ranges), freqs, float(accel_rms_g),
        interfaces=None if interfaces is None else list(interfaces),
        max_impact_speed_m_s=max_impact_speed_m_s, max_contact_force_n=max_contact_force_n,
        max_displacement_m=max_displacement_m, max_impacts_per_s=max_impacts_per_s,
        samples=int(samples), seed=int(seed))
