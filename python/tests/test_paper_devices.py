"""The paper's figure protocols take a device from the user only if it has the paper's topology
(an area-overlap comb pair and the same Hertz line stop on both sides): any other device is a
``ValueError`` naming what it lacks, raised before anything runs, never a panic."""

import pytest

import endstop


def example(root, name):
    return endstop.Device.from_toml(root / f"data/examples/{name}.toml")


def asymmetric_prototype():
    """Prototype 1 with its upper stop moved: two stops that differ."""
    d = endstop.Device.prototype(1).to_dict()
    stops = d["stops"]
    both = stops.pop("both", None)
    if both is not None:
        stops["upper"] = dict(both, gap_m=8e-6)
        stops["lower"] = dict(both)
    else:
        stops["upper"]["gap_m"] = 8e-6
    return endstop.Device.from_dict(d)


@pytest.mark.parametrize(
    "call",
    [
        lambda dev: endstop.paper.fig09.calibrate(dev),
        lambda dev: endstop.paper.fig09.run(dev),
        lambda dev: endstop.paper.fig09.run(calibrated=dev),
        lambda dev: endstop.paper.fig13.run(dev),
    ],
    ids=["fig09.calibrate", "fig09.run", "fig09.run(calibrated)", "fig13.run"],
)
@pytest.mark.parametrize("name", ["piezo_cantilever", "rigid_restitution", "asymmetric"])
def test_an_unsupported_device_is_a_value_error(root, call, name):
    dev = asymmetric_prototype() if name == "asymmetric" else example(root, name)
    with pytest.raises(ValueError, match="the paper's figures and calibration need"):
        call(dev)
