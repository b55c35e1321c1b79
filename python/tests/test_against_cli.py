"""The Python calls give the numbers of the Rust programs on the same device and seed.

Both run the same library code, so the numbers agree far beyond the digits the programs print
(4 to 5 significant digits): the tolerance is a relative 1e-9, which only floating-point
differences between two builds of the same code could use. The programs' sweeps take each
step at once (`--steps-at-once`), as the Python sweeps do by default; by default the programs
reach each step by a phase-continuous ramp, which the Python sweeps take with
`ramp_rate_hz_per_s` (the programs' `--ramp-rate`)."""

import math

import pytest

import endstop
from conftest import run_cli, summary

REL = 1e-9


def close(a, b):
    return math.isclose(a, b, rel_tol=REL, abs_tol=0.0)


def test_up_sweep_matches_endstop_sweep(root, tmp_path):
    out = run_cli(["sweep", "--device", "data/examples/my_harvester.toml", "--from", "500",
                   "--to", "800", "--step", "2", "--steps-at-once", "--accel-rms-g", "0.3", "--out",
                   str(tmp_path)],
                  tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    dev = endstop.Device.from_toml(root / "data/examples/my_harvester.toml")
    py = endstop.study.up_sweep(dev, 0.3, start_hz=500, stop_hz=800, step_hz=2)
    assert close(py["max_v1_rms_v"], cli["v1_rms_max_v"])
    assert close(max(py["v1_rms_v"]), cli["v1_rms_max_v"])
    assert ("impact_onset_hz" in cli) == (py["onset_hz"] is not None)
    if py["onset_hz"] is not None:
        assert close(py["onset_hz"], cli["impact_onset_hz"])
    assert ("branch_end_hz" in cli) == (py["branch_end_hz"] is not None)
    if py["branch_end_hz"] is not None:
        assert close(py["branch_end_hz"], cli["branch_end_hz"])


def test_ramped_up_sweep_matches_endstop_sweep(root, tmp_path):
    # The piezoelectric example (one-sided stopper) through its impacting branch and its jump,
    # each step reached by a ramp at 2 Hz/s.
    out = run_cli(["sweep", "--device", "data/examples/piezo_cantilever.toml", "--from", "110",
                   "--to", "170", "--step", "2", "--ramp-rate", "2", "--accel-rms-g", "0.5",
                   "--out", str(tmp_path)],
                  tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    dev = endstop.Device.from_toml(root / "data/examples/piezo_cantilever.toml")
    py = endstop.study.up_sweep(dev, 0.5, start_hz=110, stop_hz=170, step_hz=2,
                                ramp_rate_hz_per_s=2.0)
    at_once = endstop.study.up_sweep(dev, 0.5, start_hz=110, stop_hz=170, step_hz=2)
    assert py["branch_end_hz"] is not None and "branch_end_hz" in cli
    assert close(py["branch_end_hz"], cli["branch_end_hz"])
    assert close(py["max_v1_rms_v"], cli["v1_rms_max_v"])
    # The ramps run: the counters of the two sweeps differ.
    assert py["integrator_steps"] != at_once["integrator_steps"]


def test_a_ramp_rate_must_be_a_positive_rate(root):
    dev = endstop.Device.from_toml(root / "data/examples/piezo_cantilever.toml")
    for bad in [0.0, -1.0, float("nan")]:
        with pytest.raises(ValueError, match="ramp_rate_hz_per_s"):
            endstop.study.up_sweep(dev, 0.5, 110, 170, step_hz=2, ramp_rate_hz_per_s=bad)


def test_ensemble_matches_endstop_random(root, tmp_path):
    out = run_cli(["random", "--device", "data/examples/my_harvester.toml", "--psd", "1e-4",
                   "--records", "2", "--duration-s", "2", "--seed", "7", "--out", str(tmp_path)],
                  tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    dev = endstop.Device.from_toml(root / "data/examples/my_harvester.toml")
    py = endstop.study.ensemble(dev, 1e-4, records=2, duration_s=2.0, seed=7)
    for key in ["power_w", "power_ci95_w", "efficiency", "eq21_power_w", "bw3db_hz",
                "contact_fraction"]:
        assert close(py[key], cli[key]), key


def test_response_matches_endstop_response(root, tmp_path):
    args = ["response", "--device", "data/examples/my_harvester.toml", "--from", "560", "--to",
            "700", "--step", "4", "--steps-at-once", "--accel-rms-g", "0.3", "--out",
            str(tmp_path)]
    cli = summary(run_cli(args, tmp_path) / "summary.json")["numbers"]
    dev = endstop.Device.from_toml(root / "data/examples/my_harvester.toml")
    orbits = endstop.study.orbits(dev, 0.3, start_hz=560, stop_hz=700, step_hz=4)
    events = [k for k in cli if k.startswith("event_")]
    assert len(orbits["events"]) == len(events)
    for i, e in enumerate(orbits["events"]):
        assert close(e["freq_hz"], cli[f"event_{i}_hz"]), i
    down = endstop.study.down_sweep(dev, 0.3, start_hz=560, stop_hz=700, step_hz=4)
    assert ("down_branch_end_hz" in cli) == (down["branch_end_hz"] is not None)
    if down["branch_end_hz"] is not None:
        assert close(down["branch_end_hz"], cli["down_branch_end_hz"])


def assert_figure_matches_its_program(name, py, tmp_path):
    """The figure's numbers and claim values from Python equal those of its program."""
    out = run_cli([], tmp_path, program=name)
    cli = summary(out / name / "summary.json")
    assert set(py["numbers"]) == set(cli["numbers"])
    for key, value in cli["numbers"].items():
        assert close(py["numbers"][key], value), key
    ours = {(c["claim"], c["quantity"], c["set"]): c["ours"] for c in py["claims"]}
    theirs = {(c["claim"], c["quantity"], c["set"]): c["ours"] for c in cli["values"]}
    assert ours == theirs


def test_fig13_matches_the_fig13_program(tmp_path):
    assert_figure_matches_its_program("fig13", endstop.paper.fig13.run(), tmp_path)


def test_fig09_matches_the_fig09_program(tmp_path):
    # The program calibrates prototype 1 into the empty output directory first, as
    # endstop.paper.fig09.run() does when no calibrated device is given.
    assert_figure_matches_its_program("fig09", endstop.paper.fig09.run(), tmp_path)
