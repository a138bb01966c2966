"""A mechanism live (issue 32): any mechanism file's joints driven from levers, stepped at
the wall clock's pace, its links drawn as they move (docs/explore.md "A mechanism live").

Plain Python (no web framework): the system page (`system_app`) calls
`LiveSystem.tick` from a timer with the wall time elapsed and `LiveSystem.set_lever`
from its sliders. The physics is the system's own: `hydroarm.model.circuit_stepper.CircuitStepper`
of the compiled circuit the page runs (the one system kernel, the steps of ``simulate``); this
module only sets its inputs and reads its outputs.

Levers. Every signal source that drives something (a valve's lever or spool demand, a
controller's setpoint: the circuit's inputs carried by a signal) is a lever: a slider whose
value replaces the source's waveform from the moment it is moved, held until moved again.
Its range: ±1.5 × the largest value the signal takes in the file's own run (0 to 1.5 × it
for a signal that never goes below zero; ±1 for a signal that stays at 0), in SI units (the
signal's own: a spool demand in m). A source feeding a controller's (``pid``) reference whose
measurement is a ``position_sensor`` on a mechanical node (electronic feedback: a joint of
the mechanism, or a node a linkage positions, such as a cylinder's rod) is a *setpoint*: its
slider is the node's position in deg (rotational) or mm (translational), over the joint's
limits where it is a joint with finite ones, the signal set to the sensor's gain × position
+ offset.

Gauges: one per supply node (`supplies_of`): the outlet of each ``fixed_pump``,
``variable_pump`` and ``flow_source``, and each tank above the circuit's lowest tank
pressure (a tank at supply pressure); its setting is the highest relief valve's cracking
pressure on the node, else a variable pump's, else the tank's pressure, else the node's
highest pressure in the file's run; its scale 0 to 1.5 × the setting.

A block task (``[block_task]``, `mechanism_task`): the grasp puts the load's mass on
the hand link (`CircuitStepper.set_payloads`); the table is a floor for the hand's
tip: a tick that ends with the tip below the table, having begun at or above it, is taken
again in pieces of `CONTACT_STEP`, and a piece that takes the tip through it
stops the free joints whose own motion in the piece moved the tip down where the piece began
(velocity zero, pressures kept: `CircuitStepper.stop_joints`), every free joint if the
tip would still be through, as the arm's live view does.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from ..core.circuit.declare import ROTATIONAL
from ..core.tree import TreeModel, inverse_dynamics, make_tree_work
from ..errors import HydroarmError
from ..model.circuit import CompiledCircuit
from ..model.circuit_stepper import TREE_SLICE, CircuitStepper
from ..plotting.mechanism import stick_parents, stick_points
from .live import CONTACT_STEP, MAX_TICK
from .mechanism_task import TipOf
from .system import SystemModel, up_of

LEVER_SPAN = 1.5  # a lever's range: this many times the largest value of its signal in the run
VIEW_POSES = 50  # poses of the file's run that set the view's extent
RANGE_POSES = 729  # at most this many poses over the joints' ranges (a grid) set it too
CAMERA_FOV = 40.0  # the 3-D view's vertical field of view [deg]
CAMERA_ELEVATION, CAMERA_AZIMUTH = 20.0, -30.0  # the camera above the ground, round the front


@dataclass(frozen=True)
class Lever:
    """A lever of the live mechanism: the circuit input ``name`` it sets (``<source>.value``),
    the ``signal`` it drives, its range [SI] and its value at the start. A setpoint (module
    doc) names its ``joint`` and its ``unit`` (``deg`` or ``mm``); the signal is
    ``gain``·position + ``offset`` (the sensor's), the range and start are the signal's."""

    name: str
    signal: str
    low: float
    high: float
    start: float
    joint: str = ""
    unit: str = "SI"
    gain: float = 1.0
    offset: float = 0.0

    @property
    def factor(self) -> float:
        """Shown per SI position (deg per rad, mm per m; 1 for a plain lever)."""
        return {"deg": 180.0 / math.pi, "mm": 1e3}.get(self.unit, 1.0)

    def shown(self, signal: float) -> float:
        """The slider's value for a signal value: the joint's position in its unit."""
        return (signal - self.offset) / self.gain * self.factor if self.joint else signal

    def signal_of(self, shown: float) -> float:
        return self.gain * shown / self.factor + self.offset if self.joint else shown


def _setpoints(compiled: CompiledCircuit) -> dict[str, tuple[str, float, float]]:
    """Signals that are a setpoint (module doc): signal → (the mechanical node measured: a
    joint, or a node a linkage positions, such as a cylinder's rod; the sensor's gain,
    offset)."""
    comps = compiled.circuit.components
    measured = {}  # signal -> (node, gain, offset)
    for c in comps:
        if c.type == "position_sensor" and c.ports.get("body") in compiled.mechanical:
            P, ix = compiled.P, compiled.parameter_index
            g, o = (float(P[ix[f"{c.name}.{k}"]]) for k in ("gain", "offset"))
            if "out" in c.ports and g != 0.0:
                measured[c.ports["out"]] = (c.ports["body"], g, o)
    out = {}
    for c in comps:
        if c.type == "pid" and c.ports.get("measurement") in measured:
            if "reference" in c.ports:
                out[c.ports["reference"]] = measured[c.ports["measurement"]]
    return out


def levers_of(model: SystemModel, stepper: CircuitStepper) -> list[Lever]:
    """The levers of a system (module doc): one per input carried by a signal."""
    start = stepper.start_values()
    setpoints = _setpoints(stepper.compiled)
    mech = stepper.compiled.mechanism
    out = []
    for name, i in stepper.inputs.items():
        if not i.signal:
            continue
        run = model.columns.get(f"{i.signal}_signal")
        values = np.asarray(run if run is not None else [start[name]], dtype=float)
        top = float(np.max(np.abs(values)))
        if not (top > 0 and math.isfinite(top)):
            low, high = -1.0, 1.0
        elif float(np.min(values)) >= 0.0:
            low, high = 0.0, LEVER_SPAN * top
        else:
            low, high = -LEVER_SPAN * top, LEVER_SPAN * top
        extra: dict = {}
        if i.signal in setpoints:
            node, g, o = setpoints[i.signal]
            rotational = stepper.compiled.mech_domain[node] == ROTATIONAL
            if mech is not None and node in mech.joint_names:  # over the joint's limits
                lo, hi = mech.kernel_limits()[mech.index(node), 2:4]
                if math.isfinite(lo) and math.isfinite(hi):
                    low, high = sorted((g * lo + o, g * hi + o))
            unit = "deg" if rotational else "mm"
            extra = {"joint": node, "unit": unit, "gain": g, "offset": o}
        out.append(Lever(name, i.signal, low, high, min(max(start[name], low), high), **extra))
    return out


@dataclass(frozen=True)
class Supply:
    """A supply's gauge: its hydraulic ``node``, the components feeding it (``sources``),
    its ``setting`` [Pa] and what sets it (``what``), the scale's top [Pa]."""

    node: str
    sources: tuple[str, ...]
    setting: float
    what: str

    @property
    def top(self) -> float:
        return 1.5 * self.setting


def supplies_of(compiled: CompiledCircuit, columns: dict) -> list[Supply]:
    """The supply nodes of a circuit and their settings (module doc)."""
    comps = compiled.circuit.components
    P, ix = compiled.P, compiled.parameter_index

    def par(c, key: str) -> float:
        return float(P[ix[f"{c.name}.{key}"]])

    tanks = [c for c in comps if c.type == "tank" and "port" in c.ports]
    low = min((par(c, "pressure") for c in tanks), default=math.nan)
    fed: dict[str, list] = {}
    for c in comps:
        if c.type in ("fixed_pump", "variable_pump", "flow_source") and "outlet" in c.ports:
            fed.setdefault(c.ports["outlet"], []).append(c)
        elif c in tanks and par(c, "pressure") > low:
            fed.setdefault(c.ports["port"], []).append(c)
    out = []
    for node, sources in fed.items():
        reliefs = [
            par(c, "cracking_pressure")
            for c in comps
            if c.type == "relief_valve" and c.ports.get("inlet") == node
        ]
        pumps = [par(c, "cracking_pressure") for c in sources if c.type == "variable_pump"]
        held = [par(c, "pressure") for c in sources if c.type == "tank"]
        if reliefs:
            setting, what = max(reliefs), "relief"
        elif pumps:
            setting, what = max(pumps), "compensator"
        elif held:
            setting, what = max(held), "tank"
        else:
            run = np.asarray(columns.get(f"{node}_pressure_bar", [1.0]), dtype=float) * 1e5
            setting, what = float(np.nanmax(run)), "the run's highest"
        if not (setting > 0 and math.isfinite(setting)):
            setting, what = 1e5, "none"
        out.append(Supply(node, tuple(c.name for c in sources), setting, what))
    return out


class LiveSystem:
    """A mechanism file's system live: its levers, the stepper, the clock (module doc)."""

    def __init__(self, model: SystemModel):
        if model.mechanism is None:
            raise HydroarmError("--config", "the live view needs a mechanism ([mechanism])")
        self.model = model
        self.mechanism = model.mechanism
        self.joint_names = list(self.mechanism.joint_names)
        self.speed = 1.0
        # the visitor's own task (the model's is shared read-only by every visitor)
        self.task = copy.deepcopy(model.task)
        self.compiled = model.live_compiled  # without a block task's load (SystemModel)
        self._tip = self._load = None
        if self.task is not None:
            k = self.task.hand_index
            self._tip = TipOf(self.mechanism, k, self.task.tip)
            self._load = TipOf(self.mechanism, k, np.array(self.task.load.point))
        self.reset()
        self.levers = levers_of(model, self.stepper)
        self.supplies = supplies_of(self.compiled, model.columns)
        self.parents = stick_parents(self.mechanism)
        # up on screen: against gravity (world z where there is none)
        self.up = up_of(self.compiled)
        self.view = self._view(model)

    def _view(self, model: SystemModel) -> dict:
        """The 3-D view, fixed while driven: its ``centre`` and ``radius`` [m] (a sphere round
        the stick points of the start pose, of poses of the file's run and of a grid over the
        joints' finite ranges), the ``camera``'s position, the ``up`` vector, the ``ground``
        grid's lines (perpendicular to up, under the lowest point) and the ``link`` radius."""
        q = self._q_of(model.columns)
        rows = np.unique(np.linspace(0, len(q) - 1, min(len(q), VIEW_POSES)).astype(int))
        poses = [q[rows], self._q_of(self._outputs)]
        lo = np.asarray(self.mechanism.lower, dtype=float)
        hi = np.asarray(self.mechanism.upper, dtype=float)
        finite = np.isfinite(lo) & np.isfinite(hi)
        n = len(self.joint_names)
        per = next((k for k in (5, 3, 2) if k**n <= RANGE_POSES), 1)
        if per > 1 and finite.any():
            axes = [np.linspace(lo[j], hi[j], per) if finite[j] else q[:1, j] for j in range(n)]
            grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n)
            poses.append(grid)
        pts = stick_points(self.mechanism, np.concatenate(poses)).reshape(-1, 3)
        if self.task is not None:  # the load, where it lies and over the target
            t = self.task
            h = t.size / 2 * self.up
            pts = np.vstack([pts, t.block0 - h, t.block0 + h, t.target, t.target + 2 * h])
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        a, b = np.min(pts, axis=0), np.max(pts, axis=0)
        centre = (a + b) / 2
        radius = max(float(np.max(np.linalg.norm(pts - centre, axis=1))), 0.05)
        up = self.up
        # the front: world -y, made perpendicular to up (world x where up is along y)
        front = np.array([0.0, -1.0, 0.0])
        if abs(float(front @ up)) > 0.9:
            front = np.array([1.0, 0.0, 0.0])
        front = front - (front @ up) * up
        front /= np.linalg.norm(front)
        side = np.cross(up, front)
        az, el = math.radians(CAMERA_AZIMUTH), math.radians(CAMERA_ELEVATION)
        look = math.cos(el) * (math.cos(az) * front + math.sin(az) * side) + math.sin(el) * up
        dist = radius / math.sin(math.radians(CAMERA_FOV) / 2)  # the sphere fits the height
        # the ground: a square grid of nice steps under the lowest point
        step = float(10 ** math.floor(math.log10(radius / 2)))
        step *= next((m for m in (5, 2) if step * m <= radius / 2), 1)
        low = float(np.min(pts @ up))
        origin = centre - (centre @ up - low) * up
        half = math.ceil(1.2 * radius / step) * step
        u0, v0 = (round(float(origin @ e) / step) * step for e in (front, side))
        base = origin - (origin @ front) * front - (origin @ side) * side
        ground = []
        for k in np.arange(-half, half + step / 2, step):
            for e, f, c0, c1 in ((front, side, u0, v0), (side, front, v0, u0)):
                p0 = base + (c0 + k) * e + (c1 - half) * f
                p1 = base + (c0 + k) * e + (c1 + half) * f
                ground.append((p0.tolist(), p1.tolist()))
        return {
            "centre": centre,
            "radius": radius,
            "camera": centre + dist * look,
            "up": up,
            "ground": ground,
            "link": max(0.025 * radius, 0.002),
            "fov": CAMERA_FOV,
        }

    def reset(self) -> None:
        """Back to the file's start: the stepper anew, the levers at their sources' start
        values (the waveforms run until a lever is moved), the clock at 0."""
        self.stepper = CircuitStepper(self.compiled)
        self.values: dict[str, float] = {}  # the levers moved, by input name [SI]
        self.paused = False
        self.stopped = ""
        self._outputs = self.stepper.outputs()
        if self.task is not None:
            self.task.reset()

    def lever(self, name: str) -> Lever:
        for lv in self.levers:
            if lv.name == name:
                return lv
        raise HydroarmError("lever", f"{name!r} is not a lever of this system")

    def set_lever(self, name: str, value) -> None:
        """Set a lever [SI], clamped to its range; held until set again."""
        lv = self.lever(name) if isinstance(name, str) else self.lever(repr(name))
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise HydroarmError(f"lever.{name}", f"must be a number, got {value!r}")
        if not math.isfinite(value):
            raise HydroarmError(f"lever.{name}", f"must be finite, got {value!r}")
        v = min(max(float(value), lv.low), lv.high)
        self.stepper.set_input(name, v)
        self.values[name] = v

    def value(self, name: str) -> float:
        """A lever's value now [SI]: set, else its signal's now."""
        lv = self.lever(name)
        return self.values.get(name, self._outputs.get(f"{lv.signal}_signal", lv.start))

    def toggle_pause(self) -> None:
        if not self.stopped:
            self.paused = not self.paused

    @property
    def state(self) -> str:
        return "stopped" if self.stopped else ("paused" if self.paused else "running")

    @property
    def t(self) -> float:
        return float(self.stepper.t)

    def tick(self, wall_dt: float) -> float:
        """Advance by ``wall_dt`` [s] of wall time (at most `MAX_TICK`) × the
        speed; a run that fails stops (`stopped`; the error is raised). Returns the
        simulated time advanced [s]."""
        if self.paused or self.stopped or not wall_dt > 0:
            return 0.0
        dt = min(float(wall_dt), MAX_TICK) * self.speed
        try:
            self._advance(dt)
        except HydroarmError as exc:
            self.paused = True
            self.stopped = str(exc)
            raise
        self._outputs = self.stepper.outputs()
        if self.task is not None and self.task.where == "held":
            self.task.centre = self.load_point()
        return dt

    def _advance(self, dt: float) -> None:
        """Advance the stepper by ``dt`` [s]: in one call, unless the tip ends it below the
        table having started at or above it; then again from the same state in pieces of at
        most `CONTACT_STEP`, the floor's contact (`_contact`) after each
        (the pieces give the one call's steps where no contact acts)."""
        if self._tip is None or self.task is None:
            self.stepper.advance(dt)
            return
        table = self.task.table
        if self._height(self.stepper.joint_positions()[0]) < table:
            self.stepper.advance(dt)
            return
        saved = self.stepper.get_state()
        self.stepper.advance(dt)
        if self._height(self.stepper.joint_positions()[0]) >= table:
            return
        self.stepper.set_state(saved)
        n = max(1, math.ceil(dt / CONTACT_STEP - 1e-9))
        for _ in range(n):
            before = self.stepper.joint_positions()[0]
            self.stepper.advance(dt / n)
            self._contact(before)

    def _height(self, q: np.ndarray) -> float:
        assert self._tip is not None
        return float(self._tip(q) @ self.up)

    def _contact(self, before: np.ndarray) -> None:
        """The table as a floor for the tip (module doc): the free joints whose own motion in
        the piece just taken moved the tip down through the table are stopped where the piece
        began; all of them if the tip would still be through."""
        assert self.task is not None
        table = self.task.table
        after = self.stepper.joint_positions()[0]
        start = self._height(before)
        if not (start >= table > self._height(after)):
            return
        mech = self.mechanism
        free = [j for j in range(mech.n) if mech.master[j] == j]
        stop = []
        for j in free:
            moved = before.copy()
            moved[j] = after[j]
            if self._height(moved) < start:
                stop.append(j)
        kept = after.copy()
        kept[stop] = before[stop]
        if self._height(kept) < table:
            stop = free
        self.stepper.stop_joints({j: float(before[j]) for j in stop})

    # the block task --------------------------------------------------------------------
    def tip(self) -> np.ndarray:
        """The hand's tip now [m] (world)."""
        if self._tip is None:
            raise HydroarmError("block_task", "the file has no block task")
        return self._tip(self.stepper.joint_positions()[0])

    def load_point(self) -> np.ndarray:
        """Where the load sits on the hand link now [m] (world; drawn there while held)."""
        if self._load is None:
            raise HydroarmError("block_task", "the file has no block task")
        return self._load(self.stepper.joint_positions()[0])

    def grasp(self) -> str:
        """Grasp the load (within reach) or release the one held; returns what happened.
        While held its mass is on the hand link (`CircuitStepper.set_payloads`)."""
        task = self.task
        if task is None:
            raise HydroarmError("block_task", "the file has no block task")
        tip = self.tip()
        if task.where == "held":
            self.stepper.set_payloads(())
            task.release(tip)
        elif task.within_reach(tip):
            self.stepper.set_payloads((task.load,))
            task.where = "held"
            task.centre = self.load_point()
        else:
            away = float(np.linalg.norm(tip - task.centre))
            return f"nothing within reach: the load is {away:.2f} m from the tip"
        return task.describe()

    def holding(self) -> dict[str, float]:
        """Each joint's holding load now [N·m or N]: the torque (force) that holds the links,
        and what they carry, against gravity at the joints' positions now, at rest (the
        tree's inverse dynamics with no velocity or acceleration) — the tree the kernel
        steps, a grasped load included."""
        n = self.mechanism.n
        tree = TreeModel(*self.stepper.net[TREE_SLICE])
        q = np.ascontiguousarray(self.stepper.joint_positions()[0])
        tau, zero = np.zeros(n), np.zeros(n)
        inverse_dynamics(tree, q, zero, zero, np.zeros((n, 6)), make_tree_work(n), tau)
        return dict(zip(self.joint_names, tau.tolist(), strict=True))

    def pressures(self) -> dict[str, float]:
        """Each hydraulic node's pressure now [bar] (the gauges' and the pressures' line)."""
        o = self._outputs
        return {k[: -len("_pressure_bar")]: v for k, v in o.items() if k.endswith("_pressure_bar")}

    # what the page shows ---------------------------------------------------------------
    def _q_of(self, cols) -> np.ndarray:
        """Joint positions (records × joints) [rad, m] from output columns (a run's arrays or
        one state's floats)."""
        return np.column_stack(
            [
                np.radians(np.atleast_1d(cols[f"{n}_angle_deg"]))
                if f"{n}_angle_deg" in cols
                else np.atleast_1d(cols[f"{n}_position_m"])
                for n in self.joint_names
            ]
        )

    def joints(self) -> dict[str, str]:
        """Each joint's position now, with its unit (``lift``: ``12.3 deg``)."""
        o = self._outputs
        return {
            n: f"{o[f'{n}_angle_deg']:.2f} deg"
            if f"{n}_angle_deg" in o
            else f"{o[f'{n}_position_m'] * 1e3:.1f} mm"
            for n in self.joint_names
        }

    def points(self) -> np.ndarray:
        """The stick figure now: world positions [m] (points × 3) of the base, each joint's
        origin and each leaf's tip (`hydroarm.plotting.mechanism.stick_points`); point
        k > 0 is drawn from point `parents` [k]."""
        return stick_points(self.mechanism, self._q_of(self._outputs))[0]
