"""Simulations from Python: shapes, internal consistency, argument checks and the GIL."""

import threading
import time

import numpy as np
import pytest

import endstop


def test_record_voltages_give_its_power():
    dev = endstop.Device.prototype(2)
    r = endstop.study.record(dev, 1e-4, seed=3, stream=1, duration_s=0.5)
    n = round(0.5 * r["sample_rate_hz"])
    assert r["v1_v"].shape == (n,) and r["v2_v"].shape == (n,)
    rl = dev.to_dict()["electrical"]["load_resistance_ohm"]
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


def test_bad_arguments_raise_value_errors():
    dev = endstop.Device.prototype(2)
    with pytest.raises(ValueError, match="stop_hz"):
        endstop.study.up_sweep(dev, 0.3, start_hz=800, stop_hz=700)
    with pytest.raises(ValueError, match="psd"):
        endstop.study.record(dev, -1.0)
    with pytest.raises(ValueError, match="records"):
        endstop.study.ensemble(dev, 1e-4, records=0)


def test_simulations_release_the_gil():
    # While a record is simulated in another thread, this thread keeps running Python: it
    # visits most of the 10 ms slots of the call. Holding the GIL would leave it at most the
    # interpreter's switch interval (5 ms) before the call and none during it.
    dev = endstop.Device.prototype(2)
    state = {"running": False, "t": (0.0, 0.0)}

    def work():
        state["running"] = True
        t0 = time.perf_counter()
        endstop.study.record(dev, 1e-4, duration_s=2.0)
        state["t"] = (t0, time.perf_counter())
        state["running"] = False

    th = threading.Thread(target=work)
    slots = set()
    th.start()
    while th.is_alive():
        if state["running"]:
            slots.add(int(time.perf_counter() / 0.01))
    th.join()
    t0, t1 = state["t"]
    expected = (t1 - t0) / 0.01
    assert expected > 10, "the call was too short to tell"
    assert len(slots) > 0.5 * expected, (len(slots), expected)
