"""Nonlinear suspensions from Python: the equilibria of a double well, and a short
displacement ensemble beside the exact stationary density."""

from pathlib import Path

import numpy as np

import endstop

ROOT = Path(__file__).resolve().parents[2]


def test_double_well_equilibria():
    d = endstop.Device.from_toml(ROOT / "data/validation/random_bistable_stops_em.toml")
    eq = endstop.springs.equilibria(d)
    assert [e["stable"] for e in eq] == [True, False, True]
    assert abs(eq[2]["x_m"] - 1e-4) < 1e-15


def test_displacement_density_integrates_to_its_share_and_has_the_exact_law():
    d = endstop.Device.from_toml(ROOT / "data/validation/random_duffing_em.toml")
    r = endstop.springs.displacement(d, 6e-3, 4e-4, bins=40, records=2, duration_s=1.0)
    width = r["x_m"][1] - r["x_m"][0]
    # Nearly every sample lies within 4 linear RMS displacements of a hardening spring.
    assert 0.99 < float(np.sum(r["density_per_m"]) * width) <= 1.0 + 1e-12
    assert r["exact_density_per_m"] is not None
    assert r["transition_rate_per_s"] is None
