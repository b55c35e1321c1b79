"""Simulations from Python: shapes, internal consistency, argument checks and the GIL."""

import threading

import numpy as np
import pytest

import endstop


def test_record_voltages_give_its_power():
    dev = endstop.Device.prototype(2)
    r = endstop.study.record(dev, 1e-4, seed=3, stream=1, duration_s=0.5)
    n = round(0.5 * r["sample_rate_hz"])
    assert r["v1_v"].shape == (n,) and r["v2_v"].shape == (n,)
    rl = dev.to_dict()["transducer"]["load_resistance_ohm"]
    # The summary's power is the mean of V^2/R over the same samples (summation order aside).
    assert r["p1_w"] == pytest.approx(float(np.mean(r["v1_v"] ** 2)) / rl, rel=1e-9)
    assert r["p2_w"] == pytest.approx(float(np.mean(r["v2_v"] ** 2)) / rl, rel=1e-9)


def test_same_seed_same_record_other_stream_another():
    dev = endstop.Device.prototype(2)
    a = endstop.study.record(dev, 1e-4, seed=3, stream=0, duration_s=0.2)
    b = endstop.study.record(dev, 1e-4, seed=3, stream=0, duration_s=0.2)
    c = endstop.study.record(dev, 1e-4, seed=3, stream=1, duration_s=0.2)
    assert np.array_equal(a["v1_v"], b["v1_v"])
    assert not np.array_equal(a["v1_v"], c["v1_v"])


def test_amplitude_sweep_brackets_its_onset():
    # 665 Hz lies below the linear resonance of prototype 2 at 10 V (671 Hz) and above the
    # impact onset of Figure 13's 0.31 g up-sweep (661.7 Hz): the mass reaches the stops
    # before 0.31 g, so the onset falls inside 0.1-0.4 g.
    dev = endstop.Device.prototype(2).with_bias(10.0)
    assert 665.0 < endstop.linear.two_port(dev)["resonance_hz"]
    acc = np.linspace(0.1, 0.4, 7)
    r = endstop.study.amplitude_sweep(dev, 665.0, acc)
    assert np.array_equal(r["accel_rms_g"][: len(acc)], acc)
    assert r["onset_g"] is not None
    lo, hi = r["onset_bracket_g"]
    assert lo < r["onset_g"] < hi and hi - lo <= 0.005
    first = int(np.argmax(r["contact_fraction"] > 0))
    assert r["accel_rms_g"][first - 1] <= lo and hi <= r["accel_rms_g"][first]


def test_orbits_of_figure13_fold_above_the_grazing_and_change_stability_there():
    # Figure 13's device and drive: the impacting branch turns at a fold (the up-sweep's
    # jump) above the upper grazing point, and the orbits change stability at each fold.
    dev = endstop.Device.prototype(2).with_bias(10.0)
    r = endstop.study.orbits(dev, 0.31, start_hz=600, stop_hz=800, step_hz=2)
    assert r["max_residual"] < 1e-9
    n = len(r["freq_hz"])
    assert r["v1_rms_v"].shape == (n,) and len(r["stable"]) == n
    assert r["folds_hz"] and r["grazing_hz"]
    assert max(r["folds_hz"]) > max(r["grazing_hz"])
    for e in r["events"]:
        if e["kind"] == "fold" and not e["at_grazing"]:
            assert e["stable_before"] != e["stable_after"], e


def test_down_sweep_runs_downwards_and_ends_its_branch():
    dev = endstop.Device.prototype(2).with_bias(10.0)
    r = endstop.study.down_sweep(dev, 0.31, start_hz=600, stop_hz=800, step_hz=4)
    assert np.all(np.diff(r["freq_hz"]) < 0)
    assert r["branch_end_hz"] is not None and r["branch_end_kind"] is not None


def test_a_chirp_record_holds_the_sine_through_the_preroll_then_sweeps():
    dev = endstop.Device.prototype(2)
    steady = endstop.study.sine_record(dev, 0.05, 650.0, duration_s=0.1)
    unswept = endstop.study.sine_record(dev, 0.05, 650.0, duration_s=0.1, chirp_to_hz=650.0)
    swept = endstop.study.sine_record(dev, 0.05, 650.0, duration_s=0.1, chirp_to_hz=750.0)
    # Without a sweep the drive is the steady sine's, bit for bit.
    assert np.array_equal(steady["v1_v"], unswept["v1_v"])
    # The pre-roll is the steady sine's, so the first analysed sample is too; then it sweeps.
    assert swept["v1_v"][0] == steady["v1_v"][0]
    assert not np.array_equal(swept["v1_v"], steady["v1_v"])
    with pytest.raises(ValueError, match="chirp_to_hz"):
        endstop.study.sine_record(dev, 0.05, 650.0, chirp_to_hz=-1.0)


def test_bad_arguments_raise_value_errors():
    dev = endstop.Device.prototype(2)
    with pytest.raises(ValueError, match="stop_hz"):
        endstop.study.up_sweep(dev, 0.3, start_hz=800, stop_hz=700)
    with pytest.raises(ValueError, match="psd"):
        endstop.study.record(dev, -1.0)
    with pytest.raises(ValueError, match="records"):
        endstop.study.ensemble(dev, 1e-4, records=0)
    with pytest.raises(ValueError, match="stop_hz"):
        endstop.study.orbits(dev, 0.3, start_hz=800, stop_hz=700)
    with pytest.raises(ValueError, match="accel_rms_g"):
        endstop.study.down_sweep(dev, 0.0, start_hz=600, stop_hz=700)


def test_simulations_release_the_gil():
    # While this thread runs a 100 s record (about 1.2 s here), another thread counts to
    # 400 000 in pure Python (about 0.05 s here, ten switch intervals of 5 ms); both slow alike
    # on a loaded machine. With the GIL released the count finishes during the record. Had the
    # call kept the GIL, the count could run only while this thread is in Python around the
    # call, a switch interval or two, and would not have finished when the call returned. (A
    # check the other way round, the record in the other thread, cannot fail: when the call
    # returns, the waiting thread may take the GIL before the record's thread marks it done.)
    # The same pattern, with the GIL held in a planted build, fails `test_design.py`'s check.
    # No clock is read.
    dev = endstop.Device.prototype(2)
    counted = threading.Event()

    def count():
        n = 0
        for _ in range(400_000):
            n += 1
        counted.set()

    th = threading.Thread(target=count)
    th.start()
    endstop.study.record(dev, 1e-4, duration_s=100.0)
    finished_during = counted.is_set()
    th.join()
    assert finished_during, "the count could not run during the record: the GIL was held"
