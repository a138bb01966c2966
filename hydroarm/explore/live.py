"""The live arm's state: four levers set by sliders and held keys, the arm stepped server-side
at the wall clock's pace, its pose, gauges, the block-stacking task and the recording.

Plain Python (no web framework): the page calls `LiveArm.tick` from a timer with the
wall time elapsed, and `LiveArm.key`, `LiveArm.set_lever` from its controls.

Levers. As on the paper's lever box, a lever's position commands its joint's articulation
angle (the servo follows the lever: eq. (2)); the lever positions are kept as articulation
angles [rad] and given to the stepper as valve-lever positions [m] by
`hydroarm.arm.model.ArmJoint.lever_for_angle`, as the arm file's ``[inputs] csv`` does.
A held key moves its lever at `LEVER_RATE` (simulated time); several keys may be held
at once. The recording is the lever positions against simulated time, one row per tick in
which a lever moved (and the first and last): ``examples/block_stacking.csv``'s columns,
which the ``arm`` command replays by linear interpolation between rows, as the live run
held them.

The physics is the arm's circuit on the system kernel through
`hydroarm.arm.stepper.ArmStepper` (one physics: `hydroarm.arm.expand.arm_circuit` stepped
by a `CircuitStepper`); this module only sets its levers and its hand's payload and reads its
outputs. A held block's mass (`BLOCK_MASS`) is added to the
arm file's hand mass while it is held (`LiveArm._payload`: the mechanism's tree the kernel
takes carries it). The table top is a floor for the hand point (`LiveArm._contact`, checked
every `CONTACT_STEP`): the joints that pushed the hand down through it are stopped.

A run that cannot blow up on a user's input. The step is the arm's own stability check
(`hydroarm.arm.model.ArmScenario.check_step`, which ``hydroarm arm`` applies to a file)
at every state a lever can command (`live_step`): each joint started at either end and
the middle of its lever range with its lever at the other end (full valve opening), so that
whatever the levers do the step is stable for the state the arm is in (the file's 1 ms is not:
the component elbow's limit at full opening is 0.67-0.83 ms). The shoulder's lever stops at
80°: above it the elbow's jack, 31 bar on its annulus, cannot hold the forearm, which falls
past its crank's dead centre (physics, not the step: the same fall at 0.1 ms). Should a run
still leave the physical bounds, the live arm stops with the message in
`LiveArm.stopped`, and only `LiveArm.reset` goes on.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..arm import JOINT_NAMES, ArmScenario, arm_points
from ..arm.stepper import ArmStepper
from ..errors import HydroarmError
from ..files import csv_text
from ..model.lever import LeverInput
from .blocks import BLOCK_MASS, StackingTask

# keys of the lever box: (joint, direction); a key held moves its lever at LEVER_RATE
KEYS = {
    "q": ("shoulder_elevation", 1.0),
    "a": ("shoulder_elevation", -1.0),
    "w": ("humeral_rotation", 1.0),
    "s": ("humeral_rotation", -1.0),
    "e": ("elbow_reach", 1.0),
    "d": ("elbow_reach", -1.0),
    "r": ("wrist_rotation", 1.0),
    "f": ("wrist_rotation", -1.0),
}
GRASP_KEY = "g"  # grasp or release a block (the space bar too)
LEVER_RATE = math.radians(45.0)  # [rad/s] of lever (articulation angle) per held key: the
# elbow's full 110° in 2.4 s, about its own saturation time (2.6 rad/s over 1.9 rad, docs/arm.md)
# lever ranges [rad] (articulation angles): the paper's arm's ranges (humeral rotation ±50°,
# the shoulder rotation test's 100°; elbow flexion 0-110°; wrist rotation 180°), within each
# servo's crank reach; shoulder elevation from hanging to 80° (the paper's Appendix I goes to
# 30° above horizontal, but the model's elbow cannot hold the forearm there: with the
# shoulder's lever at 90° and the elbow's thrown to 110° the forearm swung past the elbow
# crank's dead centre within 1.1 s, at 100° also with the elbow straight, at 1 ms, 0.5 ms and
# 0.1 ms alike; at 80° every corner of the four levers, thrown at once, held for 10 s)
LEVER_RANGES = {
    "shoulder_elevation": (0.0, math.radians(80.0)),
    "humeral_rotation": (math.radians(-50.0), math.radians(50.0)),
    "elbow_reach": (0.0, math.radians(110.0)),
    "wrist_rotation": (math.radians(-90.0), math.radians(90.0)),
}
SPEEDS = (0.25, 0.5, 1.0)  # simulated seconds per wall second
MAX_TICK = 0.1  # [s] of wall time taken from one tick at most (a stalled browser or server
# does not make the arm jump: the run slows down instead)


CONTACT_STEP = 0.002  # [s] the table's contact is checked after every piece of this much
# simulated time (4 steps of 0.5 ms): the hand stops within one piece's travel above the top
MAX_SUBSTEPS = 64  # the file's step divided in at most this many
PROBE_FRACTIONS = (0.0, 0.5, 1.0)  # where in its lever range each joint starts in a probe
_STEPS: dict[int, tuple[ArmScenario, dict, float]] = {}  # live_step's answers, by scenario


def live_step(sc: ArmScenario, ranges: dict[str, tuple[float, float]]) -> float:
    """The live arm's step [s]: the scenario's step h divided in n substeps, h/n with the
    least n that the arm's own stability check
    (`check_step`) accepts in every probe: all joints
    started at one end or the middle of their lever ``ranges`` with their levers at either
    end (the valves fully open; the check also covers the pressures and speeds a motion
    passes, and the pose's inertia bounds). Remembered per scenario."""
    known = _STEPS.get(id(sc))
    if known is not None and known[0] is sc and known[1] == ranges:
        return known[2]
    n = 1
    for frac in PROBE_FRACTIONS:
        for end in (0, 1):
            start = {n: lo + frac * (hi - lo) for n, (lo, hi) in ranges.items()}
            inputs = {
                n: LeverInput(
                    np.array([0.0]),
                    np.array([sc.joint(n).lever_for_angle(ranges[n][end])]),
                    description=f"live lever at {math.degrees(ranges[n][end]):.4g} deg",
                )
                for n in ranges
            }
            probe = sc.replace(initial_angles={**sc.initial_angles, **start}, inputs=inputs)
            while True:
                try:
                    probe.replace(step=sc.step / n).check_step()
                    break
                except HydroarmError as exc:
                    if exc.field != "solver.step" or n >= MAX_SUBSTEPS:
                        raise
                    n += 1
    h = sc.step / n
    _STEPS[id(sc)] = (sc, dict(ranges), h)
    return h


def lever_range(sc: ArmScenario, name: str) -> tuple[float, float]:
    """The lever's range [rad]: `LEVER_RANGES` within the servo's crank reach
    (|θ_servo| < n·90°, kept 2° inside it) around the joint's angle offset."""
    j = sc.joint(name)
    lo, hi = LEVER_RANGES[name]
    reach = j.servo.max_angle - math.radians(2.0)
    return max(lo, j.angle_offset - reach), min(hi, j.angle_offset + reach)


class LiveArm:
    """The live arm: levers, keys held, the stepper, the clock, the task and the recording.

    ``stepper_factory(scenario)`` builds the stepper at the scenario's start, the scenario's
    step set to `live_step`'s (default: `hydroarm.arm.stepper.ArmStepper`); it
    must have ``levers`` (assigned a dict of
    valve-lever positions [m] by joint), ``hand_mass`` (assigned the payload [kg]),
    ``advance(duration)``, ``t``, ``servo_angles()``, ``stop_joints(theta, joints)``,
    ``get_state()``, ``set_state(state)`` and
    ``outputs()`` (per joint ``angle`` [rad] and ``p`` [Pa]; ``supply_pressure``,
    ``valve_flow``, ``pump_flow``)."""

    def __init__(self, scenario: ArmScenario, stepper_factory: Callable | None = None):
        self.scenario = scenario
        self.names = [j.name for j in scenario.joints]
        if set(self.names) != set(JOINT_NAMES):
            raise HydroarmError(
                "joints", f"the live arm needs all four joints ({', '.join(JOINT_NAMES)})"
            )
        self.ranges = {n: lever_range(scenario, n) for n in self.names}
        for n in self.names:
            lo, hi = self.ranges[n]
            a = scenario.initial_angles[n]
            if not lo <= a <= hi:
                raise HydroarmError(
                    f"initial.{n}",
                    f"{math.degrees(a):.4g} deg is outside the live lever's range "
                    f"{math.degrees(lo):.4g} to {math.degrees(hi):.4g} deg",
                )
        self._factory = stepper_factory or ArmStepper
        # the hand's payload: the file's when empty, a block's mass more while one is held;
        # the step is stable for both
        self.empty_hand_mass = float(scenario.geometry.hand_mass)
        loaded = scenario.replace(
            geometry=scenario.geometry.replace(hand_mass=self.empty_hand_mass + BLOCK_MASS)
        )
        self.step = min(live_step(scenario, self.ranges), live_step(loaded, self.ranges))
        self._stepped = scenario.replace(step=self.step)
        self.stopped = ""  # why the run stopped ('' while it runs)
        self._G = scenario.geometry.params()
        self._offsets = {j.name: float(j.angle_offset) for j in scenario.joints}
        self.speed = 1.0
        self.task = StackingTask()
        self.reset()

    # controls --------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the start: the arm at its initial angles with the levers holding them,
        keys released, the clock at 0, the blocks back, the recording cleared."""
        self.stepper = self._factory(self._stepped)
        self.stopped = ""
        self.levers = {n: float(self.scenario.initial_angles[n]) for n in self.names}
        self.held: set[str] = set()
        self.paused = False
        self.task.reset()
        self._payload()
        self.recording: list[tuple[float, tuple[float, ...]]] = [
            (0.0, tuple(self.levers[n] for n in JOINT_NAMES))
        ]
        self._push_levers()
        self._outputs = self.stepper.outputs()

    def set_lever(self, name: str, angle: float) -> None:
        """Set a lever to the articulation angle ``angle`` [rad] (a slider), clamped to its
        range."""
        if not isinstance(name, str) or name not in self.levers:
            raise HydroarmError("lever", f"unknown joint {name!r}")
        if isinstance(angle, bool) or not isinstance(angle, (int, float)):
            raise HydroarmError(f"lever.{name}", f"must be a number, got {angle!r}")
        if not math.isfinite(angle):
            raise HydroarmError(f"lever.{name}", f"must be finite, got {angle!r}")
        lo, hi = self.ranges[name]
        self.levers[name] = min(max(float(angle), lo), hi)
        self._push_levers()
        self._moved()

    def key(self, key: str, down: bool) -> str:
        """A key pressed (``down``) or released: a lever key starts or stops its lever; the
        grasp key (pressed) grasps or releases a block. Returns what the grasp did, or ''."""
        if not isinstance(key, str):
            raise HydroarmError("key", f"must be a key's name, got {key!r}")
        k = key.lower()
        if k in KEYS:
            if down:
                self.held.add(k)
            else:
                self.held.discard(k)
            return ""
        if down and k in (GRASP_KEY, " ", "space"):
            return self.grasp()
        return ""

    def release_keys(self) -> None:
        """Release every held key (the page lost the keyboard's focus)."""
        self.held.clear()

    def grasp(self) -> str:
        """Grasp the block in reach or release the held one (`StackingTask.toggle`);
        the hand's payload follows (`_payload`)."""
        what = self.task.toggle(self.hand(), self.t)
        self._payload()
        return what

    def _payload(self) -> None:
        """The hand's payload [kg] on the stepper: the file's hand mass, plus
        `BLOCK_MASS` while a block is held; the mechanism's tree carries it from the next
        step (its gravity torques and inertias)."""
        held = self.task.held is not None
        self.stepper.hand_mass = self.empty_hand_mass + (BLOCK_MASS if held else 0.0)

    def toggle_pause(self) -> None:
        """Pause a running arm or resume a paused one; a stopped run stays stopped (only
        `reset` goes on)."""
        if not self.stopped:
            self.paused = not self.paused

    @property
    def state(self) -> str:
        """``running``, ``paused`` or ``stopped`` (the run left the physical bounds): what the
        page's button, clock and message all show."""
        return "stopped" if self.stopped else ("paused" if self.paused else "running")

    def set_speed(self, speed: float) -> None:
        """Simulated seconds per wall second, between 0.25 and 1."""
        if not (isinstance(speed, (int, float)) and 0.25 <= speed <= 1.0):
            raise HydroarmError("speed", f"must be between 0.25 and 1, got {speed!r}")
        self.speed = float(speed)

    # the clock -------------------------------------------------------------------------
    def tick(self, wall_dt: float) -> float:
        """Advance by ``wall_dt`` [s] of wall time (at most `MAX_TICK`) × the speed:
        held keys move their levers, the stepper advances, the held block follows the hand.
        Returns the simulated time advanced [s] (0 while paused or stopped). A run that leaves
        the physical bounds stops: paused, `stopped` says why (the error is raised)."""
        if self.paused or self.stopped or not wall_dt > 0:
            return 0.0
        dt = min(float(wall_dt), MAX_TICK) * self.speed
        moved = False
        for k in self.held:
            name, sign = KEYS[k]
            lo, hi = self.ranges[name]
            v = min(max(self.levers[name] + sign * LEVER_RATE * dt, lo), hi)
            moved |= v != self.levers[name]
            self.levers[name] = v
        if moved:
            self._push_levers()
        try:
            self._advance(dt)
        except HydroarmError as exc:
            self.paused = True
            self.stopped = str(exc)
            self.task.events.append(f"stopped: {exc}")
            raise
        self._outputs = self.stepper.outputs()
        if moved:
            self._moved()
        self.task.follow(self.hand())
        return dt

    def _advance(self, dt: float) -> None:
        """Advance the stepper by ``dt`` [s]: in one call, unless the hand ends it below the
        table top's height having started at or above it; then again from the same state in
        pieces of at most `CONTACT_STEP`, the table's contact (`_contact`) after
        each. (The pieces give the one call's steps where no contact acts: the levers are
        held over the tick. Pieces in every tick cost 0.91 ms a frame against 0.50 ms:
        docs/explore.md.)"""
        before = self.stepper.servo_angles()
        start = self._hand_at(before)
        if start[2] < self.task.table_top:
            self.stepper.advance(dt)
            return
        saved = self.stepper.get_state()
        self.stepper.advance(dt)
        if self._hand_at(self.stepper.servo_angles())[2] >= self.task.table_top:
            return
        self.stepper.set_state(saved)
        n = max(1, math.ceil(dt / CONTACT_STEP - 1e-9))
        for _ in range(n):
            before = self.stepper.servo_angles()
            self.stepper.advance(dt / n)
            self._contact(before)

    def _contact(self, before: np.ndarray) -> None:
        """The table as a floor (the one contact of the live arm): when the piece just taken
        moved the hand point from at or above the table top to below it, within the table's
        extent (`StackingTask.through_table`), the joints whose own motion in the piece
        moved the hand point down are stopped where the piece began (angle back, velocity
        zero, pressures kept: an inelastic stop, `ArmStepper.stop_joints`); the others
        keep their motion, unless the hand would still be through the top, when all stop.
        A servo pushing on the table then stalls against it, its pressure building as
        against any stop; its lever set back lifts the hand off."""
        after = self.stepper.servo_angles()
        start = self._hand_at(before)
        if not self.task.through_table(start, self._hand_at(after)):
            return
        stop = []
        for j in range(len(after)):
            moved = before.copy()
            moved[j] = after[j]
            if self._hand_at(moved)[2] < start[2]:
                stop.append(j)
        kept = after.copy()
        kept[stop] = before[stop]
        if self.task.through_table(start, self._hand_at(kept)):
            stop = list(range(len(after)))
        self.stepper.stop_joints(before, stop)

    def _hand_at(self, theta: np.ndarray) -> np.ndarray:
        """The hand point [m] at the stepper's servo angles ``theta`` [rad]."""
        q = np.zeros(4)
        for j, n in enumerate(self.names):
            q[JOINT_NAMES.index(n)] = theta[j] + self._offsets[n]
        return arm_points(q, self._G)[2]

    @property
    def t(self) -> float:
        """Simulated time [s]."""
        return float(self.stepper.t)

    def _push_levers(self) -> None:
        self.stepper.levers = {
            n: self.scenario.joint(n).lever_for_angle(self.levers[n]) for n in self.names
        }

    def _moved(self) -> None:
        """A lever moved at the current time: the task's clock starts, the recording gets
        a row (replacing one at the same time)."""
        t = self.t
        self.task.start(t)
        row = (t, tuple(self.levers[n] for n in JOINT_NAMES))
        if self.recording and self.recording[-1][0] >= t:
            self.recording[-1] = row
        else:
            self.recording.append(row)

    # what the page shows ---------------------------------------------------------------
    def angles(self) -> dict[str, float]:
        """Articulation angles [rad] of the four joints now."""
        out = self._outputs
        return {n: float(out[n]["angle"]) for n in self.names}

    def points(self) -> np.ndarray:
        """Shoulder, elbow, wrist, hand [m] (4 × 3; x forward, y left, z up)."""
        a = self.angles()
        q = np.array([a[n] for n in JOINT_NAMES])
        p = arm_points(q, self._G)
        return np.vstack([np.zeros(3), p[0], p[1], p[2]])

    def hand(self) -> np.ndarray:
        """The hand point [m]."""
        return self.points()[3]

    def gauges(self) -> dict:
        """Pressures and flows now: ``pressures`` {joint: load pressure [Pa]},
        ``supply_pressure`` [Pa], ``valve_flow`` (the flow the valves draw) and ``pump_flow``
        (the pump delivers) [m³/s], the pump's capacity [m³/s] (inf: unlimited) and the
        relief pressure [Pa]."""
        o = self._outputs
        return {
            "pressures": {n: float(o[n]["p"]) for n in self.names},
            "supply_pressure": float(o["supply_pressure"]),
            "valve_flow": float(o["valve_flow"]),
            "pump_flow": float(o["pump_flow"]),
            "pump_capacity": float(self.scenario.power_pack.pump_flow),
            "relief_pressure": float(self.scenario.power_pack.supply_pressure),
        }

    def score(self) -> dict:
        """The block-stacking score now (`StackingTask.score`)."""
        return self.task.score(self.t)

    def recording_csv(self) -> str:
        """The attempt's levers as ``examples/block_stacking.csv``'s columns (``t_s`` and
        ``<joint>_deg``), with a final row at the current time."""
        rows = list(self.recording)
        now = (self.t, tuple(self.levers[n] for n in JOINT_NAMES))
        if now[0] > rows[-1][0]:
            rows.append(now)
        header = ["t_s", *(f"{n}_deg" for n in JOINT_NAMES)]
        body = [
            {
                "t_s": round(t, 6),
                **{
                    f"{n}_deg": round(math.degrees(v), 4)
                    for n, v in zip(JOINT_NAMES, a, strict=True)
                },
            }
            for t, a in rows
        ]
        return (
            "# A recorded attempt of hydroarm explore: lever positions as joint angles [deg]\n"
            "# against time [s]; replay it with the arm command ([inputs] csv = this file).\n"
            + csv_text(header, body)
        )
