"""The system page's state: any system file (a circuit, a mechanism, a component servo shown
as its circuit, a reference file or a study naming one) with sliders (and number fields)
for some of its parameters and the outputs chosen to plot (issue 29; docs/explore.md "Any
system file").

Plain Python (no web framework): `SystemModel` is read and checked once before the
server starts and shared read-only by every visitor (the file's system, the sliders, the
outputs, the file's own run); `SystemExplorer` is one visitor's state (the values
set, the outputs chosen, the last run's columns and message). A run is the system's own:
`hydroarm.analysis.systems.SystemRunner.simulate_columns`, which is
`hydroarm.model.circuit.simulate` (one physics; the columns ``hydroarm simulate
--out`` writes). The page calls `SystemExplorer.update` on a thread (the kernels
release the GIL) and draws `SystemExplorer.chart` in the browser (ECharts).

The optional ``[explore]`` section of the file (the other commands leave it alone)::

    [explore]
    outputs = ["load_position_m", "A_pressure_bar"]   # plotted first (default below)
    duration = "1 s"                                  # the page's runs (default: the file's)

    [explore.parameters]                              # sliders: name = [low, high]
    "payload.mass" = ["10 kg", "400 kg"]              # any unit of the parameter's dimension
    "controller.proportional_gain" = []               # [] : the default range

Defaults: the sliders are `DEFAULT_SLIDERS` parameters the file sets itself (sweepable,
numbers, non-zero; not the pressure of the lowest tank, the return line), those named in
`PREFERRED` first, then in the file's order; a
slider's default range is its file value ÷ 4 to × 4 (within the parameter's rule). The
outputs plotted first are the angles and positions, then the node pressures (the columns
``hydroarm simulate --plot`` draws), that move in the file's run, at most
`DEFAULT_OUTPUTS`; every output may be chosen on the page.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..analysis.systems import SystemRunner, is_system_study
from ..errors import HydroarmError
from ..io.circuit import circuit_from_doc, parameter_of
from ..io.components import is_component_file
from ..io.sections import (
    as_table,
    check_run_size,
    did_you_mean,
    read_toml_file,
    reject_unknown_keys,
    time_value,
)
from ..io.servo_circuit import scenario_circuit, servo_circuit
from ..io.system import is_reference_file, is_system_file, system_of
from ..model.circuit import Circuit, build
from ..model.circuit_stepper import CircuitStepper
from ..plotting.design import display
from ..plotting.mechanism import stick_parents, stick_points
from .charts import rounded, time_panels
from .mechanism_task import SECTION, BlockTask, read_block_task, without_payload

EXPLORE_KEYS = {"parameters", "outputs", "duration"}
DEFAULT_SLIDERS = 6  # sliders shown without [explore] parameters
MAX_SLIDERS = 16
DEFAULT_OUTPUTS = 6  # outputs plotted first without [explore] outputs
MAX_OUTPUTS = 12  # outputs plotted at once
RANGE_FACTOR = 4.0  # a default range: the file's value ÷ 4 to × 4
SLIDER_STEPS = 200  # a slider's range in steps
MAX_POINTS = 600  # points of a curve sent to the browser (the records, evenly thinned)
POSE_FRAMES = 5  # stick figures of a mechanism drawn over the run (first to last)
#: parameter names shown first by default (what a user of a circuit turns first)
PREFERRED = (
    "mass",
    "inertia",
    "proportional_gain",
    "integral_gain",
    "derivative_gain",
    "pressure",
    "cracking_pressure",
    "spool_diameter",
    "flow_gain",
    "displacement",
    "speed",
    "viscous_friction",
    "area_a",
)
#: a parameter declared in any unit (a signal's gain: taken in SI base units) is shown so
ANY_UNIT = ("SI", 1.0)
#: what a file that opens no page is told
NOT_A_SYSTEM = (
    "neither an arm file ([joints]) nor a system file: a circuit ([[component]] entries, a "
    "[mechanism]), a component servo ([actuator], [valve], …), a reference file or a study "
    "naming one ([system] file = …)"
)
#: the output columns plotted first by default: those ``hydroarm simulate --plot`` draws
#: (the motion first, then the pressures)
DEFAULT_OUTPUT_ENDINGS = (("_angle_deg", "_position_m"), ("_pressure_bar",))


@dataclass(frozen=True)
class Slider:
    """A parameter on the page: its ``name`` (``<component>.<parameter>``), ``unit`` shown
    and ``factor`` (shown = SI × factor), ``low``, ``high``, ``step`` and the file's
    ``value`` [SI]."""

    name: str
    unit: str
    factor: float
    low: float
    high: float
    step: float
    value: float

    def shown(self, si: float) -> float:
        """A value [SI] in the shown unit."""
        return si * self.factor

    @property
    def heading(self) -> str:
        """``name [unit]`` (the page's label above its number field and slider)."""
        return f"{self.name} [{self.unit}]" if self.unit else self.name

    def within(self, si: float) -> float:
        """A value [SI] checked against the slider's range (a typed value; the slider's own
        are snapped to its steps, so a rounding beyond an end is taken back to it)."""
        slack = 1e-9 * (self.high - self.low)
        if not self.low - slack <= si <= self.high + slack:
            raise HydroarmError(
                self.name,
                f"{self.shown(si):.4g} is outside the slider's range {self.shown(self.low):.4g} "
                f"to {self.shown(self.high):.4g} {self.unit} ([explore] parameters sets it)",
            )
        return min(max(si, self.low), self.high)


# ------------------------------------------------------------------ the file ---
def is_arm_doc(doc: dict) -> bool:
    """Whether a parsed file is an arm file (``[joints]``; docs/arm.md)."""
    return "joints" in doc


def is_explorable(doc: dict) -> bool:
    """Whether a parsed file opens the system page: a system file
    (`hydroarm.io.system.is_system_file`) or a study naming one (``[system] file``:
    design, evaluate, fit, sensitivity files)."""
    return is_system_file(doc) or is_system_study(doc)


def system_file_kind(doc: dict) -> str:
    """``circuit``, ``mechanism``, ``component servo``, ``reference`` or ``study``."""
    if is_component_file(doc):
        return "component servo"
    if is_reference_file(doc):
        return "reference"
    if is_system_study(doc):
        return "study"
    return "mechanism" if "mechanism" in doc else "circuit"


def read_system(doc: dict, p: Path) -> tuple[Circuit, str]:
    """The circuit a parsed system file runs and a description of the file's kind: a
    circuit or a mechanism as it is; a component servo as its circuit
    (`hydroarm.io.servo_circuit.servo_circuit`, what ``hydroarm expand`` writes); a
    reference file or a study through the file it names (`hydroarm.io.system.system_of`,
    with the values beside ``file``)."""
    kind = system_file_kind(doc)
    if kind == "component servo":
        return servo_circuit(doc, p.parent, p.stem), "component servo (shown as its circuit)"
    if kind in ("reference", "study"):
        named = doc["system"]["file"]
        what = "reference to" if kind == "reference" else "the system of a study:"
        system = system_of("system", doc["system"], p.parent)
        if isinstance(system, Circuit):
            return system, f"{what} {named}"
        inner, _ = read_toml_file((p.parent / named).expanduser())
        if not is_component_file(inner):
            raise HydroarmError("system.file", "explore shows a servo the file names directly")
        circuit = scenario_circuit(
            system,
            as_table("valve", inner.get("valve", {})),
            as_table("supply", inner.get("supply", {})),
        )
        return circuit, f"{what} the component servo {named}"
    return circuit_from_doc(doc, p.stem, p.parent), kind


def _default_range(value: float, rule: str) -> tuple[float, float] | None:
    """The file's value ÷ 4 to × 4 (within an ``in [a, b]`` rule), or None (a zero value)."""
    if value == 0.0 or not math.isfinite(value):
        return None
    lo, hi = sorted((value / RANGE_FACTOR, value * RANGE_FACTOR))
    if rule.startswith("in ["):
        a, b = (float(v) for v in rule[4:].rstrip("]").split(","))
        lo, hi = max(lo, a), min(hi, b)
    return lo, hi


def _slider(runner: SystemRunner, name: str, low: float, high: float) -> Slider:
    value = runner.current(name)
    declared = parameter_of(name, runner.system, name).unit  # type: ignore[arg-type]
    unit, factor = ANY_UNIT if declared == "*" else display(runner.unit(name))
    step = (high - low) / SLIDER_STEPS
    return Slider(name, unit, factor, low, high, step, value)


def _file_values(circuit: Circuit) -> list[str]:
    """The parameters the file sets itself, in the file's order."""
    return [
        f"{c.name}.{k}"
        for c in circuit.components
        for k, v in c.values.items()
        if not isinstance(v, str)
    ]


def _return_tanks(circuit: Circuit) -> list[str]:
    """The tanks at the lowest pressure of the circuit's tanks (the return line)."""
    tanks = {
        c.name: float(c.values.get("pressure", math.nan))
        for c in circuit.components
        if c.type == "tank"
    }
    low = min(tanks.values(), default=math.nan)
    return [n for n, p in tanks.items() if p == low]


def default_sliders(runner: SystemRunner, circuit: Circuit) -> list[Slider]:
    """The sliders without ``[explore] parameters`` (module doc)."""
    sweepable = set(runner.compiled.sweepable) - {f"{n}.pressure" for n in _return_tanks(circuit)}
    ranked = []
    for order, name in enumerate(_file_values(circuit)):
        if name not in sweepable or runner.rule(name) == "integer":
            continue
        r = _default_range(runner.current(name), runner.rule(name))
        if r is None or not r[0] < r[1]:
            continue
        pname = name.split(".", 1)[1]
        rank = PREFERRED.index(pname) if pname in PREFERRED else len(PREFERRED)
        ranked.append((rank, order, name, r))
    ranked.sort()
    return [_slider(runner, n, *r) for _, _, n, r in ranked[:DEFAULT_SLIDERS]]


def read_sliders(field: str, table, runner: SystemRunner) -> list[Slider]:
    """``[explore.parameters]``: ``name = [low, high]`` (or ``[]``: the default range)."""
    table = as_table(field, table)
    if not table:
        raise HydroarmError(field, "is empty: name at least one parameter")
    if len(table) > MAX_SLIDERS:
        raise HydroarmError(field, f"{len(table)} parameters: at most {MAX_SLIDERS}")
    out = []
    for name, bounds in table.items():
        f = f"{field}.{name}"
        key = runner.key(f, name)
        if runner.rule(key) == "integer":
            raise HydroarmError(f, "is a choice or a whole number: the page's sliders set numbers")
        value = runner.current(key)
        if not isinstance(bounds, list) or len(bounds) not in (0, 2):
            raise HydroarmError(f, 'must be [low, high] (e.g. ["10 kg", "400 kg"]) or []')
        if not bounds:
            r = _default_range(value, runner.rule(key))
            if r is None:
                raise HydroarmError(f, "its value is 0: give its range, [low, high]")
            low, high = r
        else:
            low = runner.value(f"{f}[0]", key, bounds[0])
            high = runner.value(f"{f}[1]", key, bounds[1])
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise HydroarmError(f, "the low end must be below the high end, both finite")
        if not low <= value <= high:
            s = _slider(runner, key, low, high)
            raise HydroarmError(
                f,
                f"the file's value {s.shown(value):.4g} {s.unit} is outside the range "
                f"{s.shown(low):.4g} to {s.shown(high):.4g} {s.unit}".replace("  ", " "),
            )
        out.append(_slider(runner, key, low, high))
    return out


def read_outputs(field: str, value, known: list[str]) -> list[str]:
    """``[explore] outputs``: names of the run's columns (``hydroarm simulate --out``)."""
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise HydroarmError(field, 'must be a list of output names, e.g. ["A_pressure_bar"]')
    if len(value) > MAX_OUTPUTS:
        raise HydroarmError(field, f"{len(value)} outputs: at most {MAX_OUTPUTS} at once")
    for name in value:
        if name not in known:
            raise HydroarmError(field, f"{name!r}: no such output; {did_you_mean(name, known)}")
    return list(dict.fromkeys(value))


def default_outputs(columns: dict[str, np.ndarray]) -> list[str]:
    """The outputs plotted first without ``[explore] outputs`` (module doc): the angles and
    positions, then the node pressures, that move in the file's run ``columns`` (a tank's
    fixed pressure is left out), at most `DEFAULT_OUTPUTS`."""
    named = [k for endings in DEFAULT_OUTPUT_ENDINGS for k in columns if k.endswith(endings)]
    moving = [k for k in named if np.ptp(columns[k]) > 0.0]
    return (moving or named)[:DEFAULT_OUTPUTS]


class SystemModel:
    """A system file read and checked for the page, shared read-only by every visitor: the
    circuit it runs (with ``[explore] duration``), the sliders, the outputs that may be
    plotted and those plotted first, the file's own run."""

    def __init__(self, doc: dict, path: Path):
        doc = dict(doc)
        explore = as_table("explore", doc.get("explore", {}))
        reject_unknown_keys("explore", explore, EXPLORE_KEYS)
        circuit, self.kind = read_system(doc, path)
        if "duration" in explore:
            circuit = circuit.replace(
                duration=time_value("explore.duration", explore["duration"], positive=True)
            )
            check_run_size(
                circuit.duration,
                circuit.step,
                circuit.record_every,
                duration_field="explore.duration",
                record_field="explore.duration",
            )
        self.source = path.name
        self.circuit = circuit
        self.runner = SystemRunner(circuit)
        self.units = dict(self.runner.display_units)
        self.outputs = [k for k in self.units if k != "t_s"]
        if "parameters" in explore:
            self.sliders = read_sliders("explore.parameters", explore["parameters"], self.runner)
        else:
            self.sliders = default_sliders(self.runner, circuit)
        if "outputs" in explore:
            self.shown = read_outputs("explore.outputs", explore["outputs"], self.outputs)
        self.defaults = {
            "parameters": "parameters" not in explore,
            "outputs": "outputs" not in explore,
        }
        self.mechanism = self.runner.compiled.mechanism
        self.task = self._block_task(doc.get(SECTION))  # checked before the file's run
        self.columns = self.run({})
        # the live circuit: the file's, or without the payload a block task carries (its
        # start, the empty hand's equilibrium, solved and checked here, before the server)
        self.live_compiled = self.runner.compiled
        if self.task is not None:
            if self.task.removes and circuit.mechanism is not None:
                empty = without_payload(circuit.mechanism, self.task.removes)
                self.live_compiled = build(circuit.replace(mechanism=empty))
            CircuitStepper(self.live_compiled)  # the file's own run: refused here if it fails
        if "outputs" not in explore:
            self.shown = default_outputs(self.columns)

    def _block_task(self, table) -> BlockTask | None:
        """A mechanism's ``[block_task]`` (`mechanism_task`), or None."""
        if table is None:
            return None
        cc = self.runner.compiled
        if cc.mechanism is None or self.circuit.mechanism is None:
            raise HydroarmError(SECTION, "a block task needs a mechanism ([mechanism])")
        nh = len(cc.hydraulic)
        start = cc.s0[nh + np.asarray(cc.tree_nodes)]
        return read_block_task(table, self.circuit.mechanism, cc.mechanism, start, up_of(cc))

    @property
    def name(self) -> str:
        return self.circuit.name

    def slider(self, name: str) -> Slider:
        for s in self.sliders:
            if s.name == name:
                return s
        raise HydroarmError("parameter", f"{name!r} has no slider")

    def check(self, name: str, value: float) -> None:
        """Refuse a value [SI] outside the parameter's rule (one line)."""
        if not isinstance(value, int | float) or not math.isfinite(value):
            raise HydroarmError(name, f"must be a finite number, got {value!r}")
        problem = parameter_of(name, self.circuit, name).check(float(value))
        if problem:
            raise HydroarmError(name, problem)

    def run(self, values: dict[str, float]) -> dict[str, np.ndarray]:
        """The columns of a run with parameters ``values`` [SI] set (the file's run for an
        empty dict); a run that fails raises its one-line
        [`HydroarmError`][hydroarm.HydroarmError]."""
        system = self.runner.with_values(values) if values else self.circuit
        return self.runner.simulate_columns(system)

    def describe(self) -> str:
        c = self.circuit
        return (
            f"{self.source}: {self.kind} '{c.name}', {len(c.components)} components; "
            f"{c.method} at {c.step:.3g} s for {c.duration:g} s a run"
        )


def up_of(compiled) -> np.ndarray:
    """Up for a mechanism's views: against its gravity (world z where there is none)."""
    g = np.asarray(compiled.mechanism.tree.gravity, dtype=float)
    gn = float(np.linalg.norm(g))
    return -g / gn if gn > 0 and math.isfinite(gn) else np.array([0.0, 0.0, 1.0])


def load_system_model(path) -> SystemModel:
    """Read a system file for the page (module doc); every check before the server starts."""
    doc, p = read_toml_file(path)
    if not is_explorable(doc):
        raise HydroarmError("--config", f"{p.name}: {NOT_A_SYSTEM}")
    return SystemModel(doc, p)


# ------------------------------------------------------------ one visitor ---
class SystemExplorer:
    """One visitor's state of the system page: the sliders' values [SI], the outputs
    chosen, the last run's columns and its message (``error``: '' when the last run
    worked; the curves are then the last run that did), the number of runs and the last
    one's wall time ``run_s`` [s]."""

    def __init__(self, model: SystemModel):
        self.model = model
        self.values = {s.name: s.value for s in model.sliders}
        self.shown = list(model.shown)
        self.columns = model.columns  # the file's run, shared: never written to
        self.error = ""
        self.runs = 0
        self.run_s = 0.0  # wall time of the last run [s]

    def changed(self) -> dict[str, float]:
        """The values that differ from the file's [SI]."""
        return {
            s.name: self.values[s.name]
            for s in self.model.sliders
            if self.values[s.name] != s.value
        }

    def set(self, name: str, shown_value: float) -> None:
        """Set a slider to ``shown_value`` (in its shown unit); a value outside the
        parameter's rule or the slider's range is refused
        ([`HydroarmError`][hydroarm.HydroarmError]) and the setting kept."""
        s = self.model.slider(name)
        if isinstance(shown_value, bool) or not isinstance(shown_value, int | float):
            raise HydroarmError(name, f"must be a number, got {shown_value!r}")
        value = float(shown_value) / s.factor
        self.model.check(name, value)
        self.values[name] = s.within(value)

    def run(self) -> bool:
        """Run the system with the values set: True if it ran; else ``error`` holds the
        run's one-line message and the last run's curves stay."""
        self.runs += 1
        t0 = time.perf_counter()
        try:
            self.columns = self.model.run(self.changed())
        except HydroarmError as exc:
            self.error = f"the run failed: {exc}; the curves are of the last run that worked"
            return False
        finally:
            self.run_s = time.perf_counter() - t0
        self.error = ""
        return True

    def update(self, name: str, shown_value: float) -> bool:
        """`set` then `run` (what a slider's change does, on a thread)."""
        self.set(name, shown_value)
        return self.run()

    def choose(self, outputs: list[str]) -> None:
        """The outputs to plot (names of `SystemModel.outputs`)."""
        self.shown = read_outputs("outputs", list(outputs), self.model.outputs)

    # what the page shows -----------------------------------------------------------
    def summary_rows(self) -> list[dict]:
        """Per output plotted: its unit, value at the end, least and greatest."""
        rows = []
        for name in self.shown:
            v = self.columns[name]
            rows.append(
                {
                    "output": name,
                    "unit": self.model.units[name],
                    "final": f"{v[-1]:.5g}",
                    "min": f"{np.min(v):.5g}",
                    "max": f"{np.max(v):.5g}",
                }
            )
        return rows

    def chart(self) -> dict:
        """ECharts options of the outputs plotted against time: one panel per unit (its
        y axis named by it), at most `MAX_POINTS` points a curve; data only."""
        cols = self.columns
        groups: dict[str, list[str]] = {}
        for name in self.shown:
            groups.setdefault(self.model.units[name] or "–", []).append(name)
        panels = [(unit, [(n, cols[n]) for n in names]) for unit, names in groups.items()]
        curves = time_panels(
            cols["t_s"],
            panels,
            top=60,
            height=150,
            step=200,
            time_name="t [s]",
            max_points=MAX_POINTS,
        )
        return {
            "animation": False,
            "legend": {"type": "scroll", "top": 0},
            "tooltip": {"trigger": "axis"},
            **curves,
        }

    def chart_height(self) -> int:
        """The chart's height [px] for the panels shown."""
        n = max(1, len({self.model.units[k] or "–" for k in self.shown}))
        return 60 + n * 200

    def pose(self) -> dict | None:
        """ECharts options of a mechanism's stick figure in the side view (x across, z up)
        at `POSE_FRAMES` times from the run's start (light) to its end (dark), or
        None for a circuit without a mechanism."""
        mech = self.model.mechanism
        if mech is None:
            return None
        cols = self.columns
        q = np.column_stack(
            [
                np.radians(cols[f"{n}_angle_deg"])
                if f"{n}_angle_deg" in cols
                else cols[f"{n}_position_m"]
                for n in mech.joint_names
            ]
        )
        rows = np.unique(np.linspace(0, len(q) - 1, POSE_FRAMES).astype(int))
        points = stick_points(mech, q[rows])
        parents = stick_parents(mech)
        lo = np.min(points, axis=(0, 1))
        hi = np.max(points, axis=(0, 1))
        span = max(hi[0] - lo[0], hi[2] - lo[2], 1e-3) * 0.55
        cx, cz = (hi[0] + lo[0]) / 2, (hi[2] + lo[2]) / 2
        series = []
        t = cols["t_s"]
        for f, r in enumerate(rows):
            shade = int(200 - 170 * f / max(1, len(rows) - 1))
            colour = f"rgb({shade},{shade},{min(255, shade + 40)})"
            segs = [
                {"coords": [[_r(points[f, j, 0]), _r(points[f, j, 2])],
                            [_r(points[f, k, 0]), _r(points[f, k, 2])]]}
                for k, j in enumerate(parents)
                if j >= 0
            ]  # fmt: skip
            series.append(
                {
                    "name": f"t = {t[r]:.2f} s",
                    "type": "lines",
                    "coordinateSystem": "cartesian2d",
                    "lineStyle": {"color": colour, "width": 4},
                    "data": segs,
                }
            )
        return {
            "animation": False,
            "title": {"text": "pose (side view)", "textStyle": {"fontSize": 12}},
            "legend": {"bottom": 0, "type": "scroll"},
            "grid": {"left": 56, "right": 16, "top": 32, "bottom": 72},
            "xAxis": _pose_axis("x [m]", cx, span),
            "yAxis": _pose_axis("z [m]", cz, span),
            "series": series,
        }


def _pose_axis(name: str, centre: float, span: float) -> dict:
    """An axis of the pose's square view, its ends unlabelled (they are not round)."""
    return {
        "type": "value",
        "name": name,
        "nameLocation": "middle",
        "nameGap": 28,
        "min": _r(centre - span),
        "max": _r(centre + span),
        "axisLabel": {"showMinLabel": False, "showMaxLabel": False},
    }


_r = rounded
