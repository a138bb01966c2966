"""Design studies and evaluation cards of any system (issue 29; docs/design.md "Any system",
docs/evaluate.md "Any system").

A study names its system by file, ``[system] file = "servo.toml"`` (:func:`hydroarm.io.
system.system_of`: a circuit, a mechanism or a fixed-shape component servo; fields beside
``file`` override the file's). Its requirements bound statistics of the system's named
outputs, the columns ``hydroarm simulate --out`` writes (``pressure_a_bar``, ``jack_flow_lpm``,
``load_position_m`` …), with the statistics of :mod:`hydroarm.metrics.trace` and a limit
with its unit::

    [requirements]
    settling = { output = "position_m", statistic = "settling_time", after = "1 s",
                 limit = "<= 0.6 s" }
    peak_a = { output = "pressure_a_bar", statistic = "max", limit = "<= 60 bar" }

A limit is read in the statistic's unit: the output's (any unit of its dimension: psi for
a pressure in bar), seconds for a time, percent for the overshoot. ``[metrics]`` (the same
tables without ``limit``) adds quantities to measure and to name in objectives.

:class:`SystemDesignStudy` varies the system's parameters (``[design.variables]``: a
circuit's ``<component>.<parameter>``, a component servo's sweep names, bounds in the
parameter's declared unit) with the joint's search (:func:`hydroarm.analysis.design.search`:
scrambled Sobol designs, differential evolution on one objective, the Pareto front), every
batch of candidates on the system's batch engine (a circuit's
:func:`~hydroarm.model.circuit.simulate_many`, a servo's
:func:`~hydroarm.integrators.servo.run_many`); a candidate's metrics are those of the same
system run alone by ``hydroarm simulate``. :class:`SystemEvaluation` is the card of one
system: one ``simulate`` run, each requirement's value, limit, margin.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..batch.circuit_sweep import (
    TraceMetric,
    circuit_chunk_columns,
    read_metrics,
    run_circuit_chunk,
)
from ..batch.servo_sweep import check_servo_changes
from ..errors import HydroarmError
from ..files import atomic_write_text, check_output_folder, csv_text, move_into, staging_folder
from ..integrators import registry, stability
from ..integrators.servo import run_many as run_servo_many
from ..io.circuit import parameter_of, parameter_value
from ..io.components import sweep_dimension, sweep_rule, sweep_targets
from ..io.sections import (
    as_table,
    parse_toml,
    read_text_file,
    reject_unknown_keys,
    require_table,
    text_value,
    within,
)
from ..io.system import (
    System,
    is_system_file,
    servo_parameter_name,
    servo_value,
    servo_with,
    system_of,
)
from ..io.units import SI_UNITS, value_in
from ..metrics.trace import STATISTICS
from ..model.circuit import (
    Circuit,
    CircuitResult,
    build,
    row_initial_states,
)
from ..model.circuit import (
    simulate as simulate_circuit,
)
from ..model.servo import ServoResult, ServoScenario
from ..plotting.design import display
from ..plotting.evaluate import fig_card
from ..plotting.joint import save_figure
from .design import (
    DesignEvaluation,
    DesignResult,
    Objective,
    Refine,
    Variable,
    read_search,
    read_variable,
    search,
)
from .requirements import comparison, sense_of

SECTIONS = {"name", "description", "system", "requirements", "metrics", "design"}
EVALUATE_SECTIONS = {"name", "description", "system", "requirements", "metrics"}
DESIGN_KEYS = {"samples", "seed", "variables", "objectives", "refine", "chunk"}
MAX_BLOCK_BYTES = 64 * 2**20  # recorded states of a servo batch held at once
#: the budget of a design: integration steps over every candidate (Sobol and refinement)
MAX_DESIGN_STEPS = 2 * 10**11
OUTPUT_FILES = ("designs.csv", "pareto.png", "feasibility.png", "design_report.md")
CARD_FILES = ("card.csv", "card.md", "card.png")
CARD_COLUMNS = [
    "quantity",
    "output",
    "statistic",
    "value",
    "unit",
    "requirement",
    "limit",
    "met",
    "margin",
]
# a servo column's unit (pint) -> the suffix of a metric's column (as a circuit's outputs)
_SERVO_SUFFIX = {"m/s": "m_s", "deg/s": "deg_s", "L/min": "lpm", "m**3/s/Pa**0.5": ""}


# ----------------------------------------------------------------- the system ---
class SystemRunner:
    """What a study does with its system: its outputs and their units, its parameters by
    name, and runs of many parameter sets on the system's batch engine."""

    def __init__(self, system: System):
        self.system = system
        self.circuit = isinstance(system, Circuit)
        if self.circuit:
            assert isinstance(system, Circuit)
            self.compiled = build(system)
            res = CircuitResult(
                self.compiled, np.zeros(1), self.compiled.s0[None, :], -1, self.compiled.P
            )
            self.display_units = res.display_units()
            self.suffixes = res.units()
        else:
            assert isinstance(system, ServoScenario)
            res_s = ServoResult(
                system, np.zeros(1), system.initial_state()[None, :], system.reference(np.zeros(1))
            )
            self.display_units = res_s.display_units()
            self.suffixes = {k: _SERVO_SUFFIX.get(u, u) for k, u in self.display_units.items()}

    @property
    def kind(self) -> str:
        return "circuit" if self.circuit else "component servo"

    @property
    def name(self) -> str:
        return self.system.name

    @property
    def nsteps(self) -> int:
        return int(round(self.system.duration / self.system.step))

    def describe(self) -> str:
        s = self.system
        return (
            f"the {self.kind} '{s.name}' ({s.method} at {s.step:.3g} s for {s.duration:g} s "
            "per run)"
        )

    # ------------------------------------------------------------ parameters ---
    def key(self, field: str, name: str) -> str:
        """The internal name of a parameter as a study writes it."""
        if self.circuit:
            assert isinstance(self.system, Circuit)
            parameter_of(field, self.system, name)
            if name not in self.compiled.sweepable:
                raise HydroarmError(field, "is not a parameter a study may vary")
            return name
        return servo_parameter_name(field, name)

    def value(self, field: str, key: str, value) -> float:
        """A value [SI] of the parameter ``key`` read with its declared unit and rule."""
        if self.circuit:
            assert isinstance(self.system, Circuit)
            return parameter_value(field, self.system, key, value)
        assert isinstance(self.system, ServoScenario)
        return servo_value(field, self.system, key, value)

    def unit(self, key: str) -> str:
        """The SI unit of a parameter (as :mod:`hydroarm.io.units` writes it)."""
        if self.circuit:
            assert isinstance(self.system, Circuit)
            u = parameter_of(key, self.system, key).unit
            return "" if u == "*" else u
        assert isinstance(self.system, ServoScenario)
        return _servo_unit(self.system, key)

    def check(self, field: str, keys: list[str], row) -> None:
        """Refuse one set of values [SI] (the rules of each parameter, and a servo's cross
        rules), naming ``field``."""
        if self.circuit:
            assert isinstance(self.system, Circuit)
            for k, v in zip(keys, row, strict=True):
                problem = parameter_of(field, self.system, k).check(float(v))
                if problem:
                    raise HydroarmError(field, f"{k} = {v:.6g}: {problem}")
            return
        assert isinstance(self.system, ServoScenario)
        try:
            check_servo_changes(self.system, dict(zip(keys, map(float, row), strict=True)))
        except HydroarmError as exc:
            raise HydroarmError(field, str(exc)) from None

    def with_values(self, values: dict[str, float]) -> System:
        """The system with parameters set (internal names, SI): what ``simulate`` runs."""
        if isinstance(self.system, Circuit):
            return self.system.with_values(values)
        return servo_with(self.system, values)

    # ------------------------------------------------------------------ runs ---
    def run(self, keys: list[str], x: np.ndarray, metrics) -> np.ndarray:
        """``[failed, metric…]`` of each row of values ``x`` (SI) on the batch engine."""
        x = np.atleast_2d(np.asarray(x, float))
        if isinstance(self.system, Circuit):
            cc = self.compiled
            table = np.repeat(cc.P[None, :], len(x), axis=0)
            for i, k in enumerate(keys):
                table[:, cc.parameter_index[k]] = x[:, i]
            S0 = row_initial_states(cc, keys, x, table)
            return run_circuit_chunk(self.system, table, S0, metrics)
        scs = [servo_with(self.system, dict(zip(keys, row, strict=True))) for row in x]
        return run_servo_chunk(scs, metrics)

    def columns_many(self, keys: list[str], x: np.ndarray) -> list[dict | None]:
        """The columns ``hydroarm simulate --out`` writes of each row of values ``x`` (SI),
        run together on the batch engine as :meth:`run` runs them (None: the run failed)."""
        x = np.atleast_2d(np.asarray(x, float))
        out: list[dict | None] = [None] * len(x)
        if isinstance(self.system, Circuit):
            cc = self.compiled
            table = np.repeat(cc.P[None, :], len(x), axis=0)
            for i, k in enumerate(keys):
                table[:, cc.parameter_index[k]] = x[:, i]
            S0 = row_initial_states(cc, keys, x, table)
            rows = circuit_chunk_columns(cc, table, S0)
        else:
            scs = [servo_with(self.system, dict(zip(keys, row, strict=True))) for row in x]
            rows = servo_chunk_columns(scs)
        for i, cols in rows:
            out[i] = cols
        return out

    def current(self, key: str) -> float:
        """The system's value [SI] of a parameter (internal name; a convenience name of a
        servo: its first target's)."""
        if isinstance(self.system, Circuit):
            return float(self.compiled.P[self.compiled.parameter_index[key]])
        return float(self.system.parameters[sweep_targets(key)[0]])

    def rule(self, key: str) -> str:
        """A parameter's sign rule: ``positive``, ``nonnegative``, ``in [a, b]``, ``integer``
        (a whole number or a choice), or ``any``."""
        if isinstance(self.system, Circuit):
            p = parameter_of(key, self.system, key)
            r = p.rule.strip()
            if p.choices or r.startswith("integer"):
                return "integer"
            if r.startswith("in ["):
                return r
            return {"> 0": "positive", ">= 0": "nonnegative"}.get(r, "any")
        return sweep_rule(key)

    def simulate_columns(self, system: System | None = None) -> dict[str, np.ndarray]:
        """The columns ``hydroarm simulate --out`` writes for ``system`` (default: the
        study's): the same run."""
        s = self.system if system is None else system
        if isinstance(s, Circuit):
            res = simulate_circuit(s)
            if res.bad_step >= 0:
                raise HydroarmError(
                    "system.step",
                    f"the run left finite numbers at step {res.bad_step} "
                    f"(t = {res.bad_step * s.step:.4g} s); reduce the step",
                )
            return res.columns()
        return s.run().columns()


