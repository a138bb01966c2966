"""The live arm cannot blow up on a user's input (issue 32): its step comes from the arm's own
stability check over every state a lever can command, and every pair and triple of levers
driven to full opening runs 10 s of simulated time without a stop. The stepping functions
are driven directly (no browser): the page's timer calls the same :meth:`LiveArm.tick`."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from hydroarm.arm import JOINT_NAMES, arm_points
from hydroarm.arm.stepper import ArmStepper
from hydroarm.core.tree import TreeModel, inverse_dynamics, make_tree_work
from hydroarm.errors import HydroarmError
from hydroarm.explore import LiveArm, default_arm
from hydroarm.explore.blocks import BLOCK_MASS, TABLE_TOP, TABLE_X, StackingTask
from hydroarm.explore.live import MAX_TICK, live_step
from hydroarm.integrators import system as system_kernel
from hydroarm.model.circuit_stepper import TREE_SLICE
from hydroarm.model.lever import LeverInput

RUN_S = 10.0  # simulated seconds each lever combination is driven (issue 32)


@pytest.fixture(scope="module")
def live():
    return LiveArm(default_arm())


def test_the_step_passes_the_arms_own_check(live):
    """The file's 1 ms is above the component elbow's limit at full opening (0.67-0.83 ms,
    the arm's check); the live step is below it and the check accepts it."""
    arm = live.scenario
    assert live.step < arm.step
    assert live.step == live_step(arm, live.ranges)  # remembered, the same answer
    assert live.stepper.step == live.step
    full = {n: live.ranges[n][1] for n in live.names}
    probe = arm.replace(step=live.step)
    probe.check_step()  # raises if refused
    with pytest.raises(HydroarmError, match="stable limit"):
        inputs = {
            n: LeverInput(np.array([0.0]), np.array([arm.joint(n).lever_for_angle(full[n])]))
            for n in live.names
        }
        arm.replace(inputs=inputs, initial_angles=dict.fromkeys(live.names, 0.0)).check_step()


@pytest.mark.parametrize("size", [2, 3])
def test_every_pair_and_triple_of_levers_at_full_opening_runs(live, size):
    """Each combination's levers thrown at once to the ends of their ranges (every corner),
    held for 10 s of simulated time: no stop."""
    for combo in itertools.combinations(live.names, size):
        for ends in itertools.product((0, 1), repeat=size):
            live.reset()
            for n, end in zip(combo, ends, strict=True):
                live.set_lever(n, live.ranges[n][end])
            while live.t < RUN_S - 1e-9:
                live.tick(MAX_TICK)
            assert live.state == "running", (combo, ends, live.stopped)
            a = live.angles()
            assert all(math.isfinite(v) for v in a.values()), (combo, ends, a)


def test_held_keys_together_for_two_seconds_run(live):
    """The issue's case: Q and E held together (shoulder up, elbow flexing) for 2 s, then
    every key at once for 4 s, the reverse keys, the elbow up first then the shoulder."""
    live.reset()
    for keys in (("q", "e"), ("q", "w", "e", "r"), ("a", "s", "d", "f"), ("e",), ("q", "f")):
        for k in keys:
            live.key(k, True)
        for _ in range(40):
            live.tick(MAX_TICK)
        for k in keys:
            live.key(k, False)
        assert live.state == "running", live.stopped


class _Failing:
    """A stepper that leaves the physical bounds once past 0.05 s (in the second tick)."""

    def __init__(self, sc):
        self.levers: dict = {}
        self.hand_mass = 0.0
        self.t = 0.0
        self.inner = ArmStepper(sc)

    def advance(self, dt):
        if self.inner.t >= 0.05 - 1e-9:
            raise HydroarmError("solver.step", "the run left the physical bounds (test)")
        self.inner.levers = self.levers
        self.inner.advance(dt)
        self.t = self.inner.t

    def servo_angles(self):
        return self.inner.servo_angles()

    def stop_joints(self, theta, joints):
        self.inner.stop_joints(theta, joints)

    def get_state(self):
        return self.inner.get_state()

    def set_state(self, state):
        self.inner.set_state(state)

    def outputs(self):
        return self.inner.outputs()


def test_a_stop_is_one_state_until_reset():
    """After a stop the state is 'stopped' (what the button, the clock and the message show),
    pausing does not resume it, ticks advance nothing; reset runs again."""
    live = LiveArm(default_arm(), _Failing)
    live.tick(0.05)
    with pytest.raises(HydroarmError, match="physical bounds"):
        live.tick(0.05)
    assert live.state == "stopped" and "physical bounds" in live.stopped
    live.toggle_pause()
    assert live.state == "stopped"
    assert live.tick(0.05) == 0.0
    live.reset()
    assert live.state == "running" and live.stopped == ""


def test_client_values_are_checked(live):
    for bad in ("abc", None, [], {"x": 1}, True, math.nan):
        with pytest.raises(HydroarmError, match="lever.elbow_reach"):
            live.set_lever("elbow_reach", bad)  # type: ignore[arg-type]
    with pytest.raises(HydroarmError, match="lever"):
        live.set_lever(["elbow_reach"], 0.1)  # type: ignore[arg-type]
    with pytest.raises(HydroarmError, match="key"):
        live.key(None, True)  # type: ignore[arg-type]


# the grasp's payload and the table's floor (issue 32) ----------------------------------------
PICK = {  # the pick pose of the default block transfer: the first block under the hand
    "shoulder_elevation": 35.0,
    "humeral_rotation": 0.0,
    "elbow_reach": 95.0,
    "wrist_rotation": 60.0,
}


def _to(live, degrees: dict, seconds: float = 4.0) -> list[float]:
    """Set the levers [deg] and tick for ``seconds`` of simulated time; the hand's heights."""
    for n, v in degrees.items():
        live.set_lever(n, math.radians(v))
    end = live.t + seconds
    heights = []
    while live.t < end - 1e-9:
        live.tick(MAX_TICK)
        heights.append(float(live.hand()[2]))
    return heights


def _holding_torques(stepper, mass: float) -> dict[str, float]:
    """The torques [N m] that hold the arm against gravity at the stepper's state with
    ``mass`` [kg] in the hand: the inverse dynamics at rest of the mechanism's tree the kernel
    takes (its net), each coupled joint's carried to its master by virtual work (the shoulder
    extension's to the elbow, × its ratio), by the arm's joint names."""
    stepper.hand_mass = mass
    c = stepper.circuit
    tree = TreeModel(*c.net[TREE_SLICE])
    q = np.ascontiguousarray(c.joint_positions()[0])
    n = q.size
    tau, zero = np.zeros(n), np.zeros(n)
    inverse_dynamics(tree, q, zero, zero, np.zeros((n, 6)), make_tree_work(n), tau)
    mech = c.compiled.mechanism
    for i, m in enumerate(mech.master):
        if m != i:
            tau[m] += mech.ratio[i] * tau[i]
    return {name: float(tau[mech.joint_names.index(name)]) for name in stepper.names}


def test_a_grasped_block_loads_the_joints_by_its_weight(live):
    """Grasped, the block's mass is the hand's payload: the torques holding the arm in the
    tree the kernel steps differ from the empty hand's by its weight × its moment arm — the
    shoulder's m·g·x (the hand's horizontal distance from the shoulder's axis), the elbow's
    m·g·∂z/∂ε (its virtual work, ∂z/∂ε by central differences of the arm's points), none on
    the humeral rotation at ψ = 0 or on the wrist. Tolerances: the shoulder's closed form
    against the point, rounding (1e-9 relative); the elbow's central difference at 1e-6 rad
    (rounding ~1e-10 m/rad, 1e-7 relative). The kernel is not compiled again."""
    live.reset()
    empty = live.empty_hand_mass
    assert empty == live.scenario.geometry.hand_mass == live.stepper.hand_mass
    g = live.scenario.geometry
    held = live.scenario.replace(geometry=g.replace(hand_mass=empty + BLOCK_MASS))
    assert live.step <= live_step(held, live.ranges)  # stable with the block held too
    _to(live, PICK)
    assert live.grasp() == "grasped 1"
    assert live.stepper.hand_mass == pytest.approx(empty + BLOCK_MASS, abs=1e-15)
    signatures = len(system_kernel.advance.signatures)
    st = live.stepper
    state = st.get_state()
    theta = st.servo_angles()
    loaded = _holding_torques(st, empty + BLOCK_MASS)
    bare = _holding_torques(st, empty)
    st.hand_mass = empty + BLOCK_MASS
    st.advance(0.01)  # stepped with the trees swapped in
    assert len(system_kernel.advance.signatures) == signatures
    st.set_state(state)
    q = np.array([theta[st.names.index(n)] + live._offsets[n] for n in JOINT_NAMES])
    weight = BLOCK_MASS * live._G.gravity
    x_hand = arm_points(q, live._G)[2, 0]
    assert x_hand > 0.15  # the pick pose: the hand 0.2 m in front of the shoulder
    d = 1e-6
    dq = np.zeros(4)
    dq[JOINT_NAMES.index("elbow_reach")] = d
    dz = (arm_points(q + dq, live._G)[2, 2] - arm_points(q - dq, live._G)[2, 2]) / (2 * d)
    diff = {n: loaded[n] - bare[n] for n in st.names}
    assert diff["shoulder_elevation"] == pytest.approx(weight * x_hand, rel=1e-9)
    assert diff["elbow_reach"] == pytest.approx(weight * dz, rel=1e-7)
    assert abs(diff["humeral_rotation"]) < 1e-15 and abs(diff["wrist_rotation"]) < 1e-15
    assert live.grasp() == "released 1"
    assert live.stepper.hand_mass == empty
    live.grasp()
    live.reset()
    assert live.stepper.hand_mass == empty and live.task.held is None


def test_the_table_is_a_floor_the_hand_cannot_pass(live):
    """From the pick pose (over the table) the shoulder's lever thrown to 0° drives the hand
    down onto the table for 2 s: the hand stays at or above the top at every tick (exactly:
    a piece of motion that would pass it is undone), resting on it within one contact
    piece's travel (2 ms at under 0.5 m/s: 1 mm), the shoulder stalled against it; the
    lever set back lifts the hand off."""
    live.reset()
    _to(live, PICK)
    assert live.task.over_table(live.hand()) and live.hand()[2] > TABLE_TOP
    relief = live.gauges()["relief_pressure"]
    down = _to(live, {"shoulder_elevation": 0.0}, 2.0)
    assert min(down) >= TABLE_TOP
    assert down[-1] - TABLE_TOP < 1e-3
    assert live.task.over_table(live.hand())
    assert math.degrees(live.angles()["shoulder_elevation"]) > 25.0  # held up by the table
    assert live.gauges()["pressures"]["shoulder_elevation"] < -0.9 * relief  # pushing down
    assert live.state == "running"
    up = _to(live, {"shoulder_elevation": PICK["shoulder_elevation"]}, 2.0)
    assert up[-1] - TABLE_TOP > 0.015


def test_the_arm_at_rest_hangs_beside_the_table(live):
    """The levers at their start: the hand hangs below the shoulder, behind the table's near
    edge (60 mm in front of the shoulder), not over the table, and stays there."""
    live.reset()
    for _ in range(10):
        live.tick(MAX_TICK)
        p = live.hand()
        assert p[0] < TABLE_X[0] and not live.task.over_table(p)


def test_the_floor_is_the_table_top_within_its_extent():
    """Only a move from at or above the top to below it, over the table, passes the floor;
    beside the table or from below (under it) the hand is free."""
    task = StackingTask()
    over = (0.2, 0.0)
    top = TABLE_TOP
    assert task.through_table((*over, top + 0.01), (*over, top - 1e-9))
    assert task.through_table((*over, top), (*over, top - 0.001))
    assert task.through_table((0.0, 0.0, top + 0.01), (0.07, 0.0, top - 0.001))
    assert not task.through_table((*over, top + 0.01), (*over, top))
    assert not task.through_table((0.0, 0.0, top + 0.01), (0.0, 0.0, top - 0.01))
    assert not task.through_table((*over, top - 0.05), (*over, top - 0.04))
    assert not task.through_table((0.2, 0.3, top + 0.01), (0.2, 0.3, top - 0.01))
