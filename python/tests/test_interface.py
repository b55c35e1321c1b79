"""Devices with an interface circuit from Python, through the same functions as any device and
the same library calls as the commands: the up-sweep against `endstop sweep`, the periodic
orbits continued in frequency, the charging of the storage against `endstop charge`, and noise
ensembles against `endstop random`, on the same arguments."""

import numpy as np
import pytest

import endstop
from conftest import run_cli, summary

BRIDGE = "data/examples/piezo_bridge.toml"
# The same library code on both sides (as in test_against_cli.py): only floating-point
# differences between two builds of it could use this.
REL = 1e-9


def bridge(root):
    return endstop.Device.from_toml(root / BRIDGE)


def test_orbits_behind_a_bridge_report_the_dc_power(root):
    r = endstop.study.orbits(bridge(root), 0.3, 118.0, 121.0, step_hz=0.5)
    assert len(r["freq_hz"]) == len(r["stable"]) == len(r["p_total_w"]) > 3
    assert r["freq_hz"][-1] >= 121.0
    assert np.all(r["p_total_w"] > 0.0) and np.all(r["v1_mean_v"] > 0.0)
    assert np.all(np.isfinite(r["multiplier_max_abs"]))
    rl = bridge(root).to_dict()["interface"]["load"]["resistance_ohm"]
    # The first output is the storage voltage and the DC load is across it alone: the power
    # and the RMS come from the same integral of vs^2 over the period (a square root and a
    # square apart), equal to rounding.
    assert np.allclose(r["p_total_w"], r["v1_rms_v"] ** 2 / rl, rtol=1e-12, atol=0.0)
    # The mean's square is below the mean square by the ripple's variance, about
    # (ripple / V)^2 / 12 ~ 1e-5 relative (ripple T / (2 R Cs), 1 %): 1e-3.
    assert np.allclose(r["p_total_w"], r["v1_mean_v"] ** 2 / rl, rtol=1e-3)
    assert np.all(r["v1_mean_v"] <= r["v1_rms_v"])


def test_up_sweep_behind_a_bridge_matches_the_command(root, tmp_path):
    import pandas as pd  # the test extra installs it
    ours = endstop.study.up_sweep(bridge(root), 0.3, 116.0, 120.0, step_hz=2.0)
    out = run_cli(["sweep", "--device", str(root / BRIDGE), "--from", "116", "--to", "120",
                   "--step", "2", "--steps-at-once", "--accel-rms-g", "0.3",
                   "--out", str(tmp_path)], tmp_path)
    cli = pd.read_parquet(out / "sweep.parquet")
    assert len(ours["freq_hz"]) == len(cli) >= 3
    for key in ["freq_hz", "v1_rms_v", "p1_w", "x_peak_m"]:
        np.testing.assert_allclose(ours[key], cli[key].to_numpy(dtype=float), rtol=REL,
                                   atol=0.0, err_msg=key)
    numbers = summary(out / "summary.json")["numbers"]
    assert ours["max_v1_rms_v"] == pytest.approx(numbers["v1_rms_max_v"], rel=REL)
    # Behind the bridge the first output is the storage voltage and the DC load is across it:
    # its power and the RMS come from the same integral of vs^2 over the measured block, equal
    # to rounding.
    rl = bridge(root).to_dict()["interface"]["load"]["resistance_ohm"]
    assert np.all(ours["p1_w"] > 0.0)
    assert np.allclose(ours["p1_w"], ours["v1_rms_v"] ** 2 / rl, rtol=1e-12, atol=0.0)


def test_charge_matches_the_command(root, tmp_path):
    d = bridge(root).to_dict()
    d["interface"]["load"] = {"kind": "open"}
    d["interface"]["storage_capacitance_f"] = 1e-6
    dev = endstop.Device.from_dict(d, "piezo_bridge_open")
    ours = endstop.study.charge(dev, 120.0, 0.3, 1.0, ramp_periods=20.0, t_max_s=20.0)
    assert 0.0 < ours["time_to_target_s"] < 20.0
    assert ours["t_s"].shape == ours["vs_v"].shape
    path = tmp_path / "open.toml"
    path.write_text(dev.to_toml())
    out = run_cli(["charge", "--device", str(path), "--freq-hz", "120", "--accel-rms-g", "0.3",
                   "--target-v", "1", "--ramp-periods", "20", "--t-max-s", "20",
                   "--out", str(tmp_path)], tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    assert ours["time_to_target_s"] == pytest.approx(cli["time_to_target_s"], rel=1e-9)


def test_out_of_reach_is_a_solver_error(root):
    d = bridge(root).to_dict()
    d["interface"]["load"] = {"kind": "open"}
    d["interface"]["storage_capacitance_f"] = 1e-6
    dev = endstop.Device.from_dict(d, "piezo_bridge_open")
    with pytest.raises(endstop.SolverError, match="out of reach|not reached"):
        endstop.study.charge(dev, 120.0, 0.3, 500.0, t_max_s=20.0)


def test_ensemble_behind_a_bridge_matches_the_command(root, tmp_path):
    dev = bridge(root)
    ours = endstop.study.ensemble(dev, 1e-4, records=2, duration_s=1.0)
    assert len(ours["p_dc_w_each"]) == 2
    assert 0.0 < ours["efficiency"] < 1.0
    # The pre-roll covers five storage time constants R C_s of the file (rounded up to a whole
    # millisecond), longer here than five ring-up times.
    iface = dev.to_dict()["interface"]
    settling = 5.0 * iface["load"]["resistance_ohm"] * iface["storage_capacitance_f"]
    assert ours["preroll_s"] == pytest.approx(settling, abs=1e-3)
    assert np.all(np.abs(ours["ledger_relative_residual_each"]) < 1e-9)
    out = run_cli(["random", "--device", str(root / BRIDGE), "--psd", "1e-4", "--records", "2",
                   "--duration-s", "1", "--out", str(tmp_path)], tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    # The same records by the same code: equal to rounding.
    for key in ["p_dc_w", "p_dc_ci95_w", "p_drive_w", "efficiency", "efficiency_ci95", "vdc_v"]:
        assert ours[key] == pytest.approx(cli[key], rel=1e-12), key
    # The alias is the same call.
    alias = endstop.study.interface_ensemble(dev, 1e-4, records=2, duration_s=1.0)
    assert alias["p_dc_w"] == ours["p_dc_w"] and alias["vdc_v"] == ours["vdc_v"]


def test_ensemble_refuses_an_open_load(root):
    d = bridge(root).to_dict()
    d["interface"]["load"] = {"kind": "open"}
    dev = endstop.Device.from_dict(d, "piezo_bridge_open")
    with pytest.raises(endstop.SolverError, match="open load"):
        endstop.study.ensemble(dev, 1e-4, records=1, duration_s=1.0)
