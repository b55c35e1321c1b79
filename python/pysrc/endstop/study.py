"""Simulations of the nonlinear model (eqs 1-10), each returning a dict of numbers and numpy
arrays, with the GIL released while it runs.

* :func:`up_sweep`: stepped-sine up-sweep with continuation, impact onset, jump and loss of
  contact refined by bisection (the ``endstop sweep`` command; Figures 8 and 13);
* :func:`amplitude_sweep`: amplitude continuation at one frequency with its impact onset
  (Figure 9);
* :func:`record`: one band-limited white-noise record, the load voltages and a summary;
  :func:`sine_record` the same under a sine;
* :func:`ensemble`: independent records, mean output PSD, power, efficiency and bandwidth (the
  ``endstop random`` command; Figures 11-15).

* :func:`down_sweep`: stepped-sine down-sweep with the jump up and the first contact refined
  (the ``endstop response`` command's down-sweep);
* :func:`orbits`: periodic orbits by shooting, continued in frequency through folds, with their
  Floquet stability and the folds, branch points and grazing points on the way (the
  ``endstop response`` command's continuation).

Each takes any device the description allows, with or without an ``[interface]`` table (a
bridge, SSHI or SECE into a storage capacitor), through the one library call its command makes
on it: behind a circuit the model's first output is the storage voltage and the loads' power
the DC load's (``v1_rms_v``, ``p1_w``, ``p_total_w`` of the sweeps and orbits), and
:func:`ensemble` reports the storage's DC power, efficiency and energy ledger as ``endstop
random`` does. Besides:

* :func:`charge`: the time for the storage to reach a target voltage under a sine (the
  ``endstop charge`` command's study);
* :func:`interface_ensemble`: an alias of :func:`ensemble`, named for a device behind an
  interface circuit.
"""

import numpy as np

from . import _native


def up_sweep(device, accel_rms_g, start_hz, stop_hz, step_hz=2.0, refine_tol_hz=0.1,
             ramp_rate_hz_per_s=None):
    """Up-sweep of ``device`` from ``start_hz`` to ``stop_hz`` in ``step_hz`` steps at
    ``accel_rms_g`` (g rms). Keys: the per-step arrays ``freq_hz``, ``v1_rms_v``,
    ``v2_rms_v``, ``vdiff_rms_v``, ``p1_w``, ``p2_w``, ``p_total_w``, ``x_peak_m``,
    ``contact_fraction``, ... (every step, including an extension past ``stop_hz`` while the
    mass is still in contact, from index ``extended_from``), and ``onset_hz``, ``jump_hz``,
    ``contact_lost_hz`` (midpoints of brackets ``*_bracket_hz``, or None), ``branch_end_hz``,
    ``jump_power_ratio``, ``max_v1_rms_v``. Each step is taken at once (the drive's
    frequency jumps, as the paper's figures and ``endstop sweep --steps-at-once`` do), or,
    with ``ramp_rate_hz_per_s``, reached by a phase-continuous ramp at that rate (Hz/s, as
    ``--ramp-rate``). Behind an interface circuit ``v1_rms_v`` is the RMS of the storage
    voltage and ``p1_w`` the DC load's power, as in the command's ``sweep.parquet``."""
    return _native.up_sweep(device, float(accel_rms_g), float(start_hz), float(stop_hz),
                            float(step_hz), float(refine_tol_hz), _rate(ramp_rate_hz_per_s))


def _rate(ramp_rate_hz_per_s):
    return None if ramp_rate_hz_per_s is None else float(ramp_rate_hz_per_s)


def amplitude_sweep(device, freq_hz, accels_rms_g, refine_tol_g=0.005):
    """Amplitude continuation of ``device`` at ``freq_hz`` over the increasing
    ``accels_rms_g`` (g rms), with the impact onset ``onset_g`` refined to ``refine_tol_g``."""
    a = np.ascontiguousarray(accels_rms_g, dtype=np.float64)
    return _native.amplitude_sweep(device, float(freq_hz), a, float(refine_tol_g))


def down_sweep(device, accel_rms_g, start_hz, stop_hz, step_hz=2.0, refine_tol_hz=0.1,
               ramp_rate_hz_per_s=None):
    """Down-sweep of ``device`` from ``stop_hz`` to ``start_hz`` in ``step_hz`` steps at
    ``accel_rms_g`` (g rms): the per-step arrays of :func:`up_sweep` (frequencies
    decreasing), ``jump_hz`` and ``contact_hz`` (midpoints of ``*_bracket_hz``, or None),
    ``jump_power_ratio``, ``branch_end_hz`` and ``branch_end_kind``. The steps are taken
    at once or ramped as in :func:`up_sweep`."""
    return _native.down_sweep(device, float(accel_rms_g), float(start_hz), float(stop_hz),
                              float(step_hz), float(refine_tol_hz), _rate(ramp_rate_hz_per_s))


