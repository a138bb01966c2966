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
signal's own: a spool demand in m, a setpoint in rad or m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import HydroarmError
from ..model.circuit_stepper import CircuitStepper
from ..plotting.mechanism import stick_parents, stick_points
from .live import MAX_TICK
from .system import SystemModel

LEVER_SPAN = 1.5  # a lever's range: this many times the largest value of its signal in the run
VIEW_POSES = 50  # poses of the file's run that set the view's extent
RANGE_POSES = 729  # at most this many poses over the joints' ranges (a grid) set it too
CAMERA_FOV = 40.0  # the 3-D view's vertical field of view [deg]
CAMERA_ELEVATION, CAMERA_AZIMUTH = 20.0, -30.0  # the camera above the ground, round the front


@dataclass(frozen=True)
class Lever:
    """A lever of the live mechanism: the circuit input ``name`` it sets (``<source>.value``),
    the ``signal`` it drives, its range [SI] and its value at the start."""

    name: str
    signal: str
    low: float
    high: float
    start: float


def levers_of(model: SystemModel, stepper: CircuitStepper) -> list[Lever]:
    """The levers of a system (module doc): one per input carried by a signal."""
    start = stepper.start_values()
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
        out.append(Lever(name, i.signal, low, high, min(max(start[name], low), high)))
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
        self.reset()
        self.levers = levers_of(model, self.stepper)
        self.parents = stick_parents(self.mechanism)
        g = np.asarray(self.mechanism.tree.gravity, dtype=float)
        gn = float(np.linalg.norm(g))
        # up on screen: against gravity (world z where there is none)
        self.up = -g / gn if gn > 0 and math.isfinite(gn) else np.array([0.0, 0.0, 1.0])
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
        self.stepper = CircuitStepper(self.model.runner.compiled)
        self.values: dict[str, float] = {}  # the levers moved, by input name [SI]
        self.paused = False
        self.stopped = ""
        self._outputs = self.stepper.outputs()

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
            self.stepper.advance(dt)
        except HydroarmError as exc:
            self.paused = True
            self.stopped = str(exc)
            raise
        self._outputs = self.stepper.outputs()
        return dt

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
