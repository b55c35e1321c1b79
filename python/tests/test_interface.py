"""Devices with an interface circuit from Python: the steady states by shooting and continued
in frequency, the charging of the storage and noise ensembles, against the `endstop sweep`,
`endstop charge` and `endstop random` commands on the same arguments."""

import numpy as np
import pytest

import endstop
from conftest import run_cli, summary


def bridge(root):
    return endstop.Device.from_toml(root / "data/examples/piezo_bridge.toml")


def test_interface_response_runs_and_reports_dc_power(root):
    r = endstop.study.interface_response(bridge(root), 0.3, 118.0, 121.0)
    assert r["end"] == "reached"
    assert len(r["freq_hz"]) == len(r["stable"]) == len(r["p_dc_w"]) > 3
    assert np.all(r["p_dc_w"] > 0.0) and np.all(r["vdc_v"] > 0.0)
    # The power is the mean of V^2 / R, the voltage the mean of V: they differ by the ripple's
    # variance, about (ripple / V)^2 / 12 ~ 1e-5 relative (ripple T / (2 R Cs), 1 %); 1e-3.
    rl = bridge(root).to_dict()["interface"]["load"]["resistance_ohm"]
    assert np.allclose(r["p_dc_w"], r["vdc_v"] ** 2 / rl, rtol=1e-3)
    assert np.all(np.isfinite(r["multiplier_max_abs"]))


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


def test_interface_ensemble_matches_the_command(root, tmp_path):
    dev = bridge(root)
    ours = endstop.study.interface_ensemble(dev, 1e-4, records=2, duration_s=1.0)
    assert len(ours["p_dc_w_each"]) == 2
    assert 0.0 < ours["efficiency"] < 1.0
    # The pre-roll covers five storage time constants R C_s of the file (rounded up to a whole
    # millisecond), longer here than five ring-up times.
    iface = dev.to_dict()["interface"]
    settling = 5.0 * iface["load"]["resistance_ohm"] * iface["storage_capacitance_f"]
    assert ours["preroll_s"] == pytest.approx(settling, abs=1e-3)
    assert np.all(np.abs(ours["ledger_relative_residual_each"]) < 1e-9)
    out = run_cli(["random", "--device", str(root / "data/examples/piezo_bridge.toml"),
                   "--psd", "1e-4", "--records", "2", "--duration-s", "1",
                   "--out", str(tmp_path)], tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    # The same records by the same code: equal to rounding.
    assert ours["p_dc_w"] == pytest.approx(cli["p_dc_w"], rel=1e-12)
    assert ours["efficiency"] == pytest.approx(cli["efficiency"], rel=1e-12)


def test_interface_ensemble_refuses_an_open_load(root):
    d = bridge(root).to_dict()
    d["interface"]["load"] = {"kind": "open"}
    dev = endstop.Device.from_dict(d, "piezo_bridge_open")
    with pytest.raises(endstop.SolverError, match="open load"):
        endstop.study.interface_ensemble(dev, 1e-4, records=1, duration_s=1.0)


def test_interface_sweep_matches_the_command(root, tmp_path):
    import pandas as pd  # the test extra installs it
    ours = endstop.study.interface_sweep(bridge(root), 0.3, [116.0, 118.0, 120.0])
    assert all(ours["found"]) and all(m in ("newton", "period map") for m in ours["method"])
    out = run_cli(["sweep", "--device", str(root / "data/examples/piezo_bridge.toml"),
                   "--from", "116", "--to", "120", "--step", "2", "--accel-rms-g", "0.3",
                   "--out", str(tmp_path)], tmp_path)
    cli = pd.read_parquet(out / "sweep.parquet")
    assert np.allclose(ours["freq_hz"], cli["freq_hz"], rtol=1e-12)
    # The command moves each step onto the same periodic orbit by shooting, then measures it
    # over blocks of periods and accepts a block once the RMS of `vs` changes by less than its
    # criterion's 1e-3 (relative) from the block before: that is the precision it states. The
    # DC load's power is the mean of vs^2 / R on both sides, so it is stated to 2e-3 (twice
    # the relative change of an RMS voltage).
    block_tol = 1e-3
    assert np.allclose(ours["p_dc_w"], cli["p1_w"], rtol=2.0 * block_tol, atol=0.0)
    # The command's v1 is the RMS of vs, ours its mean: the RMS exceeds the mean by at most
    # (ripple / mean)^2 / 8 relative (the variance of a signal of that peak-to-peak is at most
    # its square over 4), here near 1e-5, far inside the block criterion.
    ripple_term = (ours["ripple_v"] / ours["vdc_v"]) ** 2 / 8.0
    assert np.all(ripple_term < 0.1 * block_tol)
    assert np.allclose(ours["vdc_v"], cli["v1_rms_v"], rtol=block_tol + ripple_term.max(),
                       atol=0.0)
