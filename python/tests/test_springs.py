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
    path = ROOT / "data/validation/random_duffing_em.toml"
    d = endstop.Device.from_toml(path)
    psd_g2_per_hz, reach_m = 6e-3, 4e-4
    r = endstop.springs.displacement(d, psd_g2_per_hz, reach_m, bins=40, records=2,
                                     duration_s=1.0)
    width = r["x_m"][1] - r["x_m"][0]
    # Nearly every sample lies within 4 linear RMS displacements of a hardening spring.
    assert 0.99 < float(np.sum(r["density_per_m"]) * width) <= 1.0 + 1e-12
    assert r["transition_rate_per_s"] is None
    # The exact law computed here from the device, independently of the package's law: for
    # viscous damping c (the suspension's and the coil's, Phi^2 / (Rc + R)) and two-sided level
    # S, the density is exp(-U / theta) normalised, theta = m^2 S / (2 c) (Caughey 1971; the
    # band of the records lowers the velocity's variance, not the displacement's: the Rust
    # crate's validation::stationary_law). U = k1 x^2 / 2 + k3 x^4 / 4.
    f = d.to_dict()
    mech, coil = f["mechanics"], f["transducer"]
    m = mech["mass_kg"]
    k1, k3 = mech["suspension"]["k1_n_per_m"], mech["suspension"]["k3_n_per_m3"]
    c = mech["damping_n_s_per_m"] + coil["transduction_n_per_a"] ** 2 / (
        coil["coil_resistance_ohm"] + coil["load_resistance_ohm"])
    s = psd_g2_per_hz * 9.81 ** 2
    theta = m * m * s / (2.0 * c)
    x = np.linspace(-2e-3, 2e-3, 400001)
    weight = np.exp(-(0.5 * k1 * x ** 2 + 0.25 * k3 * x ** 4) / theta)
    z = float(np.sum(0.5 * (weight[1:] + weight[:-1]) * np.diff(x)))
    xc = np.asarray(r["x_m"])
    exact = np.exp(-(0.5 * k1 * xc ** 2 + 0.25 * k3 * xc ** 4) / theta) / z
    got = np.asarray(r["exact_density_per_m"])
    # Both are quadratures of one smooth integral: the trapezoid rule here on 1e-8 m steps
    # (about 1e-9 relative for a density whose scale is 1e-4 m) and the package's
    # Gauss-Legendre panels agree far below 1e-6; a wrong theta (a factor 2, or the band's
    # deficit of 3e-4 applied to it) moves the density in its tails by 1e-4 and more.
    assert got.shape == exact.shape
    assert np.allclose(got, exact, rtol=1e-6, atol=0.0), np.max(np.abs(got / exact - 1))


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
