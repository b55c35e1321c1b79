"""Nonlinear suspensions from Python: the equilibria of a double well, a short
displacement ensemble beside the exact stationary density, and basins placed by well."""

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


def test_basins_of_a_weakly_driven_double_well_keep_each_bottom_in_its_own_well():
    d = endstop.Device.from_toml(ROOT / "data/examples/bistable_stops_em.toml")
    # 0.05 g rms at 30 Hz cannot carry the mass over the barrier from a well's bottom; the
    # grid's positions step by 250 um, so the wells at +-500 um are cells (v = 0 too).
    r = endstop.springs.basins(d, 30.0, 0.05, (-7.5e-4, 7.5e-4), (-0.1, 0.1), cells=7,
                               seeds_per_side=3)
    assert len(r["x0_m"]) == len(r["attractor"]) == len(r["place"]) == 49
    places = {a["place"] for a in r["attractors"]}
    assert places == {"left well", "right well"}
    for x, place in ((-5e-4, "left well"), (5e-4, "right well")):
        i = next(i for i in range(49)
                 if abs(r["x0_m"][i] - x) < 1e-12 and abs(r["v0_m_per_s"][i]) < 1e-12)
        assert r["place"][i] == place
    unsettled = sum(a == "unsettled" for a in r["attractor"]) / 49
    assert abs(sum(a["share"] for a in r["attractors"]) + unsettled - 1.0) < 1e-12
