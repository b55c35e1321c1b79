"""`endstop.design` against the `endstop design` command on the same problem and seed (under
sines, under noise and over a measured record), and its errors.

Both build the problem and search it by the same library code (`endstop::design`), so every
design evaluated agrees, in order, far beyond the digits the command prints: the tolerance is
a relative 1e-9, which only floating-point differences between two builds of the same code
could use (as in test_against_cli.py)."""

import math
import threading

import numpy as np
import pandas as pd
import pytest

import endstop
from endstop import _native
from conftest import run_cli, summary

REL = 1e-9

DEVICE = "data/examples/piezo_bridge.toml"
RANGES = [("load.resistance_ohm", 5e3, 5e5), ("stops.upper.gap_m", 3e-5, 3e-4)]
# The interfaces as a designer names them: the transducer's own load, the device's own
# circuit by its key, and another circuit by its values.
SECE = {"kind": "sece", "storage_capacitance_f": 10e-6, "efficiency": 0.8,
        "load": {"kind": "resistor", "resistance_ohm": 100e3}}
INTERFACES_TOML = """
[[interface]]
kind = "resistive"

[[interface]]
kind = "full_bridge"
storage_capacitance_f = 10e-6
[interface.diode]
law = "piecewise_linear"
forward_drop_v = 0.2
on_resistance_ohm = 0.0
[interface.load]
kind = "resistor"
resistance_ohm = 41.7e3

[[interface]]
kind = "sece"
storage_capacitance_f = 10e-6
efficiency = 0.8
[interface.load]
kind = "resistor"
resistance_ohm = 100e3
"""


def test_design_matches_endstop_design(root, tmp_path):
    (tmp_path / "interfaces.toml").write_text(INTERFACES_TOML)
    out = run_cli(["design", "--device", DEVICE, "--range", "load.resistance_ohm=5e3..5e5",
                   "--range", "stops.upper.gap_m=3e-5..3e-4", "--freq-hz", "120",
                   "--accel-rms-g", "0.4", "--interfaces", str(tmp_path / "interfaces.toml"),
                   "--max-impact-speed-m-s", "0.05", "--max-displacement-m", "2e-4",
                   "--samples", "8", "--seed", "5", "--map-points", "0",
                   "--out", str(tmp_path / "cli")],
                  tmp_path)
    cli_summary = summary(out / "cli" / "summary.json")
    cli = cli_summary["numbers"]
    rows = pd.read_parquet(out / "cli" / "designs.parquet")
    py = endstop.design(root / DEVICE, RANGES, 120.0, 0.4,
                        interfaces=["resistive", "full_bridge", SECE],
                        max_impact_speed_m_s=0.05, max_displacement_m=2e-4, samples=8, seed=5)
    best = py["best"]
    assert math.isclose(best["power_w"], cli["power_w"], rel_tol=REL, abs_tol=0.0)
    assert (best["verdict"] == "optimum") == (cli["feasible"] == 1.0)
    assert py["evaluations"] == cli["evaluations"] == len(rows)
    assert py["evaluations"] <= py["budget"]
    d = py["designs"]
    assert list(d["interface"]) == list(rows["interface"])
    assert list(d["feasible"]) == list(rows["feasible"])
    for col in ["power_w", "violation", "impact_speed_m_s", "displacement_m",
                "load.resistance_ohm", "stops.upper.gap_m"]:
        np.testing.assert_allclose(d[col], rows[col].to_numpy(dtype=float), rtol=REL, atol=0.0,
                                   err_msg=col)
    # The best design is the one of most power among the feasible ones the search evaluated,
    # and its margins are those of its limits.
    feasible = d["feasible"]
    assert best["power_w"] == d["power_w"][feasible].max()
    assert set(best["margins"]) == {"impact_speed_m_s", "displacement_m"}
    assert best["margins"]["displacement_m"] == pytest.approx(
        1.0 - best["displacement_m"] / 2e-4, rel=1e-12)
    assert all(m >= 0.0 for m in best["margins"].values())
    # The run's seed and settings, recorded alike by both: what repeats it.
    assert cli_summary["seed"] == py["seed"] == 5
    cs, ps = cli_summary["settings"], py["settings"]
    for key in ["search", "steady", "freqs_hz", "accel_rms_g", "limits"]:
        assert cs[key] == ps[key], key
    assert ps["search"]["seed"] == 5 and ps["search"]["samples"] == 8