def orbits(device, accel_rms_g, start_hz, stop_hz, step_hz=2.0):
    """Periodic orbits of ``device`` at ``accel_rms_g`` continued in frequency from
    ``start_hz`` to ``stop_hz`` (steps of at most ``step_hz``): per-orbit arrays ``freq_hz``,
    ``v1_rms_v`` and ``v1_mean_v`` (the RMS and the mean over the period of the model's first
    output: load 1's voltage, or behind a circuit the storage voltage), ``p_total_w`` (the
    loads' mean power: behind a circuit, the DC load's), ``x_max_m``, ``multiplier_max_abs``
    and the list ``stable``; ``events`` (dicts with ``kind``, ``freq_hz``, ``at_grazing``,
    ``stable_before``, ``stable_after``), ``folds_hz``, ``grazing_hz`` and
    ``max_residual``."""
    return _native.orbits(device, float(accel_rms_g), float(start_hz), float(stop_hz),
                          float(step_hz))


def record(device, psd_g2_per_hz, seed=2012, stream=0, duration_s=10.0):
    """One record at two-sided level ``psd_g2_per_hz`` (g^2/Hz): ``v1_v``, ``v2_v`` (arrays at
    ``sample_rate_hz``), ``p_total_w``, ``x_rms_m``, ``contact_fraction``, ``impacts``, ..."""
    return _native.record(device, float(psd_g2_per_hz), int(seed), int(stream), float(duration_s))


def sine_record(device, accel_g, freq_hz, duration_s=10.0, sample_rate_hz=100e3,
                chirp_to_hz=None):
    """One record under the sine ``a(t) = accel_g g sin(2 pi freq_hz t)`` from rest, the
    device's pre-roll discarded and ``duration_s`` analysed (``endstop random --sine-g``); with
    ``chirp_to_hz``, swept linearly from ``freq_hz`` to it over the analysed time at a continuous
    phase (``--chirp-to-hz``): what :func:`record` returns."""
    return _native.sine_record(device, float(accel_g), float(freq_hz), float(duration_s),
                               float(sample_rate_hz),
                               None if chirp_to_hz is None else float(chirp_to_hz))


def ensemble(device, psd_g2_per_hz, records=4, duration_s=10.0, seed=2012):
    """``records`` independent records (stream i of ``seed`` for record i), each from rest with
    the device's pre-roll discarded, reported as ``endstop random`` reports the device.

    For a transducer with its own loads: ``power_w`` and its ``power_ci95_w``, ``efficiency``
    (2P/(m Sa)), ``bw3db_hz`` of the mean PSD (``freq_hz``, ``out_psd_w_per_hz``),
    ``eq21_power_w`` (None unless the transducer is a capacitor pair), ``linear_power_w`` (the
    linearised model's power over the record's band, any device), and per-record arrays in
    ``records``.

    For a device behind an interface circuit into a storage (the command's numbers of the same
    names): ``p_dc_w`` and ``efficiency`` (means, with ``p_dc_ci95_w`` and
    ``efficiency_ci95`` half-widths), ``p_drive_w``, ``vdc_v``, ``preroll_s`` (the longer of
    five ring-up times and five storage time constants) and per-record arrays ``p_dc_w_each``,
    ``p_drive_w_each``, ``vdc_v_each``, ``ledger_relative_residual_each``. An open DC load (no
    steady mean) raises :class:`endstop.SolverError`."""
    return _native.ensemble(device, float(psd_g2_per_hz), int(records), float(duration_s),
                            int(seed))


__all__ = ["up_sweep", "down_sweep", "orbits", "amplitude_sweep", "record", "sine_record",
           "ensemble", "charge", "interface_ensemble"]


def charge(device, freq_hz, accel_rms_g, target_v, start_v=0.0, ramp_periods=0.0,
           t_max_s=600.0):
    """Charges the storage of ``device`` (with an interface circuit) from ``start_v`` to
    ``target_v`` under a sine at ``freq_hz``, ``accel_rms_g``, from rest at phase zero, ramped
    up over ``ramp_periods`` periods: ``time_to_target_s``, ``stored_j`` and the arrays
    ``t_s``, ``vs_v``. A target out of reach raises :class:`endstop.SolverError`."""
    return _native.charge_storage(device, float(freq_hz), float(accel_rms_g), float(target_v),
                                  float(start_v), float(ramp_periods), float(t_max_s))


def interface_ensemble(device, psd_g2_per_hz, records=4, duration_s=10.0, seed=2012):
    """An alias of :func:`ensemble`, named for a device behind an interface circuit: it calls
    :func:`ensemble` with the same arguments and returns what it returns."""
    return ensemble(device, psd_g2_per_hz, records=records, duration_s=duration_s, seed=seed)
