"""The evaluation card of any mechanism file (issue 30; docs/evaluate.md "Any mechanism
file", docs/mechanism.md): ``hydroarm arm --config FILE --card`` writes ``card.md``,
``card.csv`` and ``card.png`` beside the run's outputs.

One protocol, defined from the file's own data, for every mechanism file. A joint is
**driven** when an actuator (a component with a hydraulic port that drives a mechanical
node: a cylinder, a rotary actuator, a motor) moves it, directly or through linkages, and a
valve feeds that actuator: a component with a ``command`` input and a ``max_stroke``
(``valve_4_3``) on the actuator's chamber nodes, or the actuator is the paper's lumped
``servo_jack`` (its own valve, driven by its ``lever``: the UCL arm's paper joints). Per
driven joint:

* **the runs**: the joint's valve is cut from whatever drove it (its controller is taken
  out) and driven by the card's source, stepped (over one solver step) at
  `STEP_TIME` to its full opening (``max_stroke``); every other input of the file is
  held at its value at t = 0, so the other joints stay on their own loops at the file's
  start pose. From the file's own start (its ``[initial]`` pose, at rest), three stages,
  each starting where the last ended: the valve fully open towards the joint's lower end
  until the joint rests at its stop; fully open the other way through the whole travel to
  the upper stop ("increasing"); and back ("decreasing"): "driven to full opening one way
  and back". A stage that has not come to rest (`SETTLED`) is run once more, longer
  (its duration from the pace it reached; at most `MAX_DURATION`). Each stage is a row
  of the batch engine (`hydroarm.model.circuit.simulate_many`, the same kernel and
  stepper as ``hydroarm simulate``), at the file's ``[solver]`` method and step;
* **a servo jack's runs** (the paper's protocol for its joints: "the valve input levers
  moved as fast as possible over the full range of motion"): the jack's mechanical
  feedback (e = lever − rod) holds the joint where its lever puts it, so its lever, cut from
  its source, is stepped (over one solver step, at `STEP_TIME`) from one end of the
  travel to the other: to the rod's position with the joint at the end of its travel (the
  kernel's projection sets the crank's x(q)). The travel is the joint's limits less the
  margins, narrowed to where the jack's moment arm |dx/dq| is at least
  `SERVO_ARM_SHARE` (cos 30°) of its largest (a crank within ±30° of its centre: the
  paper's shoulder test, 0° to 120°; the UCL file's limits are its cranks' dead centres,
  where the gearbox's loss locks a rotation joint). The same three stages: from the start to the
  lower end, up ("increasing") and back ("decreasing"), each ending where the servo brings
  the joint to rest. The valve is fully open (|e| ≥ e_o) for all but the last e_o of the
  rod's travel. Besides the rows below, on the jack's rod (the paper's Table III and its
  transients, [`hydroarm.metrics.step.step_metrics`][hydroarm.step_metrics]): the **jack speed**
  [mm/s] over the middle 80 % of the rod's motion, the **time constants** at the start and the end
  of travel (the time to move 63 % of the full valve opening e_o) and the **peak load
  pressure** [bar]. Its **blocked force** is solved for (at the end of a stage the servo
  has closed its valve): at each stage's end state (at rest at the end of the travel, the
  supply where the relief passes the pump's flow) the lever 2·e_o past the rod, the rod
  still, the load pressure at which the kernel's own rate of it vanishes (a root in p: the
  valve's flow meets the jack's leakage); the jack's force A·p there;
* **held joints' largest excursion** [deg] (and [m] for prismatic ones): the largest
  departure of any other free joint from its start position in the stage, and which: how
  well the others were held, the coupling made visible (the UCL arm's elbow gives way to its
  stop when the shoulder is raised: its reach coupling loads it with the upper arm);
* **speed** [rad/s or m/s]: the joint's travel over the middle 80 % of the stage (10 % to
  90 % of the way from where it started to where it came to rest) over the time it took,
  the paper's saturation-velocity method (`hydroarm.metrics.step.crossing_time`);
* **time constant (63 %)** [ms]: from the valve's step until the joint's velocity first
  reaches 63 % of that speed;
* **peak torque** (force) on the joint and **peak chamber pressures** of its actuator,
  **supply sag** (the valve's P node's pressure at the step less its lowest in the stage)
  and **energy** (delivered by the circuit's sources, the components whose energy over the
  stage is negative, from the step until the joint reached 90 % of its travel);
* **blocked force**: the actuator's force at the end of each stage, at rest with the valve
  still fully open (at its stop, or stalled): the joint's torque over the moment arm
  dx/dq (the product of the linkages' ratios), averaged over the last `SETTLED`;
* **stall payload** [kg]: the largest mass at the payload point that the joint holds at
  every pose of its travel (`STALL_POSES` poses from the stages' records, the other
  joints at the start pose): at each pose the blocked forces each way times the moment arm
  there bound the torque the actuator holds; the gravity torque of the mechanism and of a
  payload of mass m (the tree kernel's bias forces, `hydroarm.core.tree.bias_forces`,
  the payload's weight an external force, `hydroarm.core.tree.point_force`) is
  linear in m, so the stall payload is where it meets the bound, the smallest over the
  poses (at the **stall worst pose**). The payload point: the file's first
  ``[[mechanism.payload]]`` on a link the joint moves (the stall payload is then that
  payload's whole mass at stall), else the centre of mass of the last link the joint
  moves. A joint whose payload has no gravity moment (a vertical axis) has no stall
  payload (NaN); a negative one cannot hold its own links at its worst pose. Dry friction
  at the joint, which helps holding, is left out.

**The file's own task** (the file run as it stands, ``hydroarm arm``'s run): per
controller (a ``pid`` whose measurement is a ``position_sensor`` on a joint) the tracking
error of its measurement against its reference, RMS and largest; the cycle time (the
run's duration); the energy the sources delivered.

**Budget**: the card runs at most ``max_runs`` simulations (`MAX_RUNS`; three stages
per joint, each perhaps twice); a file whose protocol needs more is refused before any
work, as is a file with no driven joint (one line naming why).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..arm.mechanism_run import joint_pressures
from ..core import tree as T
from ..core.circuit import declare
from ..core.circuit.components import TYPES
from ..core.circuit.components.signal_source import DECLARATION as _SOURCE_DECL
from ..errors import HydroarmError
from ..files import csv_text
from ..metrics.step import crossing_time, step_metrics
from ..model.circuit import (
    Circuit,
    CircuitResult,
    ComponentSpec,
    build,
    equilibrium_state,
    simulate_many,
)
from ..model.circuit_steady import frozen_parameters, rhs
from ..model.circuit_steady import project as project_state
from ..plotting.joint import save_figure
from ..plotting.mechanism import fig_card

STEP_TIME = 0.02  # [s]: the valve's step, after the start at rest
END_MARGIN = 0.05  # share of a joint's range left at each end of its travel
FREE_SPAN = 1.0  # [rad or m]: the travel each way of a joint without limits
STALL_POSES = 5  # poses over the travel at which the holding torques are solved
MIDDLE = 0.8  # the share of the travel the speed is measured over (the paper's)
FIRST_DURATION = 2.0  # [s]: the first try of a speed run, after the step
SETTLED = 0.5  # [s]: a run ends at rest (at its stop, or stalled) when the joint did not
SETTLED_SHARE = 0.05  # move in its last SETTLED by more than this share of its travel (a
# stalled joint rings on its oil column: the excavator's stick ±2° of 110°)
MAX_DURATION = 30.0  # [s]: the longest speed run
MAX_RUNS = 60  # simulations the card may run (10 driven joints)
SERVO_ARM_SHARE = math.cos(math.radians(30.0))  # a servo jack's travel: its moment arm at
# least this share of its largest (a crank within ±30° of its centre: the paper's shoulder
# test, 120° of arm about the servo's datum through the 2:1 gearbox; nearer its dead
# centres the UCL arm's gearbox loss locks a rotation joint, docs/evaluate.md)
ARM_GRID = 721  # poses over a servo joint's limits at which its moment arm is taken
RECORDS_PER_SECOND = 500  # the speed runs' recording rate (at least)
DRIVE = "card_drive"  # the added signal source and its signal
RAMP = float(_SOURCE_DECL.parameters[0].choices.index("ramp"))  # the waveform's code


@dataclass(frozen=True)
class DrivenJoint:
    """A joint the card drives: its ``name`` and kernel ``index``, ``prismatic``, the
    ``actuator`` moving it, the ``valve`` feeding it (its ``command`` port and the command
    ``full`` at full opening), the ``supply`` node (the valve's P) and its travel
    ``(start, end)`` [rad or m]."""

    name: str
    index: int
    prismatic: bool
    actuator: str
    valve: str
    command: str
    full: float
    supply: str | None
    travel: tuple[float, float]
    rod: str | None = None  # a servo_jack's rod node (its lever is stepped end to end)

    @property
    def servo(self) -> bool:
        """A mechanically fed-back servo_jack: its lever is stepped from one end of the
        travel to the other (the paper's protocol), not its valve to full opening."""
        return self.rod is not None


@dataclass
class MechanismCard:
    """The card: ``rows`` (joint, direction, quantity, value, unit, definition), the task's
    ``task_rows`` (same keys), per joint the speed runs' traces ``traces`` (joint → list of
    (t, position) per direction), the run count ``runs`` and the actuated joints the
    protocol leaves out, each with why (``skipped``)."""

    name: str
    rows: list[dict] = field(default_factory=list)
    traces: dict[str, list[tuple[np.ndarray, np.ndarray]]] = field(default_factory=dict)
    runs: int = 0
    skipped: list[str] = field(default_factory=list)

    def value(self, joint: str, quantity: str, direction: str = "") -> float:
        """One row's value (NaN if none)."""
        for r in self.rows:
            if r["joint"] == joint and r["quantity"] == quantity and r["direction"] == direction:
                return float(r["value"])
        return math.nan

    def csv(self) -> str:
        return csv_text(
            ["joint", "direction", "quantity", "value", "unit", "definition"], self.rows
        )

    def markdown(self) -> str:
        lines = [f"# Evaluation card: {self.name}", ""]
        lines += [
            'Protocol: docs/evaluate.md "Any mechanism file" (each driven joint\'s valve '
            "stepped to full opening each way, a servo jack's lever stepped from one end of "
            "the travel to the other, the other joints held at the start pose).",
            "",
            "| joint | direction | quantity | value | unit |",
            "|---|---|---|---|---|",
        ]
        for r in self.rows:
            v = r["value"]
            shown = "—" if v != v else f"{v:.4g}"
            lines.append(
                f"| {r['joint']} | {r['direction']} | {r['quantity']} | {shown} | {r['unit']} |"
            )
        lines += ["", "## Definitions", ""]
        seen: dict[str, str] = {}
        for r in self.rows:
            seen.setdefault(r["quantity"], r["definition"])
        lines += [f"- **{k}**: {v}" for k, v in seen.items()]
        if self.skipped:
            lines += ["", "Not on this card: " + "; ".join(self.skipped) + "."]
        lines.append(f"\n{self.runs} simulations.")
        return "\n".join(lines) + "\n"

    def lines(self) -> list[str]:
        """The terminal lines of ``hydroarm arm --card``."""
        out = []
        joints = dict.fromkeys(r["joint"] for r in self.rows if r["joint"] != "task")
        for j in joints:
            up = self.value(j, "speed", "increasing")
            down = self.value(j, "speed", "decreasing")
            unit = next(
                r["unit"] for r in self.rows if r["joint"] == j and r["quantity"] == "speed"
            )
            m = self.value(j, "stall payload")
            jack = self.value(j, "jack speed", "increasing")
            if jack == jack:  # a servo jack: the paper's measures on its rod
                unit += (
                    f" (jack {jack:.3g} / {self.value(j, 'jack speed', 'decreasing'):.3g} "
                    "mm/s, time constant at the start "
                    f"{self.value(j, 'time constant, start (63 % of e_o)', 'increasing'):.3g}"
                    " / "
                    f"{self.value(j, 'time constant, start (63 % of e_o)', 'decreasing'):.3g}"
                    " ms)"
                )
            out.append(
                f"{j:<20} speed {up:.3g} / {down:.3g} {unit}, time constant "
                f"{self.value(j, 'time constant (63 %)', 'increasing'):.3g} / "
                f"{self.value(j, 'time constant (63 %)', 'decreasing'):.3g} ms, stall payload "
                f"{m:.4g} kg"
            )
        for why in self.skipped:
            out.append(f"not on the card: {why}")
        for r in self.rows:
            if r["joint"] == "task":
                out.append(
                    f"task {r['quantity']:<36} {r['value']:.4g} {r['unit']} {r['direction']}"
                )
        return out

    def write(self, folder) -> list[str]:
        """card.csv, card.md and card.png into ``folder``; their names."""
        folder = Path(folder)
        (folder / "card.csv").write_text(self.csv())
        (folder / "card.md").write_text(self.markdown())
        save_figure(fig_card(self.name, self.rows, self.traces), folder / "card.png")
        return ["card.csv", "card.md", "card.png"]


# ------------------------------------------------------------------ the file's joints ---
def _master_joint(compiled, node: str) -> int | None:
    """The mechanism joint a mechanical node is, or is driven from through linkages."""
    mech = compiled.mechanism
    master = {int(sl): int(ma) for sl, ma, _ in compiled.slaves}
    if node not in compiled.mechanical:
        return None
    i = compiled.mechanical[node]
    while i in master:
        i = master[i]
    return i if i < mech.n else None


def driven_joints(compiled) -> tuple[list[DrivenJoint], list[str]]:
    """The joints the card drives (module doc), in the kernel's order, and the actuated
    joints it leaves out, each with why; refused (one line) when it drives none."""
    c = compiled.circuit
    mech = compiled.mechanism
    if mech is None:
        raise HydroarmError("mechanism", "the file has no [mechanism] section")
    decls = dict(zip((comp.name for comp in c.components), compiled.decls, strict=True))
    found: dict[int, DrivenJoint] = {}
    skipped: list[str] = []
    for comp in c.components:
        decl = decls[comp.name]
        drive = [p for p in decl.ports if p.drives and p.domain in declare.MECHANICAL]
        hyd = [p for p in decl.ports if p.domain == declare.HYDRAULIC]
        if not drive or not hyd:
            continue
        j = _master_joint(compiled, comp.ports[drive[0].name])
        if j is None or j in found:
            continue
        name = mech.joint_names[j]
        valve: str | None = None
        command = "command"
        supply: str | None = None
        full = 0.0
        rod: str | None = None
        if comp.type == "servo_jack":  # the jack is its own valve, the lever its command
            valve, command = comp.name, "lever"
            full = float(comp.values.get("valve_saturation", math.nan))
            supply = comp.ports.get("P")
            if comp.values.get("feedback", "mechanical") == "mechanical":
                rod = comp.ports["rod"]
        chambers = {comp.ports[p.name] for p in hyd}
        for other in c.components if valve is None else ():
            od = decls[other.name]
            names = {p.name for p in od.parameters}
            sig = [p.name for p in od.ports if p.domain == declare.SIGNAL_IN]
            work = {other.ports.get(p.name) for p in od.ports if p.domain == declare.HYDRAULIC}
            if "max_stroke" in names and "command" in sig and chambers <= work:
                valve = other.name
                full = float(other.values["max_stroke"])
                supply = other.ports.get("P")
                break
        if valve is None:
            skipped.append(
                f"{name} (its {comp.type} {comp.name!r} has no valve with a full opening)"
            )
            continue
        lo, hi = float(mech.lower[j]), float(mech.upper[j])
        q0 = float(c.initial_joints.get(name, 0.0))
        if not (math.isfinite(lo) and math.isfinite(hi)):
            lo, hi = q0 - FREE_SPAN, q0 + FREE_SPAN
        m = END_MARGIN * (hi - lo)
        found[j] = DrivenJoint(
            name,
            j,
            mech.joint_types[j] == "prismatic",
            comp.name,
            valve,
            command,
            full,
            supply,
            (lo + m, hi - m),
            rod,
        )
    if not found:
        why = f": {'; '.join(skipped)}" if skipped else ""
        raise HydroarmError(
            "card",
            "no joint of the mechanism is driven by a valve-fed actuator, so the card's "
            f"protocol (each joint's valve stepped to full opening) has nothing to drive{why}",
        )
    return [found[j] for j in sorted(found)], skipped


def runs_needed(joints: list[DrivenJoint]) -> int:
    """The most simulations the protocol takes: per joint three stages (to the lower end,
    up, down), each perhaps run again once."""
    return len(joints) * 6


def check_card(circuit: Circuit, max_runs: int = MAX_RUNS) -> tuple[list[DrivenJoint], list[str]]:
    """The driven joints and those left out (`driven_joints`), the file refused (one
    line) where the protocol cannot apply or needs more than ``max_runs`` runs; before any
    work."""
    joints, skipped = driven_joints(build(circuit))
    need = runs_needed(joints)
    if need > max_runs:
        raise HydroarmError(
            "card",
            f"the protocol needs up to {need} runs for {len(joints)} driven joints, more "
            f"than the budget of {max_runs}",
        )
    return joints, skipped


# ------------------------------------------------------------------ the protocol ---
def _drive_circuit(circuit: Circuit, dj: DrivenJoint) -> Circuit:
    """The circuit with the joint's valve command cut from its driver and fed by the card's
    ramp source (a step over one solver step). The
    component that drove the command (a controller) is taken out when the valve was its
    only reader (a controller left running with nothing to act on would wind up)."""
    valve = next(c for c in circuit.components if c.name == dj.valve)
    cut = valve.ports.get(dj.command)
    readers = [
        c
        for c in circuit.components
        if c.name != dj.valve
        and any(
            p.domain == declare.SIGNAL_IN and c.ports.get(p.name) == cut
            for p in TYPES[c.type].DECLARATION.ports
        )
    ]
    comps = []
    for comp in circuit.components:
        decl = TYPES[comp.type].DECLARATION
        drives_cut = any(
            p.domain == declare.SIGNAL_OUT and comp.ports.get(p.name) == cut for p in decl.ports
        )
        if cut is not None and drives_cut and not readers:
            continue  # the valve's controller (its only reader is the valve): taken out
        if comp.name == dj.valve:
            ports = dict(comp.ports)
            ports[dj.command] = DRIVE
            comp = ComponentSpec(comp.type, comp.name, ports, comp.values, comp.arrays)
        comps.append(comp)
    comps.append(
        ComponentSpec(
            "signal_source",
            DRIVE,
            {"out": DRIVE},
            {
                "waveform": "ramp",
                "offset": 0.0,
                "rate": 0.0,
                "start_time": STEP_TIME,
                "end_time": STEP_TIME + circuit.step,
            },
        )
    )
    return circuit.replace(components=tuple(comps), equilibrium=False)


def _pose(circuit: Circuit, compiled, dj: DrivenJoint, q: float) -> dict[str, float]:
    """The pinned pose: the joint at q, the other free joints at their [initial] angles."""
    mech = compiled.mechanism
    pose = {}
    for i, name in enumerate(mech.joint_names):
        if mech.master[i] != i:
            continue
        pose[name] = q if i == dj.index else float(circuit.initial_joints.get(name, 0.0))
    return pose


def _one_record(compiled, s, P) -> dict[str, np.ndarray]:
    r = CircuitResult(compiled, np.array([0.0, 1e-9]), np.vstack([s, s]), -1, P)
    return r.columns()


def _torque_key(dj: DrivenJoint) -> str:
    return f"{dj.name}_force_n" if dj.prismatic else f"{dj.name}_torque_n_m"


def _position_key(dj: DrivenJoint) -> str:
    return f"{dj.name}_position_m" if dj.prismatic else f"{dj.name}_angle_deg"


def _speed(t, x, a, b):
    """(speed over the middle of a → b [units/s], t at 10 %, t at 90 %)."""
    sign = 1.0 if b > a else -1.0
    lo = a + (1 - MIDDLE) / 2 * (b - a)
    hi = a + (1 + MIDDLE) / 2 * (b - a)
    t1 = crossing_time(t, x, lo, sign)
    t2 = crossing_time(t, x, hi, sign, after=t1 if t1 == t1 else -math.inf)
    if t1 != t1 or t2 != t2 or t2 <= t1:
        return 0.0, t1, t2
    return MIDDLE * abs(b - a) / (t2 - t1), t1, t2


def _chain(compiled, dj: DrivenJoint) -> list[str]:
    """The linkages between the joint's actuator and the joint (their names)."""
    c = compiled.circuit
    comp = next(x for x in c.components if x.name == dj.actuator)
    decl = compiled.decls[c.components.index(comp)]
    port = next(p for p in decl.ports if p.drives and p.domain in declare.MECHANICAL)
    i = compiled.mechanical[comp.ports[port.name]]
    master = {int(sl): (int(ma), int(ci)) for sl, ma, ci in compiled.slaves}
    out = []
    while i in master:
        i, ci = master[i]
        out.append(c.components[ci].name)
    return out


def _opening_sign(compiled, dj: DrivenJoint, cols: dict) -> float:
    """+1 if the valve's positive opening moves the joint's position up, −1 if down: the
    valve feeds its A port for a positive opening, the actuator moves positive when its
    chamber a fills (a servo_jack's rod extends for a positive lever), and each linkage's
    ratio carries the sign to the joint (at the state of ``cols``)."""
    c = compiled.circuit
    act = next(x for x in c.components if x.name == dj.actuator)
    sign = 1.0
    if dj.valve != dj.actuator:
        valve = next(x for x in c.components if x.name == dj.valve)
        if valve.ports.get("A") is not None and valve.ports.get("A") == act.ports.get("b"):
            sign = -1.0
    for name in _chain(compiled, dj):
        if float(cols[f"{name}_ratio"][0]) < 0.0:
            sign = -sign
    return sign


def _arm(cols: dict, chain: list[str]) -> np.ndarray:
    """dx_actuator/dq along a run: the product of the chain's linkage ratios (1: direct)."""
    g = np.ones_like(cols["t_s"])
    for name in chain:
        g = g * cols[f"{name}_ratio"]
    return g


def _stall_rows(circuit, compiled, dj: DrivenJoint, runs: list, blocked=None) -> list[dict]:
    """The stall payload (module doc) from the two speed runs' blocked ends: the actuator's
    force there (the joint's torque over the moment arm, dx_actuator/dq) times the moment
    arm at each pose of the travel bounds what the joint holds."""
    link, point, label, mass0 = _payload_point(circuit, compiled, dj)
    chain = _chain(compiled, dj)
    forces = []  # the blocked actuator's force, each way (at its end stop)
    poses, arms = [], []
    for res, _ in runs:
        cols = res.columns()
        x = _si(cols[_position_key(dj)], dj)
        g = _arm(cols, chain)
        tail = res.t >= res.t[-1] - SETTLED
        if blocked is not None:  # a servo jack's, solved for (_servo_blocked)
            pass
        elif _settled(res, dj):  # at rest at its stop, the valve still fully open
            forces.append(float(np.mean(cols[_torque_key(dj)][tail] / g[tail])))
        else:
            forces.append(math.nan)
        poses.append(x)
        arms.append(g)
    if blocked is not None:
        forces = list(blocked)
    q = np.concatenate(poses)
    arm = np.concatenate(arms)
    order = np.argsort(q)
    q, arm = q[order], arm[order]
    pick = np.unique(np.linspace(0, q.size - 1, min(STALL_POSES, q.size)).astype(int))
    worst = (math.inf, math.nan)
    for k in pick:
        pose = _pose(circuit, compiled, dj, float(q[k]))
        g0, per_kg = _gravity(compiled, pose, dj, (link, point))
        held = [f * arm[k] for f in forces]
        if any(h != h for h in held) or abs(per_kg) <= 1e-12 * max(map(abs, held), default=1.0):
            continue
        bound = max(held) if per_kg > 0 else min(held)
        m = (bound - g0) / per_kg
        if m < worst[0]:
            worst = (m, float(q[k]))
    unit = "m" if dj.prismatic else "deg"
    shown = (lambda v: v) if dj.prismatic else math.degrees
    where = "at its end stop, the valve fully open"
    if blocked is not None:
        where = "the jack's at the end of the travel, its valve fully open, the rod still"
    definition = (
        f"the largest mass at the {label} the joint holds at every pose of its travel (the "
        f"other joints at the start pose; {len(pick)} poses): the blocked actuator's force "
        f"({where}) times the moment arm, against the tree's gravity torque"
    )
    if mass0:
        definition += f"; the file's payload is {mass0:g} kg"
    blocked_definition = "the actuator's force blocked at the end stop, valve fully open"
    if blocked is not None:
        blocked_definition = (
            "the jack's force A·p at the end of the stage with its valve fully open (the "
            "lever 2·e_o past the rod) and the rod still: the load pressure at which the "
            "kernel's rate of it vanishes (the valve's flow meets the jack's leakage)"
        )
    stall = mass0 + worst[0] if worst[0] < math.inf else math.nan
    return [
        _row(dj.name, "", "stall payload", stall, "kg", definition),
        _row(
            dj.name,
            "",
            "stall worst pose",
            shown(worst[1]),
            unit,
            "the joint's position where the stall payload is smallest",
        ),
        _row(
            dj.name,
            "increasing",
            "blocked force",
            forces[0],
            "N",
            blocked_definition,
        ),
        _row(
            dj.name,
            "decreasing",
            "blocked force",
            forces[1],
            "N",
            blocked_definition,
        ),
    ]


def _row(joint, direction, quantity, value, unit, definition) -> dict:
    return {
        "joint": joint,
        "direction": direction,
        "quantity": quantity,
        "value": float(value),
        "unit": unit,
        "definition": definition,
    }


def _sources_energy(res: CircuitResult, t1: float = -math.inf, t2: float = math.inf) -> float:
    """Energy [J] the circuit's sources (the components whose energy over the run is
    negative: delivered) delivered between t1 and t2 (NaN if t2 is)."""
    if t2 != t2:
        return math.nan
    e = res.component_energies()
    names = [c.name for c in res.compiled.circuit.components]
    power = res._quantities[1]
    keep = (res.t >= t1) & (res.t <= t2)
    total = 0.0
    for i, name in enumerate(names):
        if e[name] < 0.0:
            total -= float(np.trapezoid(power[keep, i], res.t[keep]))
    return total


def _start_state(circuit: Circuit, compiled) -> np.ndarray:
    """The file's own start (its equilibrium at the [initial] pose, or its initial state)
    as the card circuit's state: each state taken by its name (the controller taken out
    has none left)."""
    own = build(circuit)
    s = equilibrium_state(own) if circuit.equilibrium else own.s0
    by = {name: s[i] for i, (name, _) in enumerate(own.state_names)}
    out = compiled.s0.copy()
    for i, (name, _) in enumerate(compiled.state_names):
        if name in by:
            out[i] = by[name]
    return out


def _stage(base, compiled, P, s0, duration, every, card, tick, label):
    """One run of the card circuit (a row of the batch engine) from s0."""
    c2 = base.replace(duration=STEP_TIME + duration, record_every=every)
    comp2 = build(c2)
    tick(f"card: {label}, {c2.duration:.3g} s")
    t, S, bad = simulate_many(comp2, P[None, :], s0[None, :])
    card.runs += 1
    if bad[0] >= 0:
        raise HydroarmError(
            "card",
            f"{label}: the run left finite numbers at t = {bad[0] * c2.step:.4g} s: take a "
            "smaller [solver] step",
        )
    return CircuitResult(comp2, t, S[0], -1, P)


def _settled(res: CircuitResult, dj: DrivenJoint) -> bool:
    x = _si(res.columns()[_position_key(dj)], dj)
    tail = res.t >= res.t[-1] - SETTLED
    return bool(np.ptp(x[tail]) <= SETTLED_SHARE * max(abs(x[-1] - x[0]), 1e-6))


def _speed_runs(circuit: Circuit, dj: DrivenJoint, card: MechanismCard, tick) -> list[dict]:
    """The joint's runs (module doc): from the file's start, the valve fully open towards
    the lower end until the joint rests at its stop, then fully open the other way through
    the whole travel to the upper stop, then back; each stage run again once, longer, if it
    did not come to rest. Its rows, the stall's among them."""
    base = _drive_circuit(circuit, dj)
    compiled = build(base)
    k_rate = compiled.parameter_index[f"{DRIVE}.rate"]
    k_wave = compiled.parameter_index[f"{DRIVE}.waveform"]
    k_off = compiled.parameter_index[f"{DRIVE}.offset"]
    P0 = frozen_parameters(compiled, 0.0)
    P0[k_wave] = RAMP
    s = _start_state(circuit, compiled)
    held = _held_pose(compiled, dj, s)
    sign = _opening_sign(compiled, dj, _one_record(compiled, s, P0))
    every = max(1, int(round(1.0 / (RECORDS_PER_SECOND * circuit.step))))
    lo, hi = dj.travel
    span = hi - lo
    opening = 0.0
    levers = (0.0, 0.0)
    if dj.servo:  # the lever's ends: the rod where the joint is at each end of its travel
        dj = replace(dj, travel=_servo_travel(compiled, s, P0, dj))
        lo, hi = dj.travel
        span = hi - lo
        levers = (_rod_at(compiled, s, P0, dj, lo), _rod_at(compiled, s, P0, dj, hi))
        opening = _rod_at(compiled, s, P0, dj, s[_joint_state(compiled, dj)])
    duration = FIRST_DURATION
    stages = []
    for k, (direction, up) in enumerate(
        (("to the lower stop", False), ("increasing", True), ("decreasing", False))
    ):
        P = P0.copy()
        target = (1.0 if up else -1.0) * sign * dj.full
        if dj.servo:
            target = levers[1] if up else levers[0]
        P[k_off] = opening
        P[k_rate] = (target - opening) / circuit.step
        label = f"{dj.name} {direction}"
        res = _stage(base, compiled, P, s, duration, every, card, tick, label)
        if not _settled(res, dj):
            x = _si(res.columns()[_position_key(dj)], dj)
            moved = max(abs(x[-1] - x[0]), 1e-3 * span)
            far = span if k else abs(x[0] - lo) + END_MARGIN * span
            need = duration * far / moved * 1.3 + 2 * SETTLED
            duration = min(max(need, duration * 1.5), MAX_DURATION)
            res = _stage(base, compiled, P, s, duration, every, card, tick, label + " (longer)")
        x = _si(res.columns()[_position_key(dj)], dj)
        v, _, t2 = _speed(res.t, x, x[0], x[-1])
        if v > 0.0:  # the next stage crosses the whole travel at about this pace
            duration = min(
                max((t2 - STEP_TIME) * span / abs(x[-1] - x[0]) * 1.4, 0.2) + 2 * SETTLED,
                MAX_DURATION,
            )
        if k:
            stages.append((res, direction, target))
        s = res.states[-1].copy()
        opening = target
    forces = None
    if dj.servo:  # held by its servo at each end: the blocked forces from static solves
        forces = _servo_blocked(compiled, dj, stages, P0, k_off, levers)
    rows = _stall_rows(circuit, compiled, dj, [(r, d) for r, d, _ in stages], forces)
    unit = "m/s" if dj.prismatic else "rad/s"
    card.traces[dj.name] = []
    for res, direction, target in stages:
        cols = res.columns()
        x = _si(cols[_position_key(dj)], dj)
        start, end = float(x[0]), float(x[-1])
        card.traces[dj.name].append((res.t, cols[_position_key(dj)]))
        v, t1, t2 = _speed(res.t, x, start, end)
        vel = np.gradient(x, res.t)
        tau = math.nan
        if v > 0.0:
            tau = crossing_time(res.t, np.sign(end - start) * vel, 0.63 * v, 1.0, STEP_TIME)
            tau = 1e3 * (tau - STEP_TIME)
        span_text = f"{_shown(dj, start)} to {_shown(dj, end)}"
        rows.append(
            _row(
                dj.name,
                direction,
                "speed",
                v,
                unit,
                f"the travel over the middle 80 % of {span_text} over the time it took "
                "(saturation-velocity method), the valve fully open; 0: stopped short",
            )
        )
        if not dj.prismatic:
            rows.append(
                _row(
                    dj.name,
                    direction,
                    "speed [deg/s]",
                    math.degrees(v),
                    "deg/s",
                    "the speed in degrees a second",
                )
            )
        rows.append(
            _row(
                dj.name,
                direction,
                "time constant (63 %)",
                tau,
                "ms",
                "from the valve's step until the joint's velocity first reaches 63 % of its speed",
            )
        )
        if dj.servo:
            rows += _servo_rows(dj, res, cols, direction, target)
        rows += _held_rows(dj, cols, direction, held)
        torque = cols[_torque_key(dj)]
        rows.append(
            _row(
                dj.name,
                direction,
                "peak torque" if not dj.prismatic else "peak force",
                float(np.max(np.abs(torque))),
                "N m" if not dj.prismatic else "N",
                "the largest |torque| (force) of the components on the joint in the run",
            )
        )
        pressures = joint_pressures(res.compiled, cols)
        for key in sorted(k for k in pressures if k.startswith(f"{dj.name}_pressure_")):
            side = key.rsplit("_", 2)[-2]
            rows.append(
                _row(
                    dj.name,
                    direction,
                    f"peak pressure {side}",
                    float(np.max(pressures[key])),
                    "bar",
                    f"the highest pressure in the actuator's chamber {side} in the run",
                )
            )
        if dj.supply is not None and f"{dj.supply}_pressure_bar" in cols:
            p = cols[f"{dj.supply}_pressure_bar"]
            p0 = float(np.interp(STEP_TIME, res.t, p))
            rows.append(
                _row(
                    dj.name,
                    direction,
                    "supply sag",
                    p0 - float(np.min(p[res.t >= STEP_TIME])),
                    "bar",
                    f"the supply node {dj.supply!r}'s pressure at the step less its "
                    "lowest in the run",
                )
            )
        rows.append(
            _row(
                dj.name,
                direction,
                "energy",
                _sources_energy(res, STEP_TIME, t2),
                "J",
                "the energy the circuit's sources delivered from the valve's step "
                "until the joint reached 90 % of its travel",
            )
        )
    return rows


def _held_pose(compiled, dj: DrivenJoint, s: np.ndarray) -> dict[str, tuple[float, bool]]:
    """The other free joints' start positions (display units: deg or m) and whether each is
    prismatic: where the card holds them."""
    mech = compiled.mechanism
    nh = len(compiled.hydraulic)
    out = {}
    for i, name in enumerate(mech.joint_names):
        if i == dj.index or mech.master[i] != i:
            continue
        x = float(s[nh + compiled.mechanical[name]])
        prismatic = mech.joint_types[i] == "prismatic"
        out[name] = (x if prismatic else math.degrees(x), prismatic)
    return out


def _held_rows(dj: DrivenJoint, cols: dict, direction: str, held: dict) -> list[dict]:
    """How well the other joints were held in a stage: the largest excursion from the start
    pose of any of them, revolute [deg] and prismatic [m] apart, and which (the coupling
    made visible: a held joint that gives way under the moving one's loads)."""
    rows = []
    for prismatic, unit, quantity in (
        (False, "deg", "held joints' largest excursion"),
        (True, "m", "held joints' largest excursion (prismatic)"),
    ):
        worst, which = -1.0, ""
        for name, (x0, kind) in held.items():
            if kind != prismatic:
                continue
            x = cols[f"{name}_position_m" if prismatic else f"{name}_angle_deg"]
            d = float(np.max(np.abs(x - x0)))
            if d > worst:
                worst, which = d, name
        if which:
            rows.append(
                _row(
                    dj.name,
                    direction,
                    quantity,
                    worst,
                    unit,
                    "the largest departure of a held joint from its start position in the "
                    f"run ({which}, held by its own loop or lever): the coupling's",
                )
            )
    return rows


def _joint_state(compiled, dj: DrivenJoint) -> int:
    """The index of the joint's position in the state vector."""
    return len(compiled.hydraulic) + compiled.mechanical[dj.name]


def _rod_at(compiled, s: np.ndarray, P: np.ndarray, dj: DrivenJoint, q: float) -> float:
    """A servo jack's rod position [m] with its joint at q (the others as in s): the
    kernel's projection sets the linkages' slaves from the joint (the crank's x(q)), so the
    lever that holds the joint at q is this (mechanical feedback: e = lever − rod)."""
    x = s.copy()
    x[_joint_state(compiled, dj)] = q
    x = project_state(compiled, 0.0, x, P)
    assert dj.rod is not None
    return float(x[len(compiled.hydraulic) + compiled.mechanical[dj.rod]])


def _servo_travel(compiled, s, P, dj: DrivenJoint) -> tuple[float, float]:
    """A servo jack's lever travel as the joint's (module doc): its limits less the
    margins, narrowed to where the jack's moment arm |dx/dq| (the rod's motion per unit of
    the joint's, through the linkages: the kernel's projection at `ARM_GRID` poses)
    is at least `SERVO_ARM_SHARE` of its largest over the limits, the part around
    the largest."""
    lo, hi = dj.travel
    m = END_MARGIN / (1.0 - 2.0 * END_MARGIN) * (hi - lo)  # back to the limits
    q = np.linspace(lo - m, hi + m, ARM_GRID)
    x = np.array([_rod_at(compiled, s, P, dj, float(v)) for v in q])
    g = np.abs(np.gradient(x, q))
    k = int(np.argmax(g))
    ok = g >= SERVO_ARM_SHARE * g[k]
    a = k
    while a > 0 and ok[a - 1]:
        a -= 1
    b = k
    while b < q.size - 1 and ok[b + 1]:
        b += 1
    return max(lo, float(q[a])), min(hi, float(q[b]))


def _servo_blocked(compiled, dj: DrivenJoint, stages, P0, k_off, levers) -> list[float]:
    """A servo jack's blocked forces [N] (increasing, decreasing). At the end of a stage the
    servo holds the joint with its valve closed, so the jack is never blocked in the runs;
    its blocked force is solved for at each stage's end state (at rest at the end of its
    travel, the supply where the relief passes the pump's flow): the lever 2·e_o past the
    rod (the valve fully open that way), the rod still, the load pressure p at which the
    kernel's own rate of it vanishes (`hydroarm.model.circuit_steady.rhs`, the one
    physics; a root in p, the other states as they are: the valve's flow meets the jack's
    leakage), then the kernel's projection (the orifice valve's cavitation floor); the
    force is the jack's A·p there. NaN where p has no root (a linear valve without
    leakage, whose flow does not fall with the load)."""
    from scipy.optimize import brentq  # lazy, as the other analyses take scipy

    k_p = [name for name, _ in compiled.state_names].index(f"{dj.actuator}.load_pressure")
    up = 1.0 if levers[1] >= levers[0] else -1.0
    nh = len(compiled.hydraulic)
    v = nh + len(compiled.mechanical) + compiled.mechanical[dj.name]
    comp = next(c for c in compiled.circuit.components if c.name == dj.actuator)
    out = []
    for res, direction, _ in stages:
        s = res.states[-1].copy()
        s[v] = 0.0  # the joint (and so its rod) still
        P = P0.copy()
        P[k_off] = _rod_at(compiled, s, P0, dj, float(s[_joint_state(compiled, dj)]))
        P[k_off] += (up if direction == "increasing" else -up) * 2.0 * dj.full
        P = frozen_parameters(compiled, 0.0, P)
        s = project_state(compiled, 0.0, s, P)
        p_s = abs(s[compiled.hydraulic[comp.ports["P"]]] - s[compiled.hydraulic[comp.ports["T"]]])

        def rate(p, s=s, P=P):
            x = s.copy()
            x[k_p] = p
            return float(rhs(compiled, 0.0, x, P)[k_p])

        force = math.nan
        for reach in (2.0, 1e3):  # the orifice's root lies within ±p_s; a linear valve's
            lo, hi = -reach * max(p_s, 1.0), reach * max(p_s, 1.0)
            if rate(lo) * rate(hi) < 0.0:
                x = s.copy()
                x[k_p] = brentq(rate, lo, hi, xtol=1e-9 * max(p_s, 1.0), rtol=1e-12)
                x = project_state(compiled, 0.0, x, P)
                force = float(_one_record(compiled, x, P)[f"{dj.actuator}_force_n"][0])
                break
        out.append(force)
    return out


def _servo_rows(dj: DrivenJoint, res: CircuitResult, cols: dict, direction: str, target):
    """A servo jack's own rows of a stage, the paper's measures on its rod (Table III, the
    no-load transients; [`hydroarm.metrics.step.step_metrics`][hydroarm.step_metrics]): the jack's
    saturation velocity over the middle 80 % of the rod's travel, the time to move 63 % of the full
    valve opening e_o at the start and at the end of travel, and the peak load pressure."""
    assert dj.rod is not None
    x = cols[f"{dj.rod}_position_m"]
    m = step_metrics(
        res.t,
        x,
        valve_opening=dj.full,
        target=float(target),
        t_start=STEP_TIME,
        middle=MIDDLE,
    )
    span = f"the lever stepped from {1e3 * x[0]:.4g} to {1e3 * target:.4g} mm"
    p = cols[f"{dj.actuator}_load_pressure_bar"]
    return [
        _row(
            dj.name,
            direction,
            "jack speed",
            1e3 * m["saturation_velocity"],
            "mm/s",
            f"the jack rod's travel over the middle 80 % of its motion over the time it "
            f"took ({span}): the paper's saturation velocity (Table III)",
        ),
        _row(
            dj.name,
            direction,
            "time constant, start (63 % of e_o)",
            1e3 * m["time_constant_start"],
            "ms",
            "from the lever's step until the rod has moved 63 % of the full valve opening "
            f"e_o = {1e3 * dj.full:g} mm: the paper's transient time constant",
        ),
        _row(
            dj.name,
            direction,
            "time constant, end (63 % of e_o)",
            1e3 * m["time_constant_end"],
            "ms",
            "the time the rod takes from e_o to 0.37·e_o short of the lever's end: the "
            "paper's end-of-travel time constant",
        ),
        _row(
            dj.name,
            direction,
            "peak load pressure",
            float(np.max(np.abs(p))),
            "bar",
            "the largest |p_A − p_B| of the jack (its lumped load pressure) in the run",
        ),
    ]


def _shown(dj: DrivenJoint, x: float) -> str:
    return f"{x:.4g} m" if dj.prismatic else f"{math.degrees(x):.4g} deg"


def _task_rows(task: CircuitResult) -> list[dict]:
    """The file's own run: per controller on a joint its tracking error; cycle time; energy."""
    compiled = task.compiled
    mech = compiled.mechanism
    assert mech is not None
    c = compiled.circuit
    cols = task.columns()
    rows = []
    sensors = {
        comp.ports["out"]: comp.ports["body"]
        for comp in c.components
        if comp.type == "position_sensor" and "out" in comp.ports and "body" in comp.ports
    }
    joints = set(mech.joint_names)
    for comp in c.components:
        if comp.type != "pid":
            continue
        ref, meas = comp.ports.get("reference"), comp.ports.get("measurement")
        body = sensors.get(meas or "")
        if ref is None or body is None or body not in joints:
            continue
        i = mech.joint_names.index(body)
        deg = mech.joint_types[i] != "prismatic"
        f = math.degrees(1.0) if deg else 1.0
        err = (cols[f"{ref}_signal"] - cols[f"{meas}_signal"]) * f
        unit = "deg" if deg else "m"
        rows.append(
            _row(
                "task",
                body,
                "tracking error (RMS)",
                float(np.sqrt(np.mean(err**2))),
                unit,
                f"{comp.name}'s reference less its measurement, RMS over the run",
            )
        )
        rows.append(
            _row(
                "task",
                body,
                "tracking error (largest)",
                float(np.max(np.abs(err))),
                unit,
                f"{comp.name}'s largest |reference − measurement| in the run",
            )
        )
    rows.append(
        _row(
            "task",
            "",
            "cycle time",
            float(task.t[-1]),
            "s",
            "the file's run: its [solver] duration",
        )
    )
    rows.append(
        _row(
            "task",
            "",
            "energy",
            _sources_energy(task),
            "J",
            "the energy the circuit's sources delivered over the file's run",
        )
    )
    return rows


def mechanism_card(
    circuit: Circuit,
    task: CircuitResult | None = None,
    *,
    max_runs: int = MAX_RUNS,
    progress=None,
    check_only: bool = False,
) -> MechanismCard | int:
    """The card of a mechanism file's circuit (module doc); ``task``: the file's own run
    (``hydroarm arm``'s), whose rows are added. Refused before any work where the protocol
    cannot apply or needs more than ``max_runs`` runs (`check_card`); with
    ``check_only`` only that check, returning the most runs it will take."""
    tick = progress or (lambda label: None)
    joints, skipped = check_card(circuit, max_runs)
    if check_only:
        return runs_needed(joints)
    card = MechanismCard(circuit.name, skipped=skipped)
    for dj in joints:
        card.rows += _speed_runs(circuit, dj, card, tick)
    if task is not None:
        card.rows += _task_rows(task)
    return card


def _si(x, dj: DrivenJoint):
    return np.asarray(x) if dj.prismatic else np.radians(x)


def _full_q(compiled, pose) -> np.ndarray:
    mech = compiled.mechanism
    q = np.zeros(mech.n)
    for i, name in enumerate(mech.joint_names):
        if name in pose:
            q[i] = pose[name]
    for i in range(mech.n):
        m = int(mech.master[i])
        if m != i:
            q[i] = mech.ratio[i] * q[m] + mech.offset[i]
    return q


def _gravity(compiled, pose, dj: DrivenJoint, point) -> tuple[float, float]:
    """(the joint's gravity torque at rest at the pose [N m or N], its rise per kg of
    payload at ``point`` = (tree link index, point in its frame)); the tree kernel's bias
    forces, the payload's weight an external force. Coupled joints' torques reach their
    masters through the coupling (Gᵀ)."""
    mech = compiled.mechanism
    tree = mech.tree
    n = mech.n
    q = _full_q(compiled, pose)
    work = T.make_tree_work(n)
    zero = np.zeros(n)
    fext = np.zeros((n, 6))
    out = np.zeros(n)
    T.bias_forces(tree, q, zero, fext, work, out)
    g0 = _reduced(mech, out, dj.index)
    link, p = point
    R = np.zeros((n, 3, 3))
    pw = np.zeros((n, 3))
    T.forward_kinematics(tree, q, work, R, pw)
    T.point_force(
        R[link], np.asarray(p, float), np.asarray(tree.gravity, float), np.zeros(3), fext[link]
    )
    out2 = np.zeros(n)
    T.bias_forces(tree, q, zero, fext, work, out2)
    return g0, _reduced(mech, out2, dj.index) - g0


def _reduced(mech, tau: np.ndarray, j: int) -> float:
    """Joint j's generalised force with its followers' folded in (Gᵀ·τ)."""
    total = float(tau[j])
    for i in range(mech.n):
        if i != j and int(mech.master[i]) == j:
            total += float(mech.ratio[i]) * float(tau[i])
    return total


def _payload_point(circuit: Circuit, compiled, dj: DrivenJoint):
    """(tree link index, point in its frame, label) of the stall payload (module doc)."""
    mech = compiled.mechanism
    tree = mech.tree
    moved = {dj.index}
    for i in range(mech.n):
        if int(tree.parent[i]) in moved:
            moved.add(i)
    spec = circuit.mechanism
    for pl in getattr(spec, "payloads", ()):
        if pl.link in mech.link_names:
            i = mech.link_names.index(pl.link)
            if i in moved:
                return i, tuple(float(v) for v in pl.point), f"payload {pl.name!r}", pl.mass
    leaf = max(moved)
    return (
        leaf,
        tuple(float(v) for v in tree.com[leaf]),
        "centre of mass of link " + repr(mech.link_names[leaf]),
        0.0,
    )
