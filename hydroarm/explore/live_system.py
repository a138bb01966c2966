"""A mechanism live (issue 32): any mechanism file's joints driven from levers, stepped at
the wall clock's pace, its links drawn as they move (docs/explore.md "A mechanism live").

Plain Python (no web framework): the system page (:mod:`.system_app`) calls
:meth:`LiveSystem.tick` from a timer with the wall time elapsed and :meth:`LiveSystem.set_lever`
from its sliders. The physics is the system's own: :class:`hydroarm.model.circuit_stepper.
CircuitStepper` of the compiled circuit the page runs (the one system kernel, the steps of
``simulate``); this module only sets its inputs and reads its outputs.

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
from .system import SystemModel, _pose_axis, _r

LEVER_SPAN = 1.5  # a lever's range: this many times the largest value of its signal in the run
VIEW_POSES = 50  # poses of the file's run that set the view's extent


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
        # the view: square, around every pose of the file's run (it stays put while driven)
        q = self._q_of(model.columns)
        rows = np.unique(np.linspace(0, len(q) - 1, min(len(q), VIEW_POSES)).astype(int))
        pts = stick_points(self.mechanism, q[rows])
        lo, hi = np.min(pts, axis=(0, 1)), np.max(pts, axis=(0, 1))
        self._span = max(hi[0] - lo[0], hi[2] - lo[2], 1e-3) * 0.75
        self._centre = ((hi[0] + lo[0]) / 2, (hi[2] + lo[2]) / 2)

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
        """Advance by ``wall_dt`` [s] of wall time (at most :data:`~.live.MAX_TICK`) × the
        speed; a run that fails stops (:attr:`stopped`; the error is raised). Returns the
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

    def pose(self) -> dict:
        """ECharts options of the stick figure now, in the side view (x across, z up)."""
        p = stick_points(self.mechanism, self._q_of(self._outputs))[0]
        segs = [
            {"coords": [[_r(p[j, 0]), _r(p[j, 2])], [_r(p[k, 0]), _r(p[k, 2])]]}
            for k, j in enumerate(self.parents)
            if j >= 0
        ]
        cx, cz = self._centre
        return {
            "animation": False,
            "title": {"text": f"t = {self.t:.2f} s", "textStyle": {"fontSize": 12}},
            "grid": {"left": 56, "right": 16, "top": 32, "bottom": 40},
            "xAxis": _pose_axis("x [m]", cx, self._span),
            "yAxis": _pose_axis("z [m]", cz, self._span),
            "series": [
                {
                    "type": "lines",
                    "coordinateSystem": "cartesian2d",
                    "lineStyle": {"color": "#34495e", "width": 5},
                    "data": segs,
                }
            ],
        }
