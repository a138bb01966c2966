"""A mechanism live (issue 32): a mechanism file's levers drive its joints through the
system's own stepper (:class:`hydroarm.model.circuit_stepper.CircuitStepper`), stepped as the
page's timer does, without a browser (tests/test_explore_system_browser.py drives the page)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from hydroarm.errors import HydroarmError
from hydroarm.explore.live import MAX_TICK
from hydroarm.explore.live_system import LiveSystem
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
    pose = live.pose()
    assert len(pose["series"][0]["data"]) == len(live.parents) - 1  # a segment per link


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
