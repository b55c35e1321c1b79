"""Linear theory from Python against the closed forms of eqs 15-22 evaluated here."""

import math

import numpy as np
import pytest

import endstop

G = 9.81


def test_two_port_follows_eqs_15_to_22():
    dev = endstop.Device.prototype(2)
    p = dev.to_dict()
    e, m, x0 = p["transducer"], p["mechanics"], p["transducer"]["finger_overlap_m"]
    ct = e["c0_f"] + e["cp_f"] + e["load_capacitance_f"]
    c = ct / 2
    gamma = e["c0_f"] * e["bias_v"] / x0
    k = m["stiffness_n_per_m"] + 2 * e["c0_f"] ** 2 * e["bias_v"] ** 2 / (x0**2 * ct)
    tp = endstop.linear.two_port(dev)
    # Same formulas in another order of operations: agreement to rounding (1e-12).
    assert tp["k2"] == pytest.approx(gamma**2 / (k * c), rel=1e-12)
    assert endstop.linear.k2(dev) == tp["k2"]
    qm = math.sqrt(k * m["mass_kg"]) / m["damping_n_s_per_m"]
    assert tp["qm"]["open_circuit"] == pytest.approx(qm, rel=1e-12)
    rl = 2 * e["load_resistance_ohm"] * c * math.sqrt(k / m["mass_kg"])
    eff = rl * tp["k2"] * qm / (1 + (1 / qm + tp["k2"] * qm) * rl + rl * rl)
    assert endstop.linear.eq21_efficiency(dev) == pytest.approx(eff, rel=1e-12)
    assert endstop.linear.eq21_power_w(dev, 1e-3) == pytest.approx(
        m["mass_kg"] * 1e-3 * G * G / 2 * eff, rel=1e-12)


def test_linear_output_psd_integrates_to_eq21():
    # The library's own test states the identity; here through numpy: trapezoid over 1 Hz to
    # 20 kHz on a 0.05 Hz grid resolves the resonance (half-power width about 3.5 Hz) to 1e-3.
    dev = endstop.Device.prototype(2)
    f = np.arange(1.0, 20000.0, 0.05)
    s = endstop.linear.output_psd(dev, 1e-3, f)
    assert s.shape == f.shape and s.dtype == np.float64
    total = float(np.sum(0.5 * (s[1:] + s[:-1]) * np.diff(f)))
    assert total == pytest.approx(endstop.linear.eq21_power_w(dev, 1e-3), rel=1e-3)


def test_bias_for_coupling_inverts_k2():
    dev = endstop.Device.prototype(1)
    vb = endstop.linear.bias_for_coupling(dev, 0.05)
    assert endstop.linear.k2(dev.with_bias(vb)) == pytest.approx(0.05, rel=1e-12)
    with pytest.raises(ValueError):
        endstop.linear.bias_for_coupling(dev, 1.5)
