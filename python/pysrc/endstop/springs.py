"""Nonlinear suspensions (the device file's ``[mechanics.suspension]``: ``polynomial`` or
``bistable``; see the book's chapter "Nonlinear springs").

* :func:`equilibria`: the static equilibria of the suspension with the stops' springs (the
  wells, the barriers between them, any rest on a stop) and their stability;
* :func:`displacement`: the displacement of a random ensemble, its density with its 95 %
  interval across records, beside the exact stationary density where it applies (viscous
  damping only, lossless stops), and for two wells the rate of passages from one well's
  bottom to the other's (not escapes that settle: with light damping a mass above the barrier
  makes many such passages before it settles in either well);
* :func:`basins`: which stable orbit each initial state of a grid ends on under a sine, each
  orbit placed in its well or across the barrier (as ``endstop basins``).
"""

from . import _native


def equilibria(device):
    """The static equilibria of ``device``: a list of dicts with ``x_m``,
    ``stiffness_n_per_m``, ``stable``, ``energy_j`` and ``place`` (``free``, ``upper_stop``,
    ``lower_stop``), sorted by position."""
    return _native.equilibria(device)


def displacement(device, psd_g2_per_hz, reach_m, bins=80, records=8, duration_s=10.0,
                 seed=2012):
    """The displacement of ``records`` white-noise records of two-sided level
    ``psd_g2_per_hz`` (g^2/Hz), read into ``bins`` bins over ``[-reach_m, reach_m]``. Keys:
    ``x_m``, ``density_per_m``, ``density_ci95_per_m`` (arrays), ``exact_density_per_m``
    (an array, or None where the exact law does not apply), ``x2_mean_m2``, ``transitions``
    (passages from one well's bottom to the other's), ``transition_rate_per_s`` and its
    ``..._ci95_per_s`` (None without two wells),
    ``wells_m``."""
    return _native.displacement(device, float(psd_g2_per_hz), float(reach_m), int(bins),
                                int(records), float(duration_s), int(seed))


def basins(device, freq_hz, accel_rms_g, x_range_m, v_range_m_per_s, cells=21,
           max_periods=1000, settle_tol=1e-3, seeds_per_side=5):
    """The basins under a sine of ``freq_hz`` (Hz) at ``accel_rms_g`` (g rms) on ``cells`` by
    ``cells`` initial states over ``x_range_m`` and ``v_range_m_per_s`` (pairs lo, hi). Keys:
    ``x0_m``, ``v0_m_per_s`` (arrays, one value a cell), ``attractor`` and ``place`` (a label
    a cell, ``unsettled`` where a cell did not settle in ``max_periods``), ``periods``, and
    ``attractors``: a list of dicts with ``label``, ``place`` (``left well``, ``right well``,
    ``inter-well`` or ``orbit``), ``x_lower_m``, ``x_upper_m``, ``p_w`` and ``share``."""
    return _native.basins(device, float(freq_hz), float(accel_rms_g),
                          tuple(map(float, x_range_m)), tuple(map(float, v_range_m_per_s)),
                          int(cells), int(max_periods), float(settle_tol),
                          int(seeds_per_side))