def test_a_bad_range_key_raises_param_error(root):
    dev = endstop.Device.from_toml(root / DEVICE)
    with pytest.raises(endstop.ParamError) as e:
        endstop.design(dev, [("stops.upper.gapp_m", 3e-5, 3e-4)], 120.0, 0.4, samples=4)
    assert "stops.upper.gapp_m" in str(e.value)
    assert e.value.field == "stops.upper.gapp_m"


def test_an_unknown_interface_name_raises_param_error(root):
    dev = endstop.Device.from_toml(root / DEVICE)
    with pytest.raises(endstop.ParamError, match="series_sshi"):
        endstop.design(dev, RANGES, 120.0, 0.4, interfaces=["series_sshi"], samples=4)


def test_a_malformed_problem_raises_value_error(root):
    dev = endstop.Device.from_toml(root / DEVICE)
    with pytest.raises(ValueError, match="increasing"):
        endstop.design(dev, RANGES, [122.0, 118.0], 0.4, samples=4)
    with pytest.raises(ValueError, match="spacing"):
        endstop.design(dev, [("stops.upper.gap_m", 3e-5, 3e-4, "cubic")], 120.0, 0.4)


def test_design_releases_the_gil(root):
    # While this thread runs a search in the native call (two interfaces, 128 samples each:
    # about 3 s here), another thread counts to two million in pure Python (about 0.25 s
    # here). With the GIL released the count finishes during the search. Had the call kept
    # the GIL, the count could run only while this thread is in Python around the call (the
    # call is made without the Python wrapper, so that little Python runs around it), a few
    # switch intervals (5 ms each) where it needs fifty, and would not have finished when the
    # call returned. No clock is read.
    dev = endstop.Device.from_toml(root / DEVICE)
    counted = threading.Event()

    def count():
        n = 0
        for _ in range(2_000_000):
            n += 1
        counted.set()

    th = threading.Thread(target=count)
    th.start()
    _native.design(dev, RANGES, [118.0, 120.0, 122.0], 0.4,
                   interfaces=["resistive", "full_bridge"], samples=128)
    finished_during = counted.is_set()
    th.join()
    assert finished_during, "the count could not run during the search: the GIL was held"


# Under noise: the piezoelectric cantilever (no circuit: its own load is the interface), its
# load over two decades around the matched 26.5 kOhm, a small ensemble (2 records of 0.5 s,
# band 1 kHz) so that the search runs in seconds.
NOISE_DEVICE = "data/examples/piezo_cantilever.toml"
NOISE = dict(psd_g2_per_hz=1e-5, noise_band_hz=1e3, records=2, duration_s=0.5, noise_seed=11)


def test_design_under_noise_matches_endstop_design_psd(root, tmp_path):
    out = run_cli(["design", "--device", NOISE_DEVICE, "--range",
                   "load.resistance_ohm=1e3..1e5", "--psd", "1e-5", "--noise-band-hz", "1e3",
                   "--records", "2", "--duration-s", "0.5", "--noise-seed", "11",
                   "--samples", "4", "--seed", "3", "--map-points", "0",
                   "--out", str(tmp_path / "cli")],
                  tmp_path)
    cli_summary = summary(out / "cli" / "summary.json")
    cli = cli_summary["numbers"]
    rows = pd.read_parquet(out / "cli" / "designs.parquet")
    py = endstop.design(root / NOISE_DEVICE, [("load.resistance_ohm", 1e3, 1e5)], samples=4,
                        seed=3, **NOISE)
    best = py["best"]
    # The answer lies inside the range, and is the most powerful design evaluated (no limit:
    # every design is feasible).
    assert 1e3 <= best["params"]["load.resistance_ohm"] <= 1e5
    assert best["verdict"] == "optimum"
    assert best["power_w"] == np.nanmax(py["designs"]["power_w"])
    # No sine under noise: no worst frequency, and the records do not measure impact speeds.
    assert math.isnan(best["worst_freq_hz"]) and math.isnan(best["impact_speed_m_s"])
    # The confirmation runs on fresh records: another seed than the search's.
    assert py["settings"]["noise"]["seed"] == 11
    assert py["confirm_seed"] == 12 != py["settings"]["noise"]["seed"]
    assert py["power_confirmed_ci95_w"] > 0.0 and math.isfinite(py["power_confirmed_w"])
    # The same search and confirmation as the command's, by the same code.
    assert math.isclose(best["power_w"], cli["power_w"], rel_tol=REL, abs_tol=0.0)
    for key in ["power_confirmed_w", "power_confirmed_ci95_w"]:
        assert math.isclose(py[key], cli[key], rel_tol=REL, abs_tol=0.0), key
    assert py["evaluations"] == cli["evaluations"] == len(rows)
    np.testing.assert_allclose(py["designs"]["power_w"], rows["power_w"].to_numpy(dtype=float),
                               rtol=REL, atol=0.0)
    np.testing.assert_allclose(py["designs"]["load.resistance_ohm"],
                               rows["load.resistance_ohm"].to_numpy(dtype=float), rtol=REL,
                               atol=0.0)
    cs, ps = cli_summary["settings"], py["settings"]
    for key in ["search", "steady", "limits"]:
        assert cs[key] == ps[key], key
    assert cs["noise"].keys() == ps["noise"].keys()
    for key, value in cs["noise"].items():
        assert math.isclose(ps["noise"][key], value, rel_tol=REL, abs_tol=0.0), key
    # The pre-roll is the problem's: five ring-up times 2 m / b of the cantilever (its damping
    # does not vary over the range), 5 * 2 * 5e-3 / 0.0754 s, rounded up to a whole
    # millisecond.
    assert ps["noise"]["transient_s"] == pytest.approx(5 * 2 * 5e-3 / 0.0754, abs=1e-3)
    assert ps["accel_rms_g"] is None and ps["freqs_hz"] == []


