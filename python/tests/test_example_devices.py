"""Every study on the shipped example devices of data/examples/ (a piezoelectric cantilever
with a one-sided stop, an electromagnetic harvester with asymmetric stops, a rigid restitution
stop), and the CLI's numbers for them on the same arguments.

The CLI comparison uses the relative 1e-9 of test_against_cli.py (the same library code in two
builds); the ranges are short so that the whole file runs in seconds."""

import math

import numpy as np
import pytest

import endstop
from conftest import run_cli, summary

# Device file, a frequency range around its resonance (Hz) with a step, and the drive (g rms).
EXAMPLES = {
    "piezo_cantilever": (100.0, 140.0, 4.0, 0.5),
    "em_asymmetric": (44.0, 60.0, 2.0, 0.2),
    "rigid_restitution": (600.0, 700.0, 10.0, 0.3),
}


def device(root, name):
    return endstop.Device.from_toml(root / f"data/examples/{name}.toml")


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_sweeps_and_orbits_run_on_every_example(root, name):
    lo, hi, step, acc = EXAMPLES[name]
    dev = device(root, name)
    up = endstop.study.up_sweep(dev, acc, start_hz=lo, stop_hz=hi, step_hz=step)
    down = endstop.study.down_sweep(dev, acc, start_hz=lo, stop_hz=hi, step_hz=step)
    assert up["freq_hz"][0] == lo and down["freq_hz"][0] == hi
    for r in (up, down):
        assert np.all(np.isfinite(r["p_total_w"])) and np.all(r["p_total_w"] > 0.0)
    orbits = endstop.study.orbits(dev, acc, start_hz=lo, stop_hz=hi, step_hz=step)
    assert len(orbits["freq_hz"]) == len(orbits["stable"]) > 0
    assert np.all(np.isfinite(orbits["multiplier_max_abs"]))


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_ensemble_matches_endstop_random_on_every_example(root, tmp_path, name):
    rel = f"data/examples/{name}.toml"
    out = run_cli(["random", "--device", rel, "--psd", "1e-4", "--records", "2",
                   "--duration-s", "1", "--seed", "7", "--out", str(tmp_path)], tmp_path)
    cli = summary(out / "summary.json")["numbers"]
    py = endstop.study.ensemble(device(root, name), 1e-4, records=2, duration_s=1.0, seed=7)
    for key in ["power_w", "power_ci95_w", "efficiency", "linear_power_w", "bw3db_hz",
                "contact_fraction"]:
        assert math.isclose(py[key], cli[key], rel_tol=1e-9, abs_tol=0.0), key
    # Eq 21 is a capacitor pair's theory: given for a pair only, by both.
    assert (py["eq21_power_w"] is None) == ("eq21_power_w" not in cli)
    if py["eq21_power_w"] is not None:
        assert math.isclose(py["eq21_power_w"], cli["eq21_power_w"], rel_tol=1e-9)


def test_pair_theory_on_a_piezoelectric_device_is_a_value_error(root):
    dev = device(root, "piezo_cantilever")
    for f in (endstop.linear.two_port, endstop.linear.k2):
        with pytest.raises(ValueError, match="capacitor-pair"):
            f(dev)
    with pytest.raises(ValueError, match="capacitor-pair"):
        endstop.linear.eq21_power_w(dev, 1e-4)
    # The linearised model's spectrum and band power take any device.
    f = np.linspace(50.0, 200.0, 301)
    psd = endstop.linear.output_psd(dev, 1e-4, f)
    assert psd.shape == f.shape and np.all(psd > 0.0)
    p = endstop.linear.white_noise_power_w(dev, 1e-4, 1e-3, 1e4)
    assert 0.0 < p and math.isfinite(p)
