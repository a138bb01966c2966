"""A mechanism live (issue 32): a mechanism file's levers drive its joints through the
system's own stepper (:class:`hydroarm.model.circuit_stepper.CircuitStepper`), stepped as the
page's timer does, without a browser (tests/test_explore_system_browser.py drives the page)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from explore_server import excavator_copy  # tests/explore_server.py

from hydroarm.errors import HydroarmError
from hydroarm.explore.live import MAX_TICK
from hydroarm.explore.live_system import LiveSystem
from hydroarm.explore.scene import link_frame
from hydroarm.explore.system import load_system_model
from hydroarm.model.circuit_stepper import CircuitStepper
from hydroarm.model.mechanism import Payload

BOOM = Path(__file__).parent / "data" / "mechanism" / "boom.toml"
EXAMPLES = Path(__file__).parents[1] / "examples"


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


def test_the_supply_gauge_of_a_tank_at_supply_pressure(live):
    """The boom's supply is a tank at 100 bar (the return tank, at the lowest pressure, is
    not a supply): one gauge, its scale 0 to 150 bar, reading the node's pressure."""
    live.reset()
    (sup,) = live.supplies
    assert (sup.node, sup.sources, sup.what) == ("P", ("supply",), "tank")
    assert sup.setting == pytest.approx(100e5) and sup.top == pytest.approx(150e5)
    assert live.pressures()["P"] == pytest.approx(100.0)


# ---------------------------------------------------------------- the excavator's task ---
@pytest.fixture(scope="module")
def excavator(tmp_path_factory):
    return LiveSystem(load_system_model(excavator_copy(tmp_path_factory.mktemp("excavator"))))


def _hold(live) -> None:
    """Every setpoint held where it is now (the file's waveform stopped)."""
    for lv in live.levers:
        live.set_lever(lv.name, live.value(lv.name))


def test_setpoints_and_the_supply_of_the_excavator(excavator):
    """Electronic feedback (a pid fed by a signal source, measuring a joint): a setpoint in
    deg over the joint's limits; the pump's node is the supply, its relief sets the scale."""
    live = excavator
    by = {lv.joint: lv for lv in live.levers}
    assert set(by) == {"boom", "stick", "bucket"}
    boom = by["boom"]
    assert boom.unit == "deg" and boom.name == "boom_reference.value"
    assert (boom.shown(boom.low), boom.shown(boom.high)) == pytest.approx((-45.0, 50.0))
    assert by["stick"].shown(by["stick"].start) == pytest.approx(-80.0)
    assert boom.signal_of(30.0) == pytest.approx(math.radians(30.0))
    (sup,) = live.supplies
    assert (sup.node, sup.sources, sup.what) == ("P", ("pump",), "relief")
    assert sup.top == pytest.approx(1.5 * 310e5)


def test_a_grasped_load_is_the_files_payload_on_the_hand(excavator):
    """The task's load is the file's soil: the live circuit starts without it, and the grasp
    adds it to the bucket: from then on the steps are those of the file's circuit (soil in
    the bucket) from the same state, to the last bit (one physics: the tree's arrays swapped,
    no kernel compiled); held at the dig point, the boom's cap-side pressure rises."""
    live = excavator
    live.reset()
    task = live.task
    assert task.load.name == "soil" and task.load.mass == pytest.approx(1980.0)
    assert task.where == "table" and np.linalg.norm(live.tip() - task.centre) < task.size
    _hold(live)
    for _ in range(10):
        live.tick(MAX_TICK)
    p0 = live.pressures()["boom_a"]
    state = live.stepper.get_state()
    assert live.grasp() == "the load (1980 kg) held on bucket"
    ref = CircuitStepper(live.model.runner.compiled)  # the file's circuit, soil included
    ref.set_state(state)
    for _ in range(10):
        live.tick(MAX_TICK)
    ref.advance(1.0)
    assert live.t == ref.t
    # every state and parameter equal (the requested times, summed ticks or one call, aside)
    assert live.stepper.get_state()[3:].tolist() == ref.get_state()[3:].tolist()
    p1 = live.pressures()["boom_a"]
    # 1980 kg about 6 m out from the boom's foot: some 40-60 bar more under the boom's piston
    assert p1 > p0 + 30.0, (p0, p1)
    # the holding torques: the soil's weight times its moment arm about each joint's axis
    held = live.holding()
    live.stepper.set_payloads(())
    empty = live.holding()
    live.stepper.set_payloads((task.load,))
    arm = live.load_point() - live.points()[1:4]  # from each joint's origin, the axes -y
    w = 1980.0 * 9.80665
    for k, name in enumerate(("boom", "stick", "bucket")):
        assert held[name] - empty[name] == pytest.approx(w * arm[k, 0], rel=1e-9)
    assert held["boom"] - empty["boom"] > 100e3  # N·m
    assert task.centre.tolist() == live.load_point().tolist()  # drawn where it sits
    # released away from the truck: it drops onto the pit floor; reset: on the floor again
    assert "dropped on the table" in live.grasp()
    assert live.stepper.payloads == ()
    live.reset()
    assert task.where == "table" and task.centre.tolist() == task.block0.tolist()
    assert live.model.task is not task  # each visitor's own (the model's is shared)