def test_design_under_noise_refuses_what_it_cannot_do(root):
    dev = endstop.Device.from_toml(root / NOISE_DEVICE)
    r = [("load.resistance_ohm", 1e3, 1e5)]
    with pytest.raises(ValueError, match="psd_g2_per_hz replaces"):
        endstop.design(dev, r, 120.0, 0.3, samples=4, **NOISE)
    with pytest.raises(ValueError, match="impact speed"):
        endstop.design(dev, r, samples=4, max_impact_speed_m_s=0.1, **NOISE)
    with pytest.raises(ValueError, match="at least 2 records"):
        endstop.design(dev, r, samples=4, **dict(NOISE, records=1))
    with pytest.raises(ValueError, match="fresh seed"):
        endstop.design(dev, r, samples=4, **dict(NOISE, noise_seed=2**64 - 1))
    with pytest.raises(ValueError, match="give freqs_hz and accel_rms_g"):
        endstop.design(dev, r, samples=4)


# Over a measured record: the piezoelectric cantilever driven at 120 Hz, 0.3 g rms, sampled
# for 1.2 s at 8192 Hz, its load over a decade. The rate is a power of two, so that the times
# written to the command's CSV file are exact and the command reads the record at exactly this
# rate: both sides resample the same samples at the same rates, by the same code.
RECORD_FS_HZ = 8192.0


def sine_record():
    t = np.arange(round(1.2 * RECORD_FS_HZ)) / RECORD_FS_HZ
    return t, 0.3 * np.sqrt(2.0) * 9.80665 * np.sin(2.0 * np.pi * 120.0 * t)


@pytest.mark.parametrize("integrator_rate_hz", [None, 2 * RECORD_FS_HZ])
def test_design_over_a_record_matches_endstop_design_accel_file(root, tmp_path,
                                                                integrator_rate_hz):
    t, a = sine_record()
    csv = tmp_path / "record.csv"
    # repr writes each float so that it reads back as the same float.
    csv.write_text("time_s,accel_m_per_s2\n"
                   + "".join(f"{ti!r},{ai!r}\n" for ti, ai in zip(t.tolist(), a.tolist())))
    rate = RECORD_FS_HZ if integrator_rate_hz is None else integrator_rate_hz
    out = run_cli(["design", "--device", NOISE_DEVICE, "--range",
                   "load.resistance_ohm=1e4..1e5", "--accel-file", str(csv),
                   "--sample-rate-hz", repr(rate), "--samples", "4", "--seed", "3",
                   "--map-points", "0", "--out", str(tmp_path / "cli")],
                  tmp_path)
    cli_summary = summary(out / "cli" / "summary.json")
    cli = cli_summary["numbers"]
    rows = pd.read_parquet(out / "cli" / "designs.parquet")
    # A sequence, as a designer may hold a record, for the call without resampling.
    record = a if integrator_rate_hz is not None else a.tolist()
    py = endstop.design(root / NOISE_DEVICE, [("load.resistance_ohm", 1e4, 1e5)], samples=4,
                        seed=3, accel_m_s2=record, sample_rate_hz=RECORD_FS_HZ,
                        integrator_rate_hz=integrator_rate_hz)
    best = py["best"]
    assert best["verdict"] == "optimum" and 1e4 <= best["params"]["load.resistance_ohm"] <= 1e5
    assert best["power_w"] == np.nanmax(py["designs"]["power_w"]) > 0.0
    # The same optimum as the command's, and every design the search evaluated, in order.
    assert math.isclose(best["power_w"], cli["power_w"], rel_tol=REL, abs_tol=0.0)
    assert py["evaluations"] == cli["evaluations"] == len(rows)
    for col in ["power_w", "displacement_m", "impacts_per_s", "load.resistance_ohm"]:
        np.testing.assert_allclose(py["designs"][col], rows[col].to_numpy(dtype=float),
                                   rtol=REL, atol=0.0, err_msg=col)
    # A record is deterministic: nothing is confirmed on fresh records, by either.
    assert py["power_confirmed_w"] is None and py["confirm_seed"] is None
    assert "power_confirmed_w" not in cli
    # The record as the problem holds it: the integrator's rate, its samples at that rate (the
    # record's span, its len(t) - 1 steps each cut into rate / fs), and the pre-roll the
    # problem set, the command's.
    ps, cs = py["settings"], cli_summary["settings"]
    assert ps["record"]["sample_rate_hz"] == cs["record_sample_rate_hz"] == rate
    assert ps["record"]["samples"] == (len(t) - 1) * round(rate / RECORD_FS_HZ) + 1
    assert math.isclose(ps["record"]["transient_s"], cs["record_transient_s"], rel_tol=REL)
    assert 0.0 < ps["record"]["transient_s"] < 1.2
    for key in ["search", "steady", "limits"]:
        assert cs[key] == ps[key], key
    assert ps["noise"] is None and ps["accel_rms_g"] is None and ps["freqs_hz"] == []


