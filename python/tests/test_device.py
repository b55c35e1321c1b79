"""Device loading and validation: files, dicts, and errors that name the field and range."""

import pytest

import endstop


def test_from_toml_equals_bundled_prototype(root):
    assert endstop.Device.from_toml(root / "data/prototype2.toml") == endstop.Device.prototype(2)
    assert endstop.Device.from_toml(root / "data/prototype1.toml") == endstop.Device.prototype(1)


def test_dict_round_trip():
    dev = endstop.Device.prototype(2)
    d = dev.to_dict()
    assert d["mechanics"]["mass_kg"] == 1.2e-6
    assert endstop.Device.from_dict(d) == dev


def test_out_of_range_value_raises_param_error_naming_field_and_range():
    d = endstop.Device.prototype(2).to_dict()
    d["mechanics"]["mass_kg"] = -1.0
    with pytest.raises(endstop.ParamError) as e:
        endstop.Device.from_dict(d, "my.toml")
    msg = str(e.value)
    assert "mechanics.mass_kg" in msg and "must be" in msg and "my.toml" in msg
    assert e.value.field == "mechanics.mass_kg"
    assert isinstance(e.value, ValueError)


def test_poisson_ratio_range_is_in_the_message():
    d = endstop.Device.prototype(1).to_dict()
    d["stops"]["both"]["poisson_ratio"] = 0.7
    with pytest.raises(endstop.ParamError, match=r"stops.both.poisson_ratio.*between -1 and 0.5"):
        endstop.Device.from_dict(d)


def test_unknown_key_is_rejected():
    d = endstop.Device.prototype(2).to_dict()
    d["mechanics"]["mass_g"] = 1.0
    with pytest.raises(endstop.ParamError, match="mass_g"):
        endstop.Device.from_dict(d)


def test_copies_are_validated():
    dev = endstop.Device.prototype(2)
    assert dev.with_bias(10.0).bias_v == 10.0
    with pytest.raises(endstop.ParamError, match="transducer.bias_v"):
        dev.with_bias(-1.0)
    with pytest.raises(endstop.ParamError, match="stops.both.gap_m"):
        dev.with_endstop_gap(20e-6)  # larger than the finger overlap x0 = 10 um
    with pytest.raises(ValueError, match="linear"):
        dev.with_endstop("cubic", 0.4)


def test_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError, match="cannot read device file"):
        endstop.Device.from_toml(tmp_path / "none.toml")