def _servo_unit(servo: ServoScenario, key: str) -> str:
    """The SI unit of a servo parameter (its sweep dimension)."""
    if key == "spool_frequency":
        return "rad/s"
    return SI_UNITS.get(sweep_dimension(key, servo.parameters), "")


def run_servo_chunk(scenarios: list[ServoScenario], metrics) -> np.ndarray:
    """``[failed, metric…]`` of servos that differ only in parameters, on the servo batch
    engine (:func:`servo_chunk_columns`). A row whose step is above its stable limit, or
    whose run left finite numbers, fails (NaN metrics)."""
    out = np.full((len(scenarios), 1 + len(metrics)), math.nan)
    for i, cols in servo_chunk_columns(scenarios):
        out[i, 0] = float(cols is None)
        if cols is None:
            continue
        for k, m in enumerate(metrics):
            out[i, 1 + k] = m.of(cols)
    return out


def servo_chunk_columns(scenarios: list[ServoScenario]):
    """``(row, columns)`` of servos that differ only in parameters, run on the servo batch
    engine (:func:`hydroarm.integrators.servo.run_many`) in blocks whose recorded states fit
    :data:`MAX_BLOCK_BYTES`: the columns ``hydroarm simulate --out`` writes, or None for a
    row whose step is above its stable limit or whose run left finite numbers."""
    n = len(scenarios)
    if not n:
        return
    first = scenarios[0]
    code = registry.method(first.method).code
    ref = first.reference
    r0 = float(ref(0.0)[0])
    table = np.array([sc.vector() for sc in scenarios])
    S0 = np.array([sc.initial_state() for sc in scenarios])
    stable = np.array(
        [
            stability.servo_step_limit(first.method, first.step, S0[i], r0, table[i]) is None
            for i in range(n)
        ]
    )
    for i in np.nonzero(~stable)[0]:
        yield int(i), None
    rows = np.nonzero(stable)[0]
    records = first.nsteps // first.record_every + 1
    block = max(1, MAX_BLOCK_BYTES // max(1, records * S0.shape[1] * 8))
    for lo in range(0, len(rows), block):
        part = rows[lo : lo + block]
        t, S, bad = run_servo_many(
            code,
            S0[part],
            0.0,
            first.step,
            first.nsteps,
            first.record_every,
            ref.times,
            ref.positions,
            ref.sine,
            table[part],
        )
        r = ref(t)
        for j, i in enumerate(part):
            if bad[j] >= 0:
                yield int(i), None
                continue
            yield int(i), ServoResult(scenarios[i], t, S[j], r).columns()


# ---------------------------------------------------------------- requirements ---
@dataclass(frozen=True)
class OutputRequirement:
    """``metric`` (a statistic of a named output) must stay at most (``sense`` "max") or
    at least ("min") ``limit``, in ``unit`` (the statistic's: the output's display unit,
    ``s`` or ``percent``)."""

    name: str
    trace: TraceMetric
    limit: float
    sense: str
    unit: str
    label: str

    @property
    def metric(self) -> str:
        return self.name

    def met_by(self, value: float) -> bool:
        if math.isnan(value):
            return False
        return value <= self.limit if self.sense == "max" else value >= self.limit

    def margin(self, value: float) -> float:
        """Signed fraction of the limit (> 0 met): (limit − value)/|limit| for "max"."""
        if math.isnan(value):
            return -math.inf
        d = self.limit - value if self.sense == "max" else value - self.limit
        if self.limit == 0:
            return math.copysign(math.inf, d) if d else 0.0
        return d / abs(self.limit)


def statistic_display_unit(statistic: str, output_unit: str) -> str:
    """The unit (pint's syntax) of a statistic's value: the output's, ``s``, ``percent``."""
    kind = STATISTICS[statistic][0]
    if kind == "same":
        return output_unit
    if kind == "same*s":
        return f"({output_unit})*s" if output_unit else "s"
    return {"pct": "percent"}.get(kind, kind)


def read_output_requirements(
    field: str, table, runner: SystemRunner
) -> tuple[OutputRequirement, ...]:
    """The ``[requirements]`` of a study of a system (module doc)."""
    table = as_table(field, table)
    if not table:
        raise HydroarmError(field, "is empty: give at least one requirement")
    specs, limits = {}, {}
    for name, spec in table.items():
        spec = dict(as_table(f"{field}.{name}", spec))
        if "limit" not in spec:
            raise HydroarmError(f"{field}.{name}.limit", 'is missing (e.g. limit = "<= 60 bar")')
        limits[name] = spec.pop("limit")
        specs[name] = spec
    traces = read_metrics(field, specs, runner.suffixes)
    out = []
    for m in traces:
        f = f"{field}.{m.name}.limit"
        raw = limits[m.name]
        if not isinstance(raw, str):
            raise HydroarmError(
                f, f'must be a comparison and a limit, e.g. "<= 60 bar", got {raw!r}'
            )
        cmp, rest = comparison(f, raw)
        if cmp is None:
            raise HydroarmError(f, f'{raw!r}: give the comparison, e.g. "<= {rest}"')
        unit = statistic_display_unit(m.statistic, runner.display_units[m.output])
        limit = value_in(f, rest.replace("%", " percent"), unit)
        if not math.isfinite(limit):
            raise HydroarmError(f, f"{raw!r}: must be finite")
        label = f"{m.name}: {m.statistic} of {m.output} {cmp} {rest}"
        out.append(OutputRequirement(m.name, m, limit, sense_of(cmp), unit, label))
    return tuple(out)


def read_extra_metrics(doc: dict, runner: SystemRunner, taken) -> tuple[TraceMetric, ...]:
    """``[metrics]``: statistics to measure besides the requirements' (no limit)."""
    if "metrics" not in doc:
        return ()
    metrics = read_metrics("metrics", doc["metrics"], runner.suffixes)
    for m in metrics:
        if m.name in taken:
            raise HydroarmError(f"metrics.{m.name}", "is also a requirement's name")
    return metrics


def study_system(doc: dict, base_dir: Path) -> tuple[System, SystemRunner]:
    """The ``[system]`` of a study file, checked for a study: a fixed-step method, a stable
    step for a servo."""
    system = system_of("system", require_table(doc, "system"), base_dir)
    if not registry.method(system.method).fixed_step:
        raise HydroarmError(
            "system.method",
            f"a study runs the fixed-step methods ({', '.join(registry.fixed_step_methods())})",
        )
    if isinstance(system, ServoScenario):
        with within("system"):
            system.check_step()
    return system, SystemRunner(system)


# --------------------------------------------------------------------- design ---
@dataclass(frozen=True)
class SystemDesignStudy:
    """A design study of any system (module doc)."""

    name: str
    runner: SystemRunner
    requirements: tuple[OutputRequirement, ...]
    extra: tuple[TraceMetric, ...]
    variables: tuple[Variable, ...]
    keys: tuple[str, ...]  # the variables' internal names
    objectives: tuple[Objective, ...]
    samples: int = 256
    seed: int = 0
    refine: Refine | None = None
    chunk: int = 32

    @property
    def metrics(self) -> tuple[TraceMetric, ...]:
        return (*(r.trace for r in self.requirements), *self.extra)

    @property
    def step(self) -> float:
        return self.runner.system.step

    def values(self, x_row) -> dict[str, float]:
        """A design's values by internal name (SI)."""
        return {k: float(v) for k, v in zip(self.keys, x_row, strict=True)}

    def system_of(self, x_row) -> System:
        """The system of one design: what ``hydroarm simulate`` runs for it."""
        return self.runner.with_values(self.values(x_row))

    def evaluate(self, x: np.ndarray, source: str = "sobol", progress=None) -> DesignEvaluation:
        """Designs ``x`` (rows, SI) on the system's batch engine, ``chunk`` a batch."""
        x = np.atleast_2d(np.asarray(x, float))
        metrics = self.metrics
        M = np.full((len(x), 1 + len(metrics)), math.nan)
        for lo in range(0, len(x), self.chunk):
            hi = min(lo + self.chunk, len(x))
            M[lo:hi] = self.runner.run(list(self.keys), x[lo:hi], metrics)
            if progress is not None:
                progress(f"design: {hi}/{len(x)} designs evaluated ({source})")
        per = [
            {m.name: float(M[i, 1 + j]) for j, m in enumerate(metrics)} | {"failed": M[i, 0] > 0.5}
            for i in range(len(x))
        ]
        reqs = self.requirements
        w = np.array([[p[r.name] for r in reqs] for p in per]).reshape(len(x), len(reqs))
        margins = np.array(
            [[r.margin(float(v)) for r, v in zip(reqs, row, strict=True)] for row in w]
        ).reshape(len(x), len(reqs))
        obj = np.array(
            [
                [self.objective_value(o, x[i], per[i]) for o in self.objectives]
                for i in range(len(x))
            ]
        ).reshape(len(x), len(self.objectives))
        steps = np.full(len(x), self.step)
        return DesignEvaluation(x, steps, per, w, margins, obj, [source] * len(x))

    def objective_value(self, o: Objective, x_row, metrics: dict) -> float:
        names = [v.name for v in self.variables]
        if o.name in names:
            return float(x_row[names.index(o.name)])
        return float(metrics.get(o.name, math.nan))

    def unit_of(self, name: str) -> str:
        """The unit of a metric or variable named in an objective."""
        for v in self.variables:
            if v.name == name:
                return v.unit
        for r in self.requirements:
            if r.name == name:
                return r.unit
        for m in self.extra:
            if m.name == name:
                return statistic_display_unit(m.statistic, self.runner.display_units[m.output])
        return ""


def read_system_design(doc: dict, name: str, base_dir: Path, *, samples=None, refine=None):
    """A :class:`SystemDesignStudy` from a parsed design file with ``[system] file``; every
    value checked (the variables' bounds at every corner of the design space, the budget)
    before any run."""
    reject_unknown_keys("", doc, SECTIONS)
    system, runner = study_system(doc, base_dir)
    reqs = read_output_requirements("requirements", require_table(doc, "requirements"), runner)
    extra = read_extra_metrics(doc, runner, {r.name for r in reqs})
    keys: list[str] = []

    def variable(f: str, k: str, value) -> Variable:
        key = runner.key(f, k)
        if key in keys:
            raise HydroarmError(f, f"sets {key}, which another variable sets")
        keys.append(key)
        return read_variable(f, k, value, lambda f2, v: runner.value(f2, key, v), runner.unit(key))

    d = require_table(doc, "design")
    s = read_search(
        d, variable, [*(r.name for r in reqs), *(m.name for m in extra)], keys=DESIGN_KEYS,
        samples=samples,
    )  # fmt: skip
    if refine is False:
        s["refine"] = None
    variables = s["variables"]
    # every corner of the design space against the parameters' rules (one-line errors)
    lows = np.array([v.low for v in variables])
    highs = np.array([v.high for v in variables])
    for c in range(2 ** min(len(variables), 10)):
        corner = np.where([(c >> i) & 1 for i in range(len(variables))], highs, lows)
        runner.check("design.variables", keys, corner)
    ref = s["refine"]
    runs = s["samples"] + (0 if ref is None else (ref.generations + 1) * ref.population)
    if runs * runner.nsteps > MAX_DESIGN_STEPS:
        raise HydroarmError(
            "design.samples",
            f"{runs} runs of {runner.nsteps:,} steps is more than {MAX_DESIGN_STEPS:.0e} "
            "steps in all: fewer samples or generations, or a shorter system.duration",
        )
    return SystemDesignStudy(
        name=text_value("name", doc.get("name", name)),
        runner=runner,
        requirements=reqs,
        extra=extra,
        keys=tuple(keys),
        **s,
    )


@dataclass
class SystemDesignResult(DesignResult):
    """The designs of a system: the joint's tables, plots and report, without load cases."""

    study: SystemDesignStudy  # type: ignore[assignment]

    @property
    def scenarios(self) -> int:
        return len(self.evaluation.x)

    def throughput(self) -> float:
        """Designs (runs) per second, start-up included."""
        return len(self.evaluation.x) / self.elapsed_s

    def failed(self) -> int:
        return sum(bool(m.get("failed")) for m in self.evaluation.metrics)

    def _objective_labels(self) -> tuple[dict, dict]:
        s, e = self.study, self.evaluation
        vals, labels = {}, {}
        objs = list(s.objectives) or [Objective("max", "smallest_margin")]
        for k, o in enumerate(objs):
            if o.name == "smallest_margin":
                vals[o.name] = e.smallest_margin
                labels[o.name] = ("smallest margin", "")
                continue
            vals[o.name] = e.objectives[:, k]
            labels[o.name] = (f"{o.name} ({o.sense})", s.unit_of(o.name))
        return vals, labels

    def recommended_values(self, i: int) -> str:
        """A design's values as a study file writes them (``name = "value unit"``)."""
        out = []
        for k, v in enumerate(self.study.variables):
            u, f = display(v.unit)
            out.append(f"{v.name} = {self.evaluation.x[i, k] * f:.6g} {u}".rstrip())
        return ", ".join(out)

    def report(self) -> str:
        s, e = self.study, self.evaluation
        n = len(e.x)
        nf = int(self.feasible.sum())
        lines = [
            f"# Design study: {s.name}",
            "",
            f"System: {s.runner.describe()}. {n} designs ({s.samples} scrambled Sobol points, "
            f"seed {s.seed}"
            + (f", {n - s.samples} from the refinement" if n > s.samples else "")
            + f"), every one run on the batch engine; {self.failed()} failed (left the "
            f"physical bounds or above the stable step); {nf} feasible, "
            f"{int(self.pareto.sum())} on the Pareto front.",
            "",
            f"Time: {self.elapsed_s:.2f} s in all ({self.evaluation_s:.2f} s evaluating); "
            f"{self.throughput():.3g} designs per second.",
            "",
            "## Requirements",
            "",
        ]
        lines += [f"- `{r.label}`" for r in s.requirements]
        rec = self._variables_and_recommendation(
            lines, "Re-run one with `hydroarm simulate` on the system file with its values."
        )
        vu = [display(v.unit) for v in s.variables]
        head = ["design"] + [
            f"{v.name} [{u}]" if u else v.name for v, (u, _) in zip(s.variables, vu, strict=True)
        ]
        head += [f"{r.name} [{r.unit}]" if r.unit else r.name for r in s.requirements]
        head += [f"margin {r.name}" for r in s.requirements]
        lines += ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
        for i in rec:
            cells = [str(i + 1)] + [f"{v * f:.4g}" for v, (_, f) in zip(e.x[i], vu, strict=True)]
            cells += [f"{v:.4g}" for v in e.worst[i]]
            cells += [f"{m:+.3f}" for m in e.margins[i]]
            lines.append("| " + " | ".join(cells) + " |")
        if s.refine is not None:
            ref = s.refine
            src = np.array(e.source)
            lines += ["", "## Refinement", ""]
            lines.append(
                f"Differential evolution ({ref.generations} generations, population "
                f"{ref.population}, seed {ref.seed}) on `{ref.objective.label}`, feasibility as "
                f"a penalty: {int((src == 'refine').sum())} designs evaluated."
            )
        lines += ["", "![Pareto front](pareto.png)", "", "![Feasibility](feasibility.png)", ""]
        return "\n".join(lines)


def run_system_design(
    study: SystemDesignStudy, out=None, progress=None, *, t0: float | None = None
) -> SystemDesignResult:
    """Search the designs of a system (the joint's search) and write ``out``."""
    start = time.perf_counter() if t0 is None else t0
    ev, pareto, evaluation_s = search(study, progress)
    res = SystemDesignResult(study, ev, pareto, time.perf_counter() - start, evaluation_s)
    if out is not None:
        res.write(out)
    return res


# ------------------------------------------------------------------- evaluate ---
@dataclass(frozen=True)
class SystemEvaluation:
    """The card of a system: its requirements and measured metrics on one run."""

    name: str
    runner: SystemRunner
    requirements: tuple[OutputRequirement, ...]
    extra: tuple[TraceMetric, ...] = ()


def read_system_evaluation(doc: dict, name: str, base_dir: Path) -> SystemEvaluation:
    reject_unknown_keys("", doc, EVALUATE_SECTIONS)
    _, runner = study_system(doc, base_dir)
    if "requirements" not in doc and "metrics" not in doc:
        raise HydroarmError("requirements", "is missing (give [requirements] or [metrics])")
    reqs = (
        read_output_requirements("requirements", doc["requirements"], runner)
        if "requirements" in doc
        else ()
    )
    extra = read_extra_metrics(doc, runner, {r.name for r in reqs})
    return SystemEvaluation(text_value("name", doc.get("name", name)), runner, reqs, extra)


@dataclass
class SystemCard:
    """The card of one system: ``rows`` (one per requirement and metric, :data:`CARD_COLUMNS`)
    and the run's columns."""

    evaluation: SystemEvaluation
    rows: list
    elapsed_s: float = 0.0
    columns: dict = field(default_factory=dict)

    def value(self, name: str) -> float:
        for r in self.rows:
            if r["quantity"] == name:
                return r["value"]
        raise KeyError(name)

    def all_met(self) -> bool:
        return all(r["met"] for r in self.rows if r["met"] is not None)

    def csv(self) -> str:
        return csv_text(CARD_COLUMNS, self.rows)

    def lines(self) -> list[str]:
        """The terminal's lines: one per quantity."""
        out = []
        for r in self.rows:
            req = ""
            if r["requirement"]:
                met = "met" if r["met"] else "NOT met"
                req = f"  [{met}: {r['requirement']}, margin {r['margin']:+.3f}]"
            out.append(f"{r['quantity']:<24} {r['value']:.6g} {r['unit']}{req}")
        return out

    def markdown(self) -> str:
        ev = self.evaluation
        lines = [
            f"# Evaluation card: {ev.name}",
            "",
            f"System: {ev.runner.describe()}; one `hydroarm simulate` run, computed in "
            f"{self.elapsed_s:.2f} s. What each number is: docs/evaluate.md.",
            "",
            "| quantity | statistic of output | value | unit | requirement | met | margin |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in self.rows:
            met = "" if r["met"] is None else ("yes" if r["met"] else "**no**")
            margin = "" if r["margin"] is None else f"{r['margin']:+.3f}"
            lines.append(
                f"| {r['quantity']} | {r['statistic']} of `{r['output']}` | {r['value']:.5g} "
                f"| {r['unit']} | {r['requirement']} | {met} | {margin} |"
            )
        lines += ["", "![the card's numbers against the requirements](card.png)", ""]
        return "\n".join(lines)

    def figure(self):
        panels = []
        for r in self.rows:
            p: dict = {
                "quantity": f"{r['quantity']}: {r['statistic']} of {r['output']}",
                "unit": r["unit"],
                "labels": [self.evaluation.runner.name],
                "values": [r["value"]],
            }
            if r["limit"] is not None:
                p["limit"] = r["limit"]
                p["sense"] = r["sense"]
            panels.append(p)
        return fig_card(panels, title=f"{self.evaluation.name}")

    def write(self, out) -> Path:
        """``card.csv``, ``card.md`` and ``card.png`` into ``out`` (staged, then moved)."""
        folder = check_output_folder("--out", out)
        with staging_folder(folder) as stage:
            atomic_write_text(stage / "card.csv", self.csv())
            atomic_write_text(stage / "card.md", self.markdown())
            save_figure(self.figure(), stage / "card.png")
            move_into(stage, folder, CARD_FILES)
        return folder


def evaluate_system(ev: SystemEvaluation, out=None, progress=None) -> SystemCard:
    """The card of a system: its run as ``hydroarm simulate`` makes it, each requirement's
    statistic of it (:mod:`hydroarm.metrics.trace`), the limit and the margin."""
    tick = progress or (lambda label: None)
    t0 = time.perf_counter()
    tick(f"evaluate: simulating {ev.runner.describe()}")
    cols = ev.runner.simulate_columns()
    rows = []
    for r in ev.requirements:
        v = r.trace.of(cols)
        rows.append(_card_row(r.trace, v, r.unit, r))
    for m in ev.extra:
        unit = statistic_display_unit(m.statistic, ev.runner.display_units[m.output])
        rows.append(_card_row(m, m.of(cols), unit, None))
    card = SystemCard(ev, rows, time.perf_counter() - t0, cols)
    if out is not None:
        card.write(out)
    return card


def _card_row(m: TraceMetric, value: float, unit: str, req: OutputRequirement | None) -> dict:
    return {
        "quantity": m.name,
        "output": m.output,
        "statistic": m.statistic,
        "value": value,
        "unit": unit,
        "requirement": req.label.split(": ", 1)[1] if req else "",
        "limit": req.limit if req else None,
        "met": req.met_by(value) if req else None,
        "margin": req.margin(value) if req else None,
        "sense": req.sense if req else None,
    }


# ------------------------------------------------------------------ the files ---
def is_system_study(doc: dict) -> bool:
    """Whether a parsed study file names its system by ``[system] file``."""
    return isinstance(doc.get("system"), dict) and "file" in doc["system"]


def _refuse_system_file(doc: dict, command: str) -> None:
    if is_system_file(doc):
        raise HydroarmError(
            "system",
            f'this is a system file; a {command} file names it: [system] file = "…" '
            f"(docs/{command}.md)",
        )


def read_study_doc(path) -> tuple[dict, Path]:
    text, p = read_text_file(path)
    return parse_toml(text, p.name), p


def check_system_doc(doc: dict, command: str) -> bool:
    """Whether a design or evaluation file is a study of a system (``[system] file``);
    a system file given in its place is refused."""
    if is_system_study(doc):
        return True
    _refuse_system_file(doc, command)
    return False
