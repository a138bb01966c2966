"""Design studies and evaluation cards of any system (issue 29; docs/design.md "Any system",
docs/evaluate.md "Any system").

A study names its system by file, ``[system] file = "servo.toml"`` (`hydroarm.io.system.system_of`:
a circuit, a mechanism or a fixed-shape component servo; fields beside ``file`` override the
file's). Its requirements bound statistics of the system's named outputs, the columns ``hydroarm
simulate --out`` writes (``pressure_a_bar``, ``jack_flow_lpm``, ``load_position_m`` …), with the
statistics of `hydroarm.metrics.trace` and a limit with its unit::

    [requirements]
    settling = { output = "position_m", statistic = "settling_time", after = "1 s",
                 limit = "<= 0.6 s" }
    peak_a = { output = "pressure_a_bar", statistic = "max", limit = "<= 60 bar" }

A limit is read in the statistic's unit: the output's (any unit of its dimension: psi for
a pressure in bar), seconds for a time, percent for the overshoot. ``[metrics]`` (the same
tables without ``limit``) adds quantities to measure and to name in objectives.

`SystemDesignStudy` varies the system's parameters (``[design.variables]``: a
circuit's ``<component>.<parameter>``, a component servo's sweep names, bounds in the
parameter's declared unit) with the joint's search (`hydroarm.analysis.design.search`:
scrambled Sobol designs, differential evolution on one objective, the Pareto front), every
batch of candidates on the system's batch engine: a circuit's rows on
`hydroarm.batch.circuit_sweep.run_circuit_chunk`, the path of a sweep's rows (the observers
at the samples ``simulate`` records, a settling or rise time read from a probe of its output
there), a servo's on its batch path (`servo_chunk_columns`); a
candidate's metrics are those of the same system run alone by ``hydroarm simulate`` (bit
for bit; an ``integral``, ``mean`` or ``rms`` observed to the rounding of its sum).
`SystemEvaluation` is the card of one system: one ``simulate`` run, each requirement's
value, limit, margin.

Load cases (``[[case]]``, `read_cases`: a name and overrides of the study's parameters,
tables, payload masses, the duration) run every candidate of a design, or the card's
system, in each case; a requirement is judged on its worst case over the cases it covers
(``cases = [...]`` restricts it), the card and report show every case's value and which is
worst. A design's rows are candidates × cases on the same batch engine.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..batch.circuit_sweep import (
    TraceMetric,
    circuit_chunk_columns,
    read_metrics,
    run_circuit_chunk,
)
from ..batch.servo_sweep import check_servo_changes
from ..core.circuit.components import TYPES
from ..errors import HydroarmError
from ..files import atomic_write_text, check_output_folder, csv_text, move_into, staging_folder
from ..integrators import registry
from ..io.circuit import parameter_of, parameter_value
from ..io.components import sweep_dimension, sweep_rule, sweep_targets
from ..io.sections import (
    as_table,
    check_run_size,
    parse_toml,
    read_text_file,
    reject_unknown_keys,
    require_table,
    text_value,
    time_value,
    unknown_name,
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
from ..io.units import SI_UNITS, quantity, value_in
from ..metrics.trace import STATISTICS
from ..model.circuit import (
    Circuit,
    CircuitResult,
    build,
    row_initial_states,
    simulate_many,
)
from ..model.circuit import (
    simulate as simulate_circuit,
)
from ..model.servo import ServoResult, ServoScenario, servo_states
from ..model.servo_rows import same_net
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

SECTIONS = {"name", "description", "system", "case", "requirements", "metrics", "design"}
EVALUATE_SECTIONS = {"name", "description", "system", "case", "requirements", "metrics"}
MAX_CASES = 64  # [[case]] tables of one study
# rows (designs × cases) of one call of the batch engine: under the circuit's 2000 rows whose
# equilibrium starts it solves one by one (model.circuit.MAX_EQUILIBRIUM_ROWS)
MAX_BATCH_ROWS = 1024
DESIGN_KEYS = {"samples", "seed", "variables", "objectives", "refine", "chunk"}
MAX_BLOCK_BYTES = 64 * 2**20  # recorded states of a servo batch held at once
#: the budget of a design: integration steps over every candidate (Sobol and refinement)
MAX_DESIGN_STEPS = 2 * 10**11
OUTPUT_FILES = ("designs.csv", "pareto.png", "feasibility.png", "design_report.md")
CARD_FILES = ("card.csv", "card.md", "card.png")
CARD_COLUMNS = [
    "quantity",
    "case",
    "output",
    "statistic",
    "value",
    "unit",
    "requirement",
    "limit",
    "met",
    "margin",
    "worst",
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

    def for_case(self, case: SystemCase) -> SystemRunner:
        """The runner of the system as a load case changes its structure: run for the
        case's duration, its mechanism's payloads of the case's masses (this runner where
        the case changes neither; the others built once and kept)."""
        if case.duration in (None, self.system.duration) and not (case.payloads or case.arrays):
            return self
        cache = self.__dict__.setdefault("_cases", {})
        key = (case.duration, case.payloads, case.arrays)
        if key not in cache:
            cache[key] = SystemRunner(case.structure(self.system))
        return cache[key]

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
        """The SI unit of a parameter (as `hydroarm.io.units` writes it)."""
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
        """``[failed, metric…]`` of each row of values ``x`` (SI) on the batch engine: a
        circuit's on `run_circuit_chunk` (observed at the samples ``simulate`` records: a
        row holds its metrics' accumulators and the probes of its trace-only statistics'
        outputs, not its states), a servo's on `run_servo_chunk`."""
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
        run together on the batch engine as `run` runs them (None: the run failed)."""
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
    engine (`servo_chunk_columns`). A row whose step is above its stable limit, or
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
    """``(row, columns)`` of servos that differ only in parameters: the columns ``hydroarm
    simulate --out`` writes, or None for a row whose step is above its stable limit
    ([`ServoScenario.step_limit`][hydroarm.ServoScenario.step_limit]) or whose run left finite
    numbers. Rows whose circuits share one net run on the system kernel's batch path
    (`simulate_many` on their energy circuits, `_servo_circuit_columns`), others one by one
    (each row's [`run_on_system_kernel`][hydroarm.ServoScenario.run_on_system_kernel]); every
    row is its single run, bit for bit. What has no circuit form is refused before work."""
    if not scenarios:
        return
    for sc in scenarios:
        sc.circuit  # noqa: B018 (what has no circuit form is refused before any row runs)
    stable = []
    for i, sc in enumerate(scenarios):
        if sc.step_limit() is None:
            stable.append(i)
        else:
            yield i, None
    rows = np.array(stable, dtype=int)
    if not rows.size:
        return
    nets = [scenarios[i].energy_circuit.net for i in rows]
    if all(same_net(nets[0], net) for net in nets[1:]):
        yield from _servo_circuit_columns(scenarios, rows)
        return
    for i in rows:
        sc = scenarios[i]
        try:
            res = sc.run_on_system_kernel()
        except HydroarmError:  # it left finite numbers
            yield int(i), None
            continue
        yield int(i), res.columns()


def _blocks(rows: np.ndarray, records: int, width: int):
    """``rows`` in blocks whose recorded states (``records`` × ``width`` floats each) fit
    `MAX_BLOCK_BYTES`."""
    block = max(1, MAX_BLOCK_BYTES // max(1, records * width * 8))
    for lo in range(0, len(rows), block):
        yield rows[lo : lo + block]


def _servo_circuit_columns(scenarios: list[ServoScenario], rows: np.ndarray):
    """``(row, columns or None)`` of servos whose energy circuits share one net, on the
    system kernel's batch path (`simulate_many`: a row is the single run, bit for bit)."""
    first = scenarios[int(rows[0])]
    compiled = first.energy_circuit
    table = np.array([scenarios[i].energy_circuit.P for i in rows])
    S0 = np.array([scenarios[i].energy_circuit.s0 for i in rows])
    index = {int(i): j for j, i in enumerate(rows)}
    records = first.nsteps // first.record_every + 1
    for part in _blocks(rows, records, S0.shape[1]):
        at = [index[int(i)] for i in part]
        t, S, bad = simulate_many(compiled, table[at], S0[at])
        r = first.reference(t)
        for j, i in enumerate(part):
            if bad[j] >= 0:
                yield int(i), None
                continue
            sc = scenarios[i]
            res = CircuitResult(sc.energy_circuit, t, S[j], -1, table[at[j]])
            yield int(i), ServoResult(sc, t, servo_states(sc, res), r).columns()


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
    cases: tuple[str, ...] | None = None  # the load cases it bounds (None: every one)

    @property
    def metric(self) -> str:
        return self.name

    def covers(self, case: str) -> bool:
        return self.cases is None or case in self.cases

    def worst(self, values: dict[str, float]) -> tuple[float, str | None]:
        """(worst value, its case) over the cases it covers of ``values`` (case → value):
        the largest for "max", the smallest for "min"; (NaN, the case) when a run failed."""
        return worst_of(
            {c: v for c, v in values.items() if self.covers(c)},
            "max" if self.sense == "max" else "min",
        )

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


def worst_of(values: dict[str, float], sense: str) -> tuple[float, str | None]:
    """(worst value, its case) of case → value: the largest for ``sense`` "max" (a value
    that must stay below a limit), the smallest for "min"; a NaN (a failed run) is the
    worst of all; (NaN, None) for no value."""
    if not values:
        return math.nan, None
    for c, v in values.items():
        if math.isnan(v):
            return math.nan, c
    pick = max if sense == "max" else min
    case = pick(values, key=lambda c: values[c])
    return values[case], case


def statistic_display_unit(statistic: str, output_unit: str) -> str:
    """The unit (pint's syntax) of a statistic's value: the output's, ``s``, ``percent``."""
    kind = STATISTICS[statistic][0]
    if kind == "same":
        return output_unit
    if kind == "same*s":
        return f"({output_unit})*s" if output_unit else "s"
    return {"pct": "percent"}.get(kind, kind)


def read_output_requirements(
    field: str, table, runner: SystemRunner, cases: tuple[SystemCase, ...] = ()
) -> tuple[OutputRequirement, ...]:
    """The ``[requirements]`` of a study of a system (module doc); ``cases = [...]`` on one
    restricts it to those of the study's load cases (``cases``)."""
    table = as_table(field, table)
    if not table:
        raise HydroarmError(field, "is empty: give at least one requirement")
    specs, limits, covered = {}, {}, {}
    names = [c.name for c in cases]
    for name, spec in table.items():
        spec = dict(as_table(f"{field}.{name}", spec))
        if "limit" not in spec:
            raise HydroarmError(f"{field}.{name}.limit", 'is missing (e.g. limit = "<= 60 bar")')
        limits[name] = spec.pop("limit")
        if "cases" in spec:
            covered[name] = _requirement_cases(f"{field}.{name}.cases", spec.pop("cases"), names)
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
        only = covered.get(m.name)
        if only is not None:
            label += f" ({', '.join(only)})"
        out.append(OutputRequirement(m.name, m, limit, sense_of(cmp), unit, label, only))
    return tuple(out)


def _requirement_cases(field: str, value, names: list[str]) -> tuple[str, ...]:
    """A requirement's ``cases = [...]``: names of the study's [[case]] tables."""
    if not names:
        raise HydroarmError(field, "names load cases, but the study has no [[case]]")
    if not isinstance(value, list) or not value:
        raise HydroarmError(field, 'must be a non-empty list of case names, e.g. ["heavy"]')
    out = tuple(text_value(f"{field}[{i}]", v) for i, v in enumerate(value))
    for c in out:
        if c not in names:
            raise unknown_name(field, "case", c, names)
    if len(set(out)) != len(out):
        raise HydroarmError(field, "names a case twice")
    return out


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


# ---------------------------------------------------------------- load cases ---
@dataclass(frozen=True)
class SystemCase:
    """A load case of a study of a system: the system file with some parameters set
    (``values``: internal names, SI) and optionally run for another ``duration`` [s]
    (None: the system's). ``overrides``: the values as the file wrote them (for reports)."""

    name: str
    values: tuple[tuple[str, float], ...] = ()
    duration: float | None = None
    overrides: tuple[tuple[str, str], ...] = ()
    payloads: tuple[tuple[str, float], ...] = ()  # a mechanism's payload masses [kg] by name
    # a circuit component's tables: ("reference.values", (0.2, 0.5)) [SI]
    arrays: tuple[tuple[str, tuple[float, ...]], ...] = ()

    @property
    def structural(self) -> bool:
        """Whether the case changes more than parameters (the duration, a payload, a
        table): its runs need the system rebuilt."""
        return self.duration is not None or bool(self.payloads) or bool(self.arrays)

    def structure(self, system: System) -> System:
        """``system`` run for the case's duration, with its payload masses and its tables
        (what the case changes beyond parameters)."""
        if self.duration is not None:
            system = system.replace(duration=self.duration)
        if self.arrays:
            assert isinstance(system, Circuit)
            tables: dict[str, dict[str, tuple[float, ...]]] = {}
            for key, v in self.arrays:
                comp, _, name = key.partition(".")
                tables.setdefault(comp, {})[name] = v
            system = system.replace(
                components=tuple(
                    replace(c, arrays={**c.arrays, **tables[c.name]}) if c.name in tables else c
                    for c in system.components
                )
            )
        if self.payloads:
            assert isinstance(system, Circuit) and system.mechanism is not None
            mech = system.mechanism
            masses = dict(self.payloads)
            new = tuple(
                replace(p, mass=masses[p.name]) if p.name in masses else p for p in mech.payloads
            )
            system = system.replace(mechanism=replace(mech, payloads=new))
        return system

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(k for k, _ in self.values)

    @property
    def row(self) -> tuple[float, ...]:
        return tuple(v for _, v in self.values)

    def overrides_of_parameters(self) -> tuple[tuple[str, str], ...]:
        """The overrides as written, the duration and payloads left out (one per entry of
        ``values``)."""
        tables = {k for k, _ in self.arrays}
        return tuple(
            (k, v)
            for k, v in self.overrides
            if k != "duration" and not k.startswith(PAYLOAD) and k not in tables
        )

    def describe(self) -> str:
        """``payload.mass = 300 kg, duration = 2 s`` (the system file's values: "as given")."""
        shown = [f"{k} = {v}" for k, v in self.overrides]
        return ", ".join(shown) or "the system file as given"


#: a case's key of a mechanism's payload mass: "mechanism.payload.<name>.mass"
PAYLOAD = "mechanism.payload."
#: the one case of a study without [[case]]: the system file's inputs
AS_GIVEN = SystemCase("")


def read_cases(doc: dict, runner: SystemRunner, field: str = "case") -> tuple[SystemCase, ...]:
    """The ``[[case]]`` tables of a study of a system: a ``name``, overrides of any parameter
    a study may vary (``"payload.mass" = "300 kg"``, with units, each checked against its
    rule; a component servo's cross rules on the case's values), a circuit component's table
    as long as the file's (``"reference.values" = ["0.2 m", "0.3 m"]``), a mechanism's
    payload mass (``"mechanism.payload.soil.mass" = "200 kg"``) and optionally ``duration``
    (the solver's; method, step and record_every stay the study's). A case that changes a
    table, a payload or the duration has its system built here (its rules checked before
    any run). Empty: no [[case]]."""
    if field not in doc:
        return ()
    entries = doc[field]
    if not isinstance(entries, list) or not entries:
        raise HydroarmError(field, 'give [[case]] tables: a name and overrides ("load.mass" = …)')
    if len(entries) > MAX_CASES:
        raise HydroarmError(field, f"at most {MAX_CASES} cases, got {len(entries)}")
    out: list[SystemCase] = []
    s = runner.system
    for i, e in enumerate(entries):
        f = f"{field}[{i}]"
        e = as_table(f, e)
        if "name" not in e:
            raise HydroarmError(f"{f}.name", "is missing")
        name = text_value(f"{f}.name", e["name"]).strip()
        if not name:
            raise HydroarmError(f"{f}.name", "is empty")
        if any(c.name == name for c in out):
            raise HydroarmError(f"{f}.name", f"{name!r} is used by another case")
        values: dict[str, float] = {}
        shown: list[tuple[str, str]] = []
        payloads: list[tuple[str, float]] = []
        arrays: dict[str, tuple[float, ...]] = {}
        duration = None
        for k, v in e.items():
            if k == "name":
                continue
            fk = f"{f}.{k}"
            if k == "duration":
                duration = time_value(fk, v, positive=True)
                check_run_size(duration, s.step, s.record_every, duration_field=fk)
            elif k.startswith(PAYLOAD):
                mass = _payload_mass(fk, k, v, s)
                if any(n == mass[0] for n, _ in payloads):
                    raise HydroarmError(fk, "sets a payload another key of the case sets")
                payloads.append(mass)
            elif _array_of(s, k) is not None:
                arrays[k] = _case_array(fk, v, _array_of(s, k))
            elif k in ("method", "step", "record_every", "file"):
                raise HydroarmError(
                    fk, "a case may change the duration only (the solver is the study's)"
                )
            else:
                key = runner.key(fk, k)
                if key in values:
                    raise HydroarmError(fk, f"sets {key}, which another key of the case sets")
                values[key] = runner.value(fk, key, v)
            shown.append((k, str(v)))
        if values:
            runner.check(f, list(values), list(values.values()))
        case = SystemCase(
            name, tuple(values.items()), duration, tuple(shown), tuple(payloads),
            tuple(arrays.items()),
        )  # fmt: skip
        if case.structural:  # the rebuilt system checked now (a table's rules, the stroke)
            try:
                runner.for_case(case)
            except HydroarmError as exc:
                raise HydroarmError(f, f"{exc.field}: {exc.problem}") from None
        out.append(case)
    return tuple(out)


def _array_of(system: System, key: str):
    """The declaration of a circuit component's table ``<component>.<times|values>``, or
    None (not a table: a parameter or nothing)."""
    if not isinstance(system, Circuit):
        return None
    comp, _, name = key.partition(".")
    for c in system.components:
        if c.name == comp and c.arrays:
            for a in TYPES[c.type].DECLARATION.arrays:
                if a.name == name:
                    return a, c
    return None


def _case_array(field: str, value, found) -> tuple[float, ...]:
    """A case's table of a component (``"reference.values" = ["0.2 m", "0.5 m"]``) [SI]:
    as long as the file's (its other table keeps its entries), in the table's unit."""
    decl, comp = found
    old = comp.arrays[decl.name]
    if not isinstance(value, list) or len(value) != len(old):
        raise HydroarmError(
            field, f"must be a list of {len(old)} entries, as the file's (its other table)"
        )
    v = tuple(value_in(f"{field}[{i}]", x, decl.unit) for i, x in enumerate(value))
    if decl.name == "times" and any(b <= a for a, b in zip(v, v[1:], strict=False)):
        raise HydroarmError(field, "must increase")
    return v


def _payload_mass(field: str, key: str, value, system: System) -> tuple[str, float]:
    """(payload name, mass [kg]) of a case's ``"mechanism.payload.<name>.mass" = "2 kg"``."""
    name, dot, what = key[len(PAYLOAD) :].rpartition(".")
    mech = system.mechanism if isinstance(system, Circuit) else None
    if mech is None or not mech.payloads:
        raise HydroarmError(field, "the system has no mechanism payload to set")
    known = [p.name for p in mech.payloads]
    if not dot or what != "mass":
        raise HydroarmError(field, f"a case sets a payload's mass: {PAYLOAD}<name>.mass")
    if name not in known:
        raise unknown_name(field, "payload", name, known)
    return name, quantity(field, value, "mass", positive=True)


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
    cases: tuple[SystemCase, ...] = ()  # the [[case]] tables (none: the file as given)

    @property
    def metrics(self) -> tuple[TraceMetric, ...]:
        return (*(r.trace for r in self.requirements), *self.extra)

    @property
    def run_cases(self) -> tuple[SystemCase, ...]:
        """The cases every candidate runs in: the [[case]] tables, or the file as given."""
        return self.cases or (AS_GIVEN,)

    @property
    def steps_per_candidate(self) -> int:
        """Integration steps of one candidate over every case (the budget's unit)."""
        return sum(self.runner.for_case(c).nsteps for c in self.run_cases)

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
        """Designs ``x`` (rows, SI) in every case on the system's batch engine, ``chunk``
        designs a batch: the rows are designs × cases, a case's values beside the design's
        (cases of one duration and the same overridden parameters share a run)."""
        x = np.atleast_2d(np.asarray(x, float))
        per_case = self.case_metrics(x, progress, source)
        per = []
        for i in range(len(x)):
            cases = per_case[i]
            d: dict = {"failed": any(row["failed"] for row in cases.values()), "cases": cases}
            d["worst_case"] = {}
            for r in self.requirements:
                d[r.name], d["worst_case"][r.name] = r.worst(
                    {c: row[r.name] for c, row in cases.items()}
                )
            if len(cases) == 1:  # the one case: the extra metrics' values as they are
                d |= {m.name: next(iter(cases.values()))[m.name] for m in self.extra}
            per.append(d)
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

    def case_metrics(self, x: np.ndarray, progress=None, source: str = "sobol") -> list[dict]:
        """Per design, case name → ``{failed, metric…}``: every design in every case on the
        batch engine, ``chunk`` designs (× cases) a batch."""
        metrics = self.metrics
        out: list[dict] = [{} for _ in range(len(x))]
        groups: dict[tuple, list[SystemCase]] = {}
        for c in self.run_cases:
            groups.setdefault((c.duration, c.payloads, c.arrays, c.keys), []).append(c)
        for lo in range(0, len(x), self.chunk):
            hi = min(lo + self.chunk, len(x))
            for (*_, case_keys), cases in groups.items():
                rows = np.array(
                    [[*x[i], *c.row] for i in range(lo, hi) for c in cases], dtype=float
                )
                runner = self.runner.for_case(cases[0])
                keys = [*self.keys, *case_keys]
                M = np.vstack(
                    [
                        runner.run(keys, rows[k : k + MAX_BATCH_ROWS], metrics)
                        for k in range(0, len(rows), MAX_BATCH_ROWS)
                    ]
                )
                for k, (i, c) in enumerate((i, c) for i in range(lo, hi) for c in cases):
                    row = {m.name: float(M[k, 1 + j]) for j, m in enumerate(metrics)}
                    out[i][c.name] = row | {"failed": bool(M[k, 0] > 0.5)}
            if progress is not None:
                progress(f"design: {hi}/{len(x)} designs evaluated ({source})")
        # the file's order of the cases
        return [{c.name: d[c.name] for c in self.run_cases} for d in out]

    def objective_value(self, o: Objective, x_row, metrics: dict) -> float:
        """A design variable's value, or a metric's worst value over the cases it covers
        (the smallest for a "max" objective, the largest for a "min" one)."""
        names = [v.name for v in self.variables]
        if o.name in names:
            return float(x_row[names.index(o.name)])
        cases = metrics.get("cases")
        if not cases:
            return float(metrics.get(o.name, math.nan))
        req = next((r for r in self.requirements if r.name == o.name), None)
        values = {c: row[o.name] for c, row in cases.items() if req is None or req.covers(c)}
        return worst_of(values, "min" if o.sense == "max" else "max")[0]

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
    """A `SystemDesignStudy` from a parsed design file with ``[system] file``; every
    value checked (the variables' bounds at every corner of the design space, the budget)
    before any run."""
    reject_unknown_keys("", doc, SECTIONS)
    system, runner = study_system(doc, base_dir)
    cases = read_cases(doc, runner)
    reqs = read_output_requirements(
        "requirements", require_table(doc, "requirements"), runner, cases
    )
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
    _check_case_keys(runner, keys, cases)
    for case in cases or (AS_GIVEN,):
        for c in range(2 ** min(len(variables), 10)):
            corner = np.where([(c >> i) & 1 for i in range(len(variables))], highs, lows)
            try:
                runner.check("design.variables", [*keys, *case.keys], [*corner, *case.row])
            except HydroarmError as exc:
                if not case.name:
                    raise
                raise HydroarmError(exc.field, f"in case {case.name!r}: {exc.problem}") from None
    study = SystemDesignStudy(
        name=text_value("name", doc.get("name", name)),
        runner=runner,
        requirements=reqs,
        extra=extra,
        keys=tuple(keys),
        cases=cases,
        **s,
    )
    ref = s["refine"]
    candidates = s["samples"] + (0 if ref is None else (ref.generations + 1) * ref.population)
    steps = candidates * study.steps_per_candidate
    if steps > MAX_DESIGN_STEPS:
        ncases = len(study.run_cases)
        raise HydroarmError(
            "design.samples",
            f"{candidates} candidates × {ncases} case{'s' if ncases > 1 else ''} is "
            f"{steps:.3g} integration steps, more than {MAX_DESIGN_STEPS:.0e} in all: fewer "
            "samples, generations or cases, or a shorter duration",
        )
    return study


def _check_case_keys(runner: SystemRunner, keys: list[str], cases) -> None:
    """A case may not set what a design variable varies (for a component servo: the same
    target parameter under another name, ``piston_area`` and ``area_a``)."""

    def targets(k: str) -> set[str]:
        return {k} if runner.circuit else set(sweep_targets(k))

    varied = {t: k for k in keys for t in targets(k)}
    for i, c in enumerate(cases):
        for (k, _), (written, _) in zip(c.values, c.overrides_of_parameters(), strict=True):
            hit = targets(k) & set(varied)
            if hit:
                raise HydroarmError(
                    f"case[{i}].{written}",
                    f"sets {sorted(hit)[0]}, which the design variable {varied[sorted(hit)[0]]} "
                    "varies: a case may not set a design variable",
                )


@dataclass(repr=False)
class SystemDesignResult(DesignResult):
    """The designs of a system: the joint's tables, plots and report, without load cases."""

    study: SystemDesignStudy  # type: ignore[assignment]

    @property
    def scenarios(self) -> int:
        """Runs: designs × load cases."""
        return len(self.evaluation.x) * len(self.study.run_cases)

    def throughput(self) -> float:
        """Designs per second (each in every load case), start-up included."""
        return len(self.evaluation.x) / self.elapsed_s

    def failed(self) -> int:
        return sum(bool(m.get("failed")) for m in self.evaluation.metrics)

    def columns(self) -> list[str]:
        """The joint's columns, and with load cases each requirement's worst case."""
        cols = super().columns()
        if self.study.cases:
            cols += [f"worst_case_{r.name}" for r in self.study.requirements]
        return cols

    def rows(self) -> list[dict]:
        rows = super().rows()
        if self.study.cases:
            for row, m in zip(rows, self.evaluation.metrics, strict=True):
                for r in self.study.requirements:
                    row[f"worst_case_{r.name}"] = m["worst_case"][r.name] or ""
        return rows

    def case_rows(self) -> list[dict]:
        """``cases.csv``: one row per design, case and quantity (requirement or metric):
        its value in its unit, and for a requirement whether the case is its worst."""
        s, e = self.study, self.evaluation
        out = []
        for i, m in enumerate(e.metrics):
            for case, values in m["cases"].items():
                for r in s.requirements:
                    if not r.covers(case):
                        continue
                    out.append(
                        {
                            "design": i + 1,
                            "case": case,
                            "quantity": r.name,
                            "value": values[r.name],
                            "unit": r.unit,
                            "worst": str(m["worst_case"][r.name] == case).lower(),
                            "failed": str(values["failed"]).lower(),
                        }
                    )
                for x in s.extra:
                    unit = statistic_display_unit(x.statistic, s.runner.display_units[x.output])
                    out.append(
                        {
                            "design": i + 1,
                            "case": case,
                            "quantity": x.name,
                            "value": values[x.name],
                            "unit": unit,
                            "worst": "",
                            "failed": str(values["failed"]).lower(),
                        }
                    )
        return out

    def extra_files(self) -> list[tuple[str, str]]:
        if not self.study.cases:
            return []
        cols = ["design", "case", "quantity", "value", "unit", "worst", "failed"]
        return [("cases.csv", csv_text(cols, self.case_rows()))]

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

    def _case_table(self, designs: list[int]) -> list[str]:
        """The report's table of each listed design's requirement values in every case, the
        worst case of each requirement in bold ("—": a case the requirement does not cover)."""
        s, e = self.study, self.evaluation
        head = ["design", "case"] + [
            f"{r.name} [{r.unit}]" if r.unit else r.name for r in s.requirements
        ]
        lines = [
            "",
            "### Each case of these designs",
            "",
            "The worst case of each requirement in bold.",
            "",
            "| " + " | ".join(head) + " |",
            "|---" * len(head) + "|",
        ]
        for i in designs:
            m = e.metrics[i]
            for case, values in m["cases"].items():
                cells = [str(i + 1), case]
                for r in s.requirements:
                    if not r.covers(case):
                        cells.append("—")
                        continue
                    v = f"{values[r.name]:.4g}"
                    cells.append(f"**{v}**" if m["worst_case"][r.name] == case else v)
                lines.append("| " + " | ".join(cells) + " |")
        return lines

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
            + ")"
            + (f" × {len(s.cases)} load cases ({n * len(s.cases)} runs)" if s.cases else "")
            + f", every run on the batch engine; {self.failed()} failed (a run left the "
            f"physical bounds or was above the stable step); {nf} feasible, "
            f"{int(self.pareto.sum())} on the Pareto front.",
            "",
            f"Time: {self.elapsed_s:.2f} s in all ({self.evaluation_s:.2f} s evaluating); "
            f"{self.throughput():.3g} designs per second.",
            "",
            "## Requirements",
            "",
        ]
        lines += [f"- `{r.label}`" for r in s.requirements]
        if s.cases:
            lines += [
                "",
                "## Load cases",
                "",
                f"Every design runs in each case ({len(e.x) * len(s.cases)} runs); a "
                "requirement is judged on its worst case.",
                "",
            ]
            lines += [f"- {c.name}: {c.describe()}" for c in s.cases]
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
        if s.cases:
            lines += self._case_table(rec)
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
    """The card of a system: its requirements and measured metrics on one run per load
    case (``cases``; none: one run of the file as given)."""

    name: str
    runner: SystemRunner
    requirements: tuple[OutputRequirement, ...]
    extra: tuple[TraceMetric, ...] = ()
    cases: tuple[SystemCase, ...] = ()

    @property
    def run_cases(self) -> tuple[SystemCase, ...]:
        return self.cases or (AS_GIVEN,)

    def case_system(self, case: SystemCase) -> System:
        """The system of one case: what ``hydroarm simulate`` runs for it."""
        return case.structure(self.runner.with_values(dict(case.values)))


