"""Fitting from Python: the twin of ``endstop fit`` recovers a known device and names a bad
free parameter."""

import numpy as np
import pytest

import endstop


def _truth():
    # Prototype 2 with a 9 um gap, inside the gap's range (it must not exceed x0 = 10 um).
    return endstop.Device.prototype(2).with_endstop_gap(9e-6)


def test_fit_recovers_the_gap_and_damping_of_a_noise_free_sweep():
    truth = _truth()
    s = endstop.study.up_sweep(truth, 0.3, 600.0, 760.0, step_hz=10.0)
    n = 17  # the requested grid; later steps extend the sweep while in contact
    f, v = s["freq_hz"][:n], s["v1_rms_v"][:n]
    data = endstop.fit.sweep_data(f, v, 0.3, sigma=0.02 * v, jump=(s["branch_end_hz"], 1.0))
    start = truth.with_endstop_gap(8.3e-6).to_dict()
    start["mechanics"]["damping_n_s_per_m"] = 3.2e-5
    r = endstop.fit.fit(
        endstop.Device.from_dict(start, "start"),
        [data],
        {"mechanics.damping_n_s_per_m": (1e-5, 1e-4), "stops.both.gap_m": (7e-6, 1e-5)},
    )
    assert r["converged"], r
    assert "Gauss-Newton" in r["uncertainty"]
    truth_values = {"mechanics.damping_n_s_per_m": 2.5e-5, "stops.both.gap_m": 9e-6}
    for p in r["params"]:
        lo, hi = p["interval"]
        assert lo <= truth_values[p["path"]] <= hi, p
    assert isinstance(r["device"], endstop.Device)
    assert np.asarray(r["correlation"]).shape == (2, 2)
    assert r["residuals"]["model"].shape == (n + 1,)
    # Every start of the design is listed, and the reported one among them.
    assert r["starts_tried"] == len(r["starts"]) > 1
    assert sum(s["reported"] for s in r["starts"]) == 1
    assert r["headline"] is None, r["headline"]


def test_a_device_with_an_interface_circuit_is_refused_naming_it(root):
    # The fit models a transducer on its resistive load: a bridge must not be fitted as if
    # it were not there.
    bridge = endstop.Device.from_toml(root / "data/examples/piezo_bridge.toml")
    data = endstop.fit.sweep_data([100.0, 110.0, 120.0], [0.1, 0.2, 0.3], 0.5)
    with pytest.raises(ValueError, match="interface circuit .*full_bridge"):
        endstop.fit.fit(bridge, [data], {"stops.upper.gap_m": (0.05e-3, 0.3e-3)})


def test_an_unknown_free_parameter_raises_param_error_naming_it():
    data = endstop.fit.sweep_data([600.0, 610.0, 620.0], [0.1, 0.2, 0.3], 0.3)
    with pytest.raises(endstop.ParamError) as e:
        endstop.fit.fit(_truth(), [data], {"mechanics.no_such_key": (1.0, 2.0)})
    assert e.value.field == "mechanics.no_such_key"
