"""A mechanism live (issue 32): a mechanism file's levers drive its joints through the
system's own stepper (:class:`hydroarm.model.circuit_stepper.CircuitStepper`), stepped as the
page's timer does, without a browser (tests/test_explore_system_browser.py drives the page)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.errors import HydroarmError
from hydroarm.explore.live import MAX_TICK
from hydroarm.explore.live_system import LiveSystem
from hydroarm.explore.scene import link_frame
from hydroarm.explore.system import load_system_model
from hydroarm.model.circuit_stepper import CircuitStepper

BOOM = Path(__file__).parent / "data" / "mechanism" / "boom.toml"


@pytest.fixture(scope="module")
def live():
    return LiveSystem(load_system_model(BOOM))


def _angle(live) -> float:
    return float(live.stepper.outputs()["lift_angle_deg"])


def test_the_lever_is_the_files_signal_source(live):
    (lever,) = live.levers
    # the file's lever steps to +0.3 mm and -0.2 mm: the range is ±1.5 × 0.3 mm
    assert lever.name == "lever.value" and lever.signal == "spool"
    assert (lever.low, lever.high) == pytest.approx((-0.45e-3, 0.45e-3), rel=1e-12)
    assert live.joints() == {"lift": f"{_angle(live):.2f} deg"}


def test_a_lever_drives_the_joint_as_the_stepper_does(live):
    """The lever opened: the boom rises; the angle is the stepper's of the same input (one
    physics: the same kernel, the same steps, so equal to the last bit)."""
    live.reset()
    a0 = _angle(live)
    live.set_lever("lever.value", 0.3e-3)
    for _ in range(5):
        live.tick(MAX_TICK)  # 0.5 s
    ref = CircuitStepper(live.model.runner.compiled)
    ref.set_input("lever.value", 0.3e-3)
    ref.advance(0.5)
    assert live.t == pytest.approx(0.5, abs=1e-9)
    assert _angle(live) == ref.outputs()["lift_angle_deg"]
    assert _angle(live) > a0 + 1.0  # degrees: the boom rose
    # the other way: it falls back
    live.set_lever("lever.value", -0.45e-3)
    before = _angle(live)
    for _ in range(3):
        live.tick(MAX_TICK)
    assert _angle(live) < before
    assert live.value("lever.value") == -0.45e-3


def test_the_3d_view_fits_the_mechanism_and_follows_the_lever(live):
    """The stick points the scene draws: the boom's tip (0.8 m out) at the joint's angle;
    the view: up against gravity, the camera far enough to see the sphere round every pose
    over the joint's range (-30 to 60 deg), the ground grid under the lowest point."""
    live.reset()
    view = live.view
    assert view["up"].tolist() == [0.0, 0.0, 1.0]  # gravity along -z
    P = live.points()
    assert live.parents == [-1, 0, 1] and P.shape == (3, 3)
    a = math.radians(_angle(live))
    assert P[2] == pytest.approx([0.8 * math.cos(a), 0.0, 0.8 * math.sin(a)], abs=1e-9)
    # the range's ends: tips at z = 0.8 sin(60 deg) and 0.8 sin(-30 deg) inside the sphere
    for deg in (-30.0, 60.0):
        tip = np.array([0.8 * math.cos(math.radians(deg)), 0, 0.8 * math.sin(math.radians(deg))])
        assert np.linalg.norm(tip - view["centre"]) <= view["radius"] + 1e-9
    dist = np.linalg.norm(view["camera"] - view["centre"])
    assert dist * math.sin(math.radians(view["fov"] / 2)) >= view["radius"]
    assert view["camera"] @ view["up"] > view["centre"] @ view["up"]  # looking down a little
    heights = {round(p @ view["up"], 9) for line in view["ground"] for p in map(np.array, line)}
    assert heights == {round(-0.4, 9)}  # the grid at the lowest tip, 0.8 sin(-30 deg)
    # the lever opened: the tip rises, as drawn
    live.set_lever("lever.value", 0.3e-3)
    for _ in range(3):
        live.tick(MAX_TICK)
    assert live.points()[2, 2] > P[2, 2] + 0.01
    # a link's frame takes the cylinder's axis (local y) along the link
    R = np.array(link_frame(live.points()[2] - live.points()[1], view["up"]))
    d = live.points()[2] / np.linalg.norm(live.points()[2])
    assert R @ [0.0, 1.0, 0.0] == pytest.approx(d, abs=1e-12)
    assert R.T @ R == pytest.approx(np.eye(3), abs=1e-12)
    # no length: along up
    assert np.array(link_frame(np.zeros(3), view["up"])) @ [0, 1, 0] == pytest.approx([0, 0, 1])


def test_levers_are_clamped_and_checked(live):
    live.reset()
    live.set_lever("lever.value", 1.0)  # far beyond: held at the range's end
    assert live.value("lever.value") == pytest.approx(0.45e-3, rel=1e-12)
    for bad in ("abc", None, math.nan, True):
        with pytest.raises(HydroarmError, match="lever.lever.value"):
            live.set_lever("lever.value", bad)
    with pytest.raises(HydroarmError, match="not a lever"):
        live.set_lever("supply.pressure", 1e5)


def test_a_circuit_without_a_mechanism_has_no_live_view():
    servo = Path(__file__).parents[1] / "examples" / "circuit_position_servo.toml"
    with pytest.raises(HydroarmError, match="needs a mechanism"):
        LiveSystem(load_system_model(servo))