def read_system_evaluation(doc: dict, name: str, base_dir: Path) -> SystemEvaluation:
    reject_unknown_keys("", doc, EVALUATE_SECTIONS)
    _, runner = study_system(doc, base_dir)
    cases = read_cases(doc, runner)
    if "requirements" not in doc and "metrics" not in doc:
        raise HydroarmError("requirements", "is missing (give [requirements] or [metrics])")
    reqs = (
        read_output_requirements("requirements", doc["requirements"], runner, cases)
        if "requirements" in doc
        else ()
    )
    extra = read_extra_metrics(doc, runner, {r.name for r in reqs})
    ev = SystemEvaluation(text_value("name", doc.get("name", name)), runner, reqs, extra, cases)
    for i, c in enumerate(cases):  # a component servo's case at its stable step, as the file
        system = ev.case_system(c)
        if isinstance(system, ServoScenario):
            with within(f"case[{i}]"):
                system.check_step()
    return ev


@dataclass
class SystemCard:
    """The card of one system: ``rows`` (one per requirement or metric and load case,
    `CARD_COLUMNS`) and each case's run's columns (``columns``: case → columns)."""

    evaluation: SystemEvaluation
    rows: list
    elapsed_s: float = 0.0
    columns: dict = field(default_factory=dict)

    def value(self, name: str, case: str | None = None) -> float:
        """A quantity's value: in ``case``, or (None) its worst case's (the only one
        without load cases)."""
        for r in self.rows:
            if r["quantity"] == name and (r["case"] == case if case is not None else r["worst"]):
                return r["value"]
        raise KeyError(name if case is None else (name, case))

    def worst_case(self, name: str) -> str:
        """The case in which a requirement is worst."""
        for r in self.rows:
            if r["quantity"] == name and r["worst"]:
                return r["case"]
        raise KeyError(name)

    def all_met(self) -> bool:
        return all(r["met"] for r in self.rows if r["met"] is not None)

    def csv(self) -> str:
        return csv_text(CARD_COLUMNS, self.rows)

    def lines(self) -> list[str]:
        """The terminal's lines: one per quantity (and case)."""
        out = []
        for r in self.rows:
            req = ""
            if r["requirement"]:
                met = "met" if r["met"] else "NOT met"
                req = f"  [{met}: {r['requirement']}, margin {r['margin']:+.3f}]"
            case = ""
            if r["case"]:
                case = f"{r['case']}{' (worst)' if r['worst'] and r['requirement'] else ''}: "
            out.append(f"{r['quantity']:<24} {case}{r['value']:.6g} {r['unit']}{req}")
        return out

    def markdown(self) -> str:
        ev = self.evaluation
        runs = (
            f"one `hydroarm simulate` run per load case ({len(ev.cases)})"
            if ev.cases
            else "one `hydroarm simulate` run"
        )
        lines = [
            f"# Evaluation card: {ev.name}",
            "",
            f"System: {ev.runner.describe()}; {runs}, computed in {self.elapsed_s:.2f} s. What "
            "each number is: docs/evaluate.md.",
            "",
        ]
        if ev.cases:
            lines += ["## Load cases", ""]
            lines += [f"- {c.name}: {c.describe()}" for c in ev.cases]
            lines += [
                "",
                "A requirement is judged on its worst case (**bold**): met when that case "
                "meets it.",
                "",
            ]
        lines += [
            "| quantity | case | statistic of output | value | unit | requirement | met | margin |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in self.rows:
            met = "" if r["met"] is None else ("yes" if r["met"] else "**no**")
            margin = "" if r["margin"] is None else f"{r['margin']:+.3f}"
            value = f"{r['value']:.5g}"
            case = r["case"]
            if ev.cases and r["worst"] and r["requirement"]:
                value, case = f"**{value}**", f"**{case}**"
            lines.append(
                f"| {r['quantity']} | {case} | {r['statistic']} of `{r['output']}` | {value} "
                f"| {r['unit']} | {r['requirement']} | {met} | {margin} |"
            )
        lines += ["", "![the card's numbers against the requirements](card.png)", ""]
        return "\n".join(lines)

    def figure(self):
        panels: dict[str, dict] = {}
        for r in self.rows:
            if r["quantity"] not in panels:
                p: dict = {
                    "quantity": f"{r['quantity']}: {r['statistic']} of {r['output']}",
                    "unit": r["unit"],
                    "labels": [],
                    "values": [],
                }
                if r["limit"] is not None:
                    p["limit"] = r["limit"]
                    p["sense"] = r["sense"]
                panels[r["quantity"]] = p
            p = panels[r["quantity"]]
            p["labels"].append(r["case"] or self.evaluation.runner.name)
            p["values"].append(r["value"])
        return fig_card(list(panels.values()), title=f"{self.evaluation.name}")

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
    """The card of a system: its run in each load case as ``hydroarm simulate`` makes it,
    each requirement's statistic of it (`hydroarm.metrics.trace`) in the cases it
    covers, the limit, the margin and the worst case (the one the verdict is judged on)."""
    tick = progress or (lambda label: None)
    t0 = time.perf_counter()
    columns = {}
    for c in ev.run_cases:
        tick(
            f"evaluate: simulating {ev.runner.describe()}"
            + (f", case {c.name!r}" if c.name else "")
        )
        columns[c.name] = ev.runner.simulate_columns(ev.case_system(c))
    rows = []
    for r in ev.requirements:
        values = {c: r.trace.of(cols) for c, cols in columns.items() if r.covers(c)}
        _, worst = r.worst(values)
        rows += [_card_row(r.trace, v, r.unit, r, c, c == worst) for c, v in values.items()]
    for m in ev.extra:
        unit = statistic_display_unit(m.statistic, ev.runner.display_units[m.output])
        rows += [_card_row(m, m.of(cols), unit, None, c, True) for c, cols in columns.items()]
    card = SystemCard(ev, rows, time.perf_counter() - t0, columns)
    if out is not None:
        card.write(out)
    return card


def _card_row(
    m: TraceMetric,
    value: float,
    unit: str,
    req: OutputRequirement | None,
    case: str = "",
    worst: bool = True,
) -> dict:
    return {
        "quantity": m.name,
        "case": case,
        "output": m.output,
        "statistic": m.statistic,
        "value": value,
        "unit": unit,
        "requirement": req.label.split(": ", 1)[1] if req else "",
        "limit": req.limit if req else None,
        "met": req.met_by(value) if req else None,
        "margin": req.margin(value) if req else None,
        "sense": req.sense if req else None,
        "worst": worst,
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