def record_design(root, **kw):
    """`endstop.design` of the cantilever's load over a record: the sine record at its rate
    unless the keywords replace it."""
    args = dict(accel_m_s2=sine_record()[1], sample_rate_hz=RECORD_FS_HZ, samples=4)
    args.update(kw)
    return endstop.design(root / NOISE_DEVICE, [("load.resistance_ohm", 1e4, 1e5)], **args)


def test_an_empty_record_is_refused(root):
    with pytest.raises(ValueError, match="accel_m_s2: 0 samples: must be at least 16"):
        record_design(root, accel_m_s2=[])


def test_a_record_with_a_sample_not_finite_is_refused(root):
    for bad in [float("nan"), float("inf")]:
        a = sine_record()[1]
        a[5] = bad
        with pytest.raises(ValueError, match="accel_m_s2: sample 5: accel = .* is not a finite"):
            record_design(root, accel_m_s2=a)


def test_a_record_rate_not_positive_is_refused(root):
    for bad in [0.0, -8192.0, float("nan"), float("inf")]:
        with pytest.raises(ValueError, match="sample_rate_hz = .* must be finite and > 0"):
            record_design(root, sample_rate_hz=bad)
        with pytest.raises(ValueError, match="integrator_rate_hz = .* must be finite and > 0"):
            record_design(root, integrator_rate_hz=bad)


def test_a_record_beside_the_sines_or_the_noise_is_refused(root):
    with pytest.raises(ValueError, match="accel_m_s2 replaces freqs_hz and accel_rms_g"):
        record_design(root, freqs_hz=[118.0, 120.0, 122.0], accel_rms_g=0.3)
    with pytest.raises(ValueError, match="accel_m_s2 replaces freqs_hz and accel_rms_g"):
        record_design(root, freqs_hz=120.0)
    with pytest.raises(ValueError, match="not both"):
        record_design(root, psd_g2_per_hz=1e-5)


def test_a_record_refuses_what_it_cannot_do(root):
    # Without its rate, or a rate without a record.
    with pytest.raises(ValueError, match="accel_m_s2 needs its sample_rate_hz"):
        record_design(root, sample_rate_hz=None)
    with pytest.raises(ValueError, match="give accel_m_s2 with them"):
        record_design(root, accel_m_s2=None, freqs_hz=120.0, accel_rms_g=0.3)
    # Not a 1-D record.
    with pytest.raises(ValueError, match="1-D"):
        record_design(root, accel_m_s2=np.zeros((2, 100)))
    # Shorter than the pre-roll the ranges need (0.66 s for the cantilever).
    with pytest.raises(ValueError, match="give a longer record"):
        record_design(root, accel_m_s2=sine_record()[1][:1000])
    # A record measures no impact speed.
    with pytest.raises(ValueError, match="impact speed"):
        record_design(root, max_impact_speed_m_s=0.1)


def test_the_docstring_example_runs(root, monkeypatch):
    # The example opens its device by a path relative to the repository's root.
    import doctest
    from endstop import _design
    monkeypatch.chdir(root)
    failed, tried = doctest.testmod(_design)
    assert tried >= 9 and failed == 0