def test_the_table_is_a_floor_for_the_tip(excavator):
    """The setpoints thrown to a pose whose tip is 0.65 m below the pit floor (boom -30,
    stick -90, bucket -90 deg): at every tick the tip stays at or above the floor, and ends
    on it (within 5 mm), the boom stopped above -30 deg and pushing at the supply."""
    live = excavator
    live.reset()
    for name, deg in (("boom", -30.0), ("stick", -90.0), ("bucket", -90.0)):
        lv = live.lever(f"{name}_reference.value")
        live.set_lever(lv.name, lv.signal_of(deg))
    heights = []
    for _ in range(30):
        live.tick(MAX_TICK)
        heights.append(live.task.height(live.tip()) - live.task.table)
    assert min(heights) >= 0.0, heights
    assert heights[-1] < 0.005, heights
    boom = live.stepper.outputs()["boom_angle_deg"]
    assert boom > -25.0
    assert live.pressures()["boom_b"] > 0.9 * live.pressures()["P"]


def test_a_stepper_stops_joints_and_takes_payloads(live):
    """CircuitStepper's contact and payload entries: a joint stopped is at rest where it was
    put, the pressures kept; a payload on a link the mechanism lacks is refused with its
    field; a joint index outside the tree is refused."""
    live.reset()
    s = live.stepper
    s.advance(0.05)
    p = s.outputs()["A_pressure_bar"]
    s.stop_joints({0: 0.1})
    q, v = s.joint_positions()
    assert q.tolist() == [0.1] and v.tolist() == [0.0]
    assert s.outputs()["A_pressure_bar"] == p
    with pytest.raises(HydroarmError, match="not a free joint"):
        s.stop_joints({3: 0.0})
    with pytest.raises(HydroarmError, match="mechanism.payload"):
        s.set_payloads((Payload("x", "nowhere", 1.0),))
    live.reset()


def test_a_setpoint_on_a_cylinders_rod_is_in_mm():
    """The UCL arm as a mechanism: its elbow's loop measures the elbow cylinder's rod (a node
    its linkage positions, not the joint): that setpoint's slider is the rod's position in
    mm (the range the file's run sets: ±1.5 × its largest reference, 4.08 mm); the other
    joints' levers (valve demands, no loop) stay in SI; the pump's node is the supply."""
    live = LiveSystem(load_system_model(EXAMPLES / "ucl-arm-mechanism.toml"))
    by = {lv.name: lv for lv in live.levers}
    elbow = by["elbow_reach_reference.value"]
    assert (elbow.joint, elbow.unit) == ("elbow_reach_rod", "mm")
    assert elbow.shown(elbow.high) == pytest.approx(1.5 * 4.080064390440961, rel=1e-9)
    assert by["shoulder_elevation_lever.value"].unit == "SI"
    (sup,) = live.supplies
    assert (sup.node, sup.what) == ("supply", "relief")
