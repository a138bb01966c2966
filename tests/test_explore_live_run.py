"""The live arm cannot blow up on a user's input (issue 32): its step comes from the arm's own
stability check over every state a lever can command, and every pair and triple of levers
driven to full opening runs 10 s of simulated time without a stop. The stepping functions
are driven directly (no browser): the page's timer calls the same :meth:`LiveArm.tick`."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from hydroarm.arm.stepper import ArmStepper
from hydroarm.errors import HydroarmError
from hydroarm.explore import LiveArm, default_arm
from hydroarm.explore.live import MAX_TICK, live_step
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
