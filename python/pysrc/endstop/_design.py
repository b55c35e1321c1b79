"""The designer's inverse question, the twin of the ``endstop design`` command: which values of
a device's parameters within ranges, and which interface circuit, deliver the most DC power
under a sine (the worst over a band of frequencies), under band-limited white noise (the mean
over an ensemble of records) or over a measured acceleration record (the mean over it), within
the limits the device survives.
The problem is built and solved by the library's ``endstop::design`` (the book chapter "Design
your harvester"), as the command builds and solves it."""

import os

import numpy as np

from . import _native


def design(device, ranges, freqs_hz=None, accel_rms_g=None, *, interfaces=None,
           max_impact_speed_m_s=None, max_contact_force_n=None, max_displacement_m=None,
           max_impacts_per_s=None, samples=32, seed=0, psd_g2_per_hz=None, records=8,
           duration_s=2.0, noise_band_hz=10e3, noise_seed=2012, accel_m_s2=None,
           sample_rate_hz=None, integrator_rate_hz=None):
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
    * ``psd_g2_per_hz``: in place of ``freqs_hz`` and ``accel_rms_g``, the two-sided density
      (g^2/Hz) of band-limited white noise up to ``noise_band_hz`` (sampled at ten times it):
      the objective is then the mean DC power over ``records`` records of ``duration_s`` s
      each, streams ``0..records`` of ``noise_seed``, the same records for every design
      (common random numbers), after one pre-roll from rest for the whole problem (the longest
      over the corners of the ranges). The answer is measured again on fresh records (seed
      ``noise_seed + 1``) with its 95 % interval: the search's value is biased up by its choice
      among noisy values, the fresh one is not (the command's ``--psd``, ``--records``,
      ``--duration-s``, ``--noise-band-hz`` and ``--noise-seed``). Records measure the
      displacement and the impacts, not the impact speed or the contact force: those limits
      are refused under noise.
    * ``accel_m_s2``: in place of ``freqs_hz`` and ``accel_rms_g`` (and of the noise), a
      measured base acceleration (m/s^2), a 1-D array or sequence of samples at
      ``t = k / sample_rate_hz`` (``sample_rate_hz`` in Hz, needed with it). It is checked and
      resampled (band-limited) to ``integrator_rate_hz`` (default: the record's own rate),
      the rate the drive is read at by linear interpolation between samples, as the command's
      ``--accel-file`` is resampled to its ``--sample-rate-hz`` (default 100 kHz there: give
      ``integrator_rate_hz=100e3`` for the command's answer on a record of another rate, and a
      rate well above the device's resonance for a coarsely sampled record). The objective is
      the mean DC power over the record after one pre-roll from rest for the whole problem
      (the longest over the corners of the ranges), the same record for every design; it is
      deterministic, so nothing is confirmed on fresh records. As under noise, the record
      measures the displacement and the impacts, not the impact speed or the contact force:
      those limits are refused. An empty or too short record (fewer than 16 samples, or none
      left after the pre-roll), a sample that is not finite, a rate that is not finite and
      positive, or a record given beside the sines or the noise raises ``ValueError`` naming
      the argument.

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
    ``max_iters``, ``budget`` (the most evaluations the search may make), ``evaluations``;
    under noise ``power_confirmed_w`` and ``power_confirmed_ci95_w`` (the answer's mean power
    on the fresh records and its 95 % half-width, the command's numbers of those names) and
    ``confirm_seed`` (all three ``None`` under sines); and ``settings``, what repeats the run
    besides the device (as the command's ``summary.json`` records it): ``freqs_hz``,
    ``accel_rms_g`` (``None`` under noise or a record), ``noise`` (``psd_g2_per_hz``,
    ``bandwidth_hz``, ``records``, ``duration_s``, ``seed``, ``transient_s``; ``None`` otherwise),
    ``record`` (``sample_rate_hz``, the integrator's, ``samples`` at it, ``transient_s``,
    ``analysed_s``; ``None`` otherwise), ``limits``,
    ``search`` (``samples``,
    ``polish_starts``, ``max_iters``, ``simplex_size``, ``sd_tolerance``, ``seed``) and
    ``steady`` (the steady state's ``rtol``, ``transient_periods``, ``max_newton``, ``tol``,
    ``jacobian``, ``max_map_periods``).

    A range or interface that does not fit the device raises :class:`endstop.ParamError`
    naming the field; a malformed problem (no range, bad frequencies or limits) ``ValueError``;
    a problem no design of which could be evaluated :class:`endstop.SolverError`. The GIL is
    released while the search runs.

    Under noise, the load of the piezoelectric cantilever over two decades (a few seconds):

    >>> import endstop
    >>> r = endstop.design("data/examples/piezo_cantilever.toml",
    ...                    [("load.resistance_ohm", 1e3, 1e5)], psd_g2_per_hz=1e-5,
    ...                    noise_band_hz=1e3, records=2, duration_s=0.5, samples=4)
    >>> 1e3 <= r["best"]["params"]["load.resistance_ohm"] <= 1e5
    True
    >>> r["confirm_seed"] == r["settings"]["noise"]["seed"] + 1
    True

    Over a measured record (here a 120 Hz sine of 0.3 g rms sampled at 10 kHz for 1.2 s):

    >>> import numpy as np
    >>> t = np.arange(12_000) / 10e3
    >>> a = 0.3 * np.sqrt(2) * 9.80665 * np.sin(2 * np.pi * 120 * t)
    >>> r = endstop.design("data/examples/piezo_cantilever.toml",
    ...                    [("load.resistance_ohm", 1e4, 1e5)], accel_m_s2=a,
    ...                    sample_rate_hz=10e3, samples=4)
    >>> r["best"]["power_w"] > 0 and r["power_confirmed_w"] is None
    True
    """
    if isinstance(device, (str, os.PathLike)):
        device = _native.Device.from_toml(device)
    record = None
    if accel_m_s2 is not None:
        record = np.ascontiguousarray(np.asarray(accel_m_s2, dtype=float))
        if record.ndim != 1:
            raise ValueError(
                f"accel_m_s2 must be a 1-D array or sequence of samples, not of shape "
                f"{record.shape}")
    freqs = None if freqs_hz is None else [
        float(f) for f in np.atleast_1d(np.asarray(freqs_hz, dtype=float))]
    return _native.design(
        device, list(ranges), freqs, None if accel_rms_g is None else float(accel_rms_g),
        interfaces=None if interfaces is None else list(interfaces),
        max_impact_speed_m_s=max_impact_speed_m_s, max_contact_force_n=max_contact_force_n,
        max_displacement_m=max_displacement_m, max_impacts_per_s=max_impacts_per_s,
        samples=int(samples), seed=int(seed),
        psd_g2_per_hz=None if psd_g2_per_hz is None else float(psd_g2_per_hz),
        records=int(records), duration_s=float(duration_s), noise_band_hz=float(noise_band_hz),
        noise_seed=int(noise_seed), accel_m_s2=record,
        sample_rate_hz=None if sample_rate_hz is None else float(sample_rate_hz),
        integrator_rate_hz=None if integrator_rate_hz is None else float(integrator_rate_hz))
