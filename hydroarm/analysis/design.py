"""Design studies: the joints that meet requirements, and their Pareto front (issue 17;
docs/design.md).

A design file names a starting joint (``[joint]``, as in scenario files), load cases
(``[[load_case]]``), requirements (``[requirements]``, `hydroarm.analysis.requirements`)
and the design space (``[design]``): ranges of joint fields (``[design.variables]``), the
number of scrambled Sobol points (`scipy.stats.qmc.Sobol`, seeded) and objectives
(``"max stall_mass"``: a metric's worst value over the load cases, or a design variable).
`run_design` evaluates every sampled design on the batch engine over every load case
and direction (`case_metrics`), marks the feasible
designs (every requirement met) and the Pareto designs (feasible, not dominated in the
objectives by another feasible design), and optionally refines one objective with
`scipy.optimize.differential_evolution` (``vectorized``: each generation one batch),
the feasibility a penalty. [`DesignResult.write`][hydroarm.DesignResult.write] writes
``designs.csv`` (and ``designs.parquet`` with pyarrow), the Pareto and feasibility plots and
``design_report.md``, staged and moved into place together.
"""

from __future__ import annotations

import io
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Protocol

import numpy as np

from ..display import Summarised, fmt
from ..errors import HydroarmError
from ..files import atomic_write_bytes, atomic_write_text, csv_text, move_into, staging_folder
from ..io.progress import Progress
from ..io.sections import (
    FIELD_DIMENSIONS,
    JOINT_KEYS,
    PHYSICS_KEYS,
    as_table,
    field_value,
    joint_from_table,
    optional_table,
    parse_toml,
    read_text_file,
    reject_unknown_keys,
    require_table,
    text_value,
    time_value,
    unknown_name,
    whole_number,
)
from ..io.units import SI_UNITS, unit_suffix
from ..model.joint import ServoJoint
from ..model.scenario import DEFAULT_STEP
from ..plotting.design import display, feasibility_figure, pareto_figure
from ..plotting.joint import save_figure
from .requirements import (
    METRICS,
    LoadCase,
    Requirement,
    case_metrics,
    check_cases,
    motion_duration,
    needed_metrics,
    read_load_cases,
    read_requirements,
    stable_step,
    worst,
)

# ServoJoint fields a design may vary (numbers; the stiffness is given through the volume)
VARIABLES = tuple(k for k in (*JOINT_KEYS, *PHYSICS_KEYS) if k != "hydraulic_stiffness")
DESIGN_SECTIONS = {"name", "description", "joint", "physics", "load_case", "requirements", "design"}
DESIGN_KEYS = {"samples", "seed", "variables", "objectives", "refine", "step", "chunk"}
REFINE_KEYS = {"objective", "generations", "population", "seed"}
MAX_SAMPLES = 2**16
MAX_GENERATIONS = 1000  # refinement generations (each one batch of `population` designs)
MAX_POPULATION = 1024
MAX_VARIABLES = 32
CHUNK = 32  # designs per batch (and per progress line)
OUTPUT_FILES = ("designs.csv", "pareto.png", "feasibility.png", "design_report.md")


@dataclass(frozen=True)
class Variable:
    """A joint field varied over [low, high] [SI], uniformly or on a log scale."""

    name: str
    low: float
    high: float
    log: bool = False
    si_unit: str | None = None  # None: the joint field's (FIELD_DIMENSIONS)

    def from_unit(self, u: np.ndarray) -> np.ndarray:
        """Values [SI] of points ``u`` in [0, 1]."""
        if self.log:
            return np.exp(np.log(self.low) + u * (np.log(self.high) - np.log(self.low)))
        return self.low + u * (self.high - self.low)

    @property
    def unit(self) -> str:
        if self.si_unit is not None:
            return self.si_unit
        return SI_UNITS[FIELD_DIMENSIONS[self.name]]


@dataclass(frozen=True)
class Objective:
    """Maximise (``sense`` "max") or minimise ("min") a metric's worst value over the load
    cases, or a design variable."""

    sense: str
    name: str

    @property
    def label(self) -> str:
        return f"{self.sense} {self.name}"


@dataclass(frozen=True)
class Refine:
    """Differential evolution on one objective, feasibility as a penalty."""

    objective: Objective
    generations: int = 10
    population: int = 16
    seed: int = 0


class SearchStudy(Protocol):
    """What the search (`search`: Sobol designs, then the refinement) reads of a
    study: the joint's [`DesignStudy`][hydroarm.DesignStudy] and a system's
    (`hydroarm.analysis.systems.SystemDesignStudy`) alike."""

    @property
    def variables(self) -> tuple[Variable, ...]: ...
    @property
    def objectives(self) -> tuple[Objective, ...]: ...
    @property
    def samples(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def refine(self) -> Refine | None: ...
    @property
    def chunk(self) -> int: ...
    def evaluate(self, x: np.ndarray, source: str = "sobol", progress=None) -> DesignEvaluation: ...
    def objective_value(self, o: Objective, x_row, metrics: dict) -> float: ...


@dataclass(frozen=True)
class DesignStudy:
    """A design study (a design file, docs/design.md): designs of a joint, evaluated over load
    cases against requirements and objectives.

    Parameters
    ----------
    name : str
        Label.
    joint : ServoJoint
        The base joint; each design changes its ``variables``.
    cases : tuple of LoadCase
        The load cases each design runs.
    requirements : tuple of Requirement
        The requirements a feasible design meets.
    variables : tuple of Variable
        The joint fields varied, with their bounds (SI).
    objectives : tuple of Objective
        The objectives of the Pareto front.
    samples : int
        Number of candidate designs [-] (Sobol points).
    seed : int
        Seed of the scrambled Sobol sequence.
    refine : Refine, optional
        A local refinement of the best designs (None: none).
    step : float
        Fixed integration step [s].
    chunk : int
        Designs per batch run (and per progress line) [-].
    """

    name: str
    joint: ServoJoint
    cases: tuple[LoadCase, ...]
    requirements: tuple[Requirement, ...]
    variables: tuple[Variable, ...]
    objectives: tuple[Objective, ...]
    samples: int = 256
    seed: int = 0
    refine: Refine | None = None
    step: float = DEFAULT_STEP
    chunk: int = CHUNK

    def metrics(self) -> tuple[str, ...]:
        """The metrics the requirements and the objectives need."""
        return needed_metrics(
            self.requirements, [o.name for o in self.objectives if o.name in METRICS]
        )

    def evaluate(self, x: np.ndarray, source: str = "sobol", progress=None) -> DesignEvaluation:
        """Designs ``x`` evaluated over the load cases
        ([`evaluate`][hydroarm.DesignStudy.evaluate])."""
        return evaluate(self, x, source=source, progress=progress)

    def objective_value(self, o: Objective, x_row, metrics: dict) -> float:
        return objective_value(self, o, x_row, metrics)

    def joints(self, x: np.ndarray) -> list[ServoJoint]:
        """The joints of design points ``x`` (one row per design, SI values)."""
        names = [v.name for v in self.variables]
        return [
            self.joint.replace(
                name=f"design {i + 1}", **dict(zip(names, map(float, row), strict=True))
            )
            for i, row in enumerate(np.atleast_2d(x))
        ]


# ------------------------------------------------------------------ the file ---
def read_design_file(
    path, *, samples: int | None = None, refine: bool | None = None
) -> DesignStudy:
    """Read a design file; every problem is a one-line error before any simulation.

    Parameters
    ----------
    path : str or pathlib.Path
        The design file (docs/design.md).
    samples : int, optional
        Number of candidate designs [-], in place of ``[design] samples``.
    refine : bool, optional
        False drops ``[design] refine``.

    Returns
    -------
    DesignStudy
        The study, checked.
    """
    text, p = read_text_file(path)
    study = design_from_doc(parse_toml(text, p.name), p.stem, samples=samples, base_dir=p.parent)
    return replace(study, refine=None) if refine is False else study


def _objective(field: str, text, known) -> Objective:
    t = text_value(field, text)
    parts = t.split()
    if len(parts) != 2 or parts[0] not in ("max", "min"):
        raise HydroarmError(field, f'must be "max <name>" or "min <name>", got {t!r}')
    if parts[1] not in known:
        raise unknown_name(field, "metric or design variable", parts[1], known)
    return Objective(sense=parts[0], name=parts[1])


def read_variable(field: str, name: str, value, read, si_unit: str | None = None) -> Variable:
    """A design variable ``[low, high]`` or ``{range = [low, high], scale = "log"}``, each
    end read by ``read(field, value)`` [SI]."""
    log = False
    if isinstance(value, dict):
        reject_unknown_keys(field, value, {"range", "scale"})
        if "range" not in value:
            raise HydroarmError(f"{field}.range", 'is missing, e.g. range = ["20 bar", "60 bar"]')
        log = text_value(f"{field}.scale", value.get("scale", "linear"), ("linear", "log")) == "log"
        value = value["range"]
    if not isinstance(value, list) or len(value) != 2:
        raise HydroarmError(field, 'must be [low, high] with units, e.g. ["20 bar", "60 bar"]')
    low, high = (read(field, x) for x in value)
    if not low < high:
        raise HydroarmError(field, "low must be below high")
    if log and low <= 0:
        raise HydroarmError(field, "a log scale needs a positive low end")
    return Variable(name=name, low=low, high=high, log=log, si_unit=si_unit)


def _variable(field: str, name: str, value) -> Variable:
    if name not in VARIABLES:
        raise unknown_name(field, "joint parameter", name, VARIABLES)
    return read_variable(field, name, value, lambda f, x: field_value(f, name, x))


def read_search(
    d: dict, variable, metrics, *, keys=DESIGN_KEYS, samples: int | None = None
) -> dict:
    """The search's fields of a ``[design]`` table (shared by every system): ``variables``
    (each read by ``variable(field, name, value)``), ``samples``, ``seed``, ``objectives``
    (``metrics``: the names besides the variables an objective may name), ``refine`` and
    ``chunk``; every budget checked here, before any run."""
    reject_unknown_keys("design", d, keys)
    vt = as_table("design.variables", d.get("variables", {}))
    if not vt:
        raise HydroarmError("design.variables", "give at least one parameter to vary")
    if len(vt) > MAX_VARIABLES:
        raise HydroarmError("design.variables", f"at most {MAX_VARIABLES} variables")
    variables = tuple(variable(f"design.variables.{k}", k, v) for k, v in vt.items())
    var_names = [v.name for v in variables]
    n = samples if samples is not None else d.get("samples", 256)
    n = whole_number("design.samples", n, minimum=2)
    if n > MAX_SAMPLES:
        raise HydroarmError("design.samples", f"at most {MAX_SAMPLES}, got {n}")
    seed = whole_number("design.seed", d.get("seed", 0), minimum=0)
    raw = d.get("objectives", [])
    if not isinstance(raw, list):
        raise HydroarmError("design.objectives", 'must be a list, e.g. ["max stall_mass"]')
    known = [*metrics, *var_names]
    objectives = tuple(_objective(f"design.objectives[{i}]", o, known) for i, o in enumerate(raw))
    if len({o.name for o in objectives}) != len(objectives):
        raise HydroarmError("design.objectives", "names a quantity twice")
    refine = None
    r = d.get("refine", False)
    if isinstance(r, bool):
        if r:
            if not objectives:
                raise HydroarmError("design.refine", "needs an objective (design.objectives)")
            refine = Refine(objective=objectives[0], seed=seed)
    else:
        rt = as_table("design.refine", r)
        reject_unknown_keys("design.refine", rt, REFINE_KEYS)
        if "objective" in rt:
            obj = _objective("design.refine.objective", rt["objective"], known)
        elif objectives:
            obj = objectives[0]
        else:
            raise HydroarmError("design.refine.objective", "is missing")
        generations = whole_number("design.refine.generations", rt.get("generations", 10))
        if generations > MAX_GENERATIONS:
            raise HydroarmError(
                "design.refine.generations", f"at most {MAX_GENERATIONS}, got {generations}"
            )
        population = whole_number("design.refine.population", rt.get("population", 16), 5)
        if population > MAX_POPULATION:
            raise HydroarmError(
                "design.refine.population", f"at most {MAX_POPULATION}, got {population}"
            )
        refine = Refine(
            objective=obj,
            generations=generations,
            population=population,
            seed=whole_number("design.refine.seed", rt.get("seed", seed), minimum=0),
        )
    chunk = whole_number("design.chunk", d.get("chunk", CHUNK))
    if chunk > MAX_SAMPLES:
        raise HydroarmError("design.chunk", f"at most {MAX_SAMPLES}, got {chunk}")
    return {
        "variables": variables,
        "objectives": objectives,
        "samples": n,
        "seed": seed,
        "refine": refine,
        "chunk": chunk,
    }


def design_from_doc(
    doc: dict,
    name: str = "design",
    *,
    samples: int | None = None,
    base_dir: Path = Path("."),
) -> DesignStudy:
    reject_unknown_keys("", doc, DESIGN_SECTIONS)
    joint = joint_from_table(
        "joint",
        optional_table(doc, "joint"),
        default_set="ucl-arm-measured",
        physics=optional_table(doc, "physics"),
        base_dir=base_dir,
    )
    if "load_case" not in doc:
        raise HydroarmError("load_case", "is missing (give [[load_case]] entries: name, load)")
    cases = read_load_cases(doc["load_case"])
    reqs = read_requirements(require_table(doc, "requirements"))
    check_cases(reqs, cases)
    d = require_table(doc, "design")
    search = read_search(d, _variable, list(METRICS), samples=samples)
    step = time_value("design.step", d["step"], positive=True) if "step" in d else DEFAULT_STEP
    study = DesignStudy(
        name=text_value("name", doc.get("name", name)),
        joint=joint,
        cases=cases,
        requirements=reqs,
        step=step,
        **search,
    )
    # ServoJoint validates every field at both corners of the design space (one-line errors)
    v = study.variables
    study.joints(np.array([[x.low for x in v], [x.high for x in v]]))
    return study


# --------------------------------------------------------------- evaluation ---
@dataclass
class DesignEvaluation:
    """The designs ``x`` (SI, one row each) and what the batch engine measured of them."""

    x: np.ndarray
    steps: np.ndarray  # solver step [s] of each design
    metrics: list  # per design: case_metrics' dictionary
    worst: np.ndarray  # (designs, requirements): each requirement's worst value
    margins: np.ndarray  # (designs, requirements): signed fraction of the limit
    objectives: np.ndarray  # (designs, objectives): each objective's worst value
    source: list = field(default_factory=list)

    @property
    def feasible(self) -> np.ndarray:
        return np.all(self.margins >= 0.0, axis=1)

    @property
    def smallest_margin(self) -> np.ndarray:
        return np.min(self.margins, axis=1)


def objective_value(study: DesignStudy, o: Objective, x_row, metrics: dict) -> float:
    """An objective's value for one design: a design variable's value, or the metric's
    worst value over the load cases (the smallest for "max", the largest for "min")."""
    names = [v.name for v in study.variables]
    if o.name in names:
        return float(x_row[names.index(o.name)])
    sense = "min" if o.sense == "max" else "max"  # the worst of a quantity to maximise: min
    return worst(Requirement(metric=o.name, limit=0.0, sense=sense), metrics)


def _safe_step(study: DesignStudy, joint: ServoJoint) -> float:
    try:
        return stable_step(joint, study.cases, study.step)
    except HydroarmError:
        return math.nan


def evaluate(
    study: DesignStudy, x: np.ndarray, source: str = "sobol", progress=None
) -> DesignEvaluation:
    """Evaluate designs ``x`` (one row per design, SI values of the study's variables) on
    the batch engine, ``study.chunk`` designs per batch (one ``progress`` call each)."""
    x = np.atleast_2d(np.asarray(x, float))
    joints = study.joints(x)
    steps = np.array([_safe_step(study, j) for j in joints])
    want = study.metrics()
    metrics: list[dict] = [{} for _ in joints]
    # designs of one simulated duration and step share a batch: chunks in that order
    ok = sorted(
        (i for i in range(len(joints)) if math.isfinite(steps[i])),
        key=lambda i: (motion_duration(joints[i]), steps[i]),
    )
    for k in range(0, len(ok), study.chunk):
        part = ok[k : k + study.chunk]
        got = case_metrics(
            [joints[i] for i in part],
            study.cases,
            metrics=want,
            step=[float(steps[i]) for i in part],
            keep_failures=True,
            grid_durations=True,
        )
        for i, m in zip(part, got, strict=True):
            metrics[i] = m
        if progress is not None:
            progress(f"design: {min(k + study.chunk, len(ok))}/{len(ok)} designs evaluated")
    reqs = study.requirements
    w = np.array([[worst(r, m) for r in reqs] for m in metrics]).reshape(len(x), len(reqs))
    margins = np.array(
        [[r.margin(float(v)) for r, v in zip(reqs, row, strict=True)] for row in w]
    ).reshape(len(x), len(reqs))
    obj = np.array(
        [
            [objective_value(study, o, x[i], metrics[i]) for o in study.objectives]
            for i in range(len(x))
        ]
    ).reshape(len(x), len(study.objectives))
    return DesignEvaluation(x, steps, metrics, w, margins, obj, [source] * len(x))


def merge(a: DesignEvaluation, b: DesignEvaluation) -> DesignEvaluation:
    return DesignEvaluation(
        np.vstack([a.x, b.x]),
        np.concatenate([a.steps, b.steps]),
        a.metrics + b.metrics,
        np.vstack([a.worst, b.worst]),
        np.vstack([a.margins, b.margins]),
        np.vstack([a.objectives, b.objectives]),
        a.source + b.source,
    )


def pareto_mask(objectives: np.ndarray, senses, feasible: np.ndarray) -> np.ndarray:
    """The feasible designs no other feasible design dominates: at least as good in every
    objective and better in one. With no objective, every feasible design."""
    f = np.asarray(feasible, bool)
    if objectives.shape[1] == 0:
        return f.copy()
    sign = np.array([-1.0 if s == "max" else 1.0 for s in senses])
    y = objectives * sign  # all minimised
    out = np.zeros(len(y), bool)
    idx = np.nonzero(f & ~np.any(np.isnan(y), axis=1))[0]  # ±inf compare as numbers
    for i in idx:
        others = y[idx]
        dom = np.all(others <= y[i], axis=1) & np.any(others < y[i], axis=1)
        out[i] = not dom.any()
    return out


def dominates(a, b, senses) -> bool:
    """Whether objective vector ``a`` dominates ``b`` (``senses``: "max"/"min" each)."""
    sign = np.array([-1.0 if s == "max" else 1.0 for s in senses])
    ya, yb = np.asarray(a) * sign, np.asarray(b) * sign
    return bool(np.all(ya <= yb) and np.any(ya < yb))


def sobol_points(study: SearchStudy) -> np.ndarray:
    """``study.samples`` scrambled Sobol points (seeded) mapped onto the variables [SI]."""
    from scipy.stats import qmc

    with warnings.catch_warnings():  # any number is allowed; a power of 2 keeps the balance
        warnings.filterwarnings("ignore", "The balance properties", UserWarning)
        sobol = qmc.Sobol(d=len(study.variables), scramble=True, seed=study.seed)
        u = sobol.random(study.samples)
    return np.column_stack([v.from_unit(u[:, i]) for i, v in enumerate(study.variables)])


def _refine(study: SearchStudy, start: DesignEvaluation, progress=None) -> DesignEvaluation:
    """Differential evolution on the refine objective (minimised; a "max" objective
    negated), every generation one batch; infeasible designs penalised by their violation.
    The population starts from the feasible Sobol designs (best margins first), filled up
    with the designs of largest smallest margin."""
    from scipy.optimize import differential_evolution

    ref = study.refine
    assert ref is not None
    logs = np.array([v.log for v in study.variables])
    lo = np.array([math.log(v.low) if v.log else v.low for v in study.variables])
    hi = np.array([math.log(v.high) if v.log else v.high for v in study.variables])
    sign = -1.0 if ref.objective.sense == "max" else 1.0
    start_vals = np.array(
        [study.objective_value(ref.objective, start.x[i], m) for i, m in enumerate(start.metrics)]
    )
    finite = start_vals[np.isfinite(start_vals)]
    # the objective in units of its spread over the Sobol designs
    scale = (float(np.ptp(finite)) or abs(float(finite[0])) or 1.0) if finite.size else 1.0
    # ... measured from the best Sobol value, so that feasible costs are of order one
    offset = float(np.min(sign * finite)) if finite.size else 0.0
    evals: list[DesignEvaluation] = []
    calls: list[int] = []  # new designs per generation

    def to_si(z: np.ndarray) -> np.ndarray:  # (n, S) DE vectors -> (S, n) SI designs
        x = np.array(np.atleast_2d(z.T), dtype=float)
        x[:, logs] = np.exp(x[:, logs])
        return x

    def known(x: np.ndarray) -> np.ndarray:
        """Index of the Sobol design each row of ``x`` is (to 1e-12, the round trip through
        the optimiser's scaling), or −1: those are not simulated again."""
        out = np.full(len(x), -1)
        for i, row in enumerate(x):
            hit = np.nonzero(np.all(np.isclose(start.x, row, rtol=1e-12, atol=0.0), axis=1))[0]
            if len(hit):
                out[i] = hit[0]
        return out

    def cost(z: np.ndarray) -> np.ndarray:
        x = to_si(z)
        k = known(x)
        new = np.nonzero(k < 0)[0]
        metrics: list = [start.metrics[i] if i >= 0 else None for i in k]
        margins = np.zeros((len(x), start.margins.shape[1]))
        margins[k >= 0] = start.margins[k[k >= 0]]
        if len(new):
            ev = study.evaluate(x[new], source="refine")
            evals.append(ev)
            for n, i in enumerate(new):
                metrics[i] = ev.metrics[n]
                margins[i] = ev.margins[n]
        if progress is not None:
            progress(f"design: refine generation {len(calls) + 1} ({len(new)} new designs)")
        calls.append(len(new))
        f = sign * np.array(
            [study.objective_value(ref.objective, x[i], m) for i, m in enumerate(metrics)]
        )
        f = (f - offset) / scale
        shortfall = -np.nan_to_num(margins, nan=-1e3, neginf=-1e3)
        violation = np.sum(np.clip(shortfall, 0.0, None), axis=1)
        # a feasible design always beats an infeasible one: feasible costs are held below
        # 500 (spreads from the best sampled value), the penalty starts at 1000
        bad = ~np.all(margins >= 0.0, axis=1) | ~np.isfinite(f)
        return np.where(bad, 1e3 + violation, np.minimum(f, 500.0))

    order = np.lexsort((-start.smallest_margin, ~start.feasible))
    init = np.array(start.x[order[: ref.population]], dtype=float)
    init[:, logs] = np.log(init[:, logs])
    if len(init) < ref.population:  # fewer Sobol designs than the population: random ones
        rng = np.random.default_rng(ref.seed)
        extra = lo + rng.random((ref.population - len(init), len(lo))) * (hi - lo)
        init = np.vstack([init, extra])
    init = np.clip(init, lo, hi)
    differential_evolution(
        cost,
        bounds=list(zip(lo, hi, strict=True)),
        init=init,
        maxiter=ref.generations,
        seed=ref.seed,
        vectorized=True,
        updating="deferred",
        polish=False,
        tol=0.0,
    )
    out = DesignEvaluation(
        np.empty((0, start.x.shape[1])),
        np.empty(0),
        [],
        np.empty((0, start.worst.shape[1])),
        np.empty((0, start.margins.shape[1])),
        np.empty((0, start.objectives.shape[1])),
    )
    for e in evals:
        out = merge(out, e)
    return out


@dataclass(repr=False)
class DesignResult(Summarised):
    """The designs of a study evaluated, and their Pareto front.

    Parameters
    ----------
    study : DesignStudy
        The study.
    evaluation : DesignEvaluation
        Every design's values (SI), metrics and requirement checks.
    pareto : numpy.ndarray
        Indices of the feasible designs on the Pareto front.
    elapsed_s : float
        Wall-clock time of the whole study [s].
    evaluation_s : float
        Wall-clock time of the designs' runs [s].
    """

    study: DesignStudy
    evaluation: DesignEvaluation
    pareto: np.ndarray
    elapsed_s: float
    evaluation_s: float

    def _summary(self) -> list[tuple[str, str]]:
        n = len(self.evaluation.x)
        return [
            ("study", self.study.name),
            ("designs", str(n)),
            ("feasible", f"{int(np.sum(self.feasible))} of {n}"),
            ("Pareto designs", str(int(np.sum(self.pareto)))),
            ("recommended", ", ".join(str(i) for i in self.recommended()) or "none"),
            ("time", f"{fmt(self.elapsed_s, 's', 3)} ({fmt(self.throughput(), '/s', 3)})"),
        ]

    @property
    def feasible(self) -> np.ndarray:
        return self.evaluation.feasible

    @property
    def scenarios(self) -> int:
        """Saturation tests simulated on the batch engine (designs × cases × directions)."""
        motions = sum(len(c.directions) for c in self.study.cases)
        return len(self.evaluation.x) * motions

    def throughput(self) -> float:
        """Designs × load cases per second, start-up (compilation, reading) included."""
        return len(self.evaluation.x) * len(self.study.cases) / self.elapsed_s

    def recommended(self, n: int = 5) -> list[int]:
        """Up to ``n`` Pareto designs (or, without any, feasible ones), largest smallest
        margin first."""
        pool = np.nonzero(self.pareto)[0]
        if not len(pool):
            pool = np.nonzero(self.feasible)[0]
        m = self.evaluation.smallest_margin[pool]
        return [int(i) for i in pool[np.argsort(-m, kind="stable")][:n]]

    # ------------------------------------------------------------ tables ---
    def columns(self) -> list[str]:
        s = self.study
        cols = ["design", "source", "solver_step_s"]
        cols += [column_name(v.name, v.unit) for v in s.variables]
        cols += [
            column_name(f"worst_{r.metric}", r.unit) + _suffix(s, i)
            for i, r in enumerate(s.requirements)
        ]
        cols += [
            column_name(f"objective_{o.sense}_{o.name}", _objective_unit(s, o))
            for o in s.objectives
        ]
        cols += [f"margin_{r.metric}{_suffix(s, i)}" for i, r in enumerate(s.requirements)]
        cols += ["smallest_margin", "feasible", "pareto"]
        return cols

    def rows(self) -> list[dict]:
        e = self.evaluation
        out = []
        cols = DesignResult.columns(self)  # a subclass's own columns come after these
        for i in range(len(e.x)):
            vals = [i + 1, e.source[i], float(e.steps[i])]
            vals += [repr(float(v)) for v in e.x[i]]  # every digit: the design can be re-run
            vals += [float(v) for v in e.worst[i]]
            vals += [float(v) for v in e.objectives[i]]
            vals += [float(v) for v in e.margins[i]]
            vals += [float(e.smallest_margin[i]), bool(e.feasible[i]), bool(self.pareto[i])]
            out.append(dict(zip(cols, vals, strict=True)))
        return out

    def csv(self) -> str:
        rows = [
            {k: (str(v).lower() if isinstance(v, bool) else v) for k, v in r.items()}
            for r in self.rows()
        ]
        return csv_text(self.columns(), rows)

    # ------------------------------------------------------------ output ---
    def write(self, out) -> Path:
        """designs.csv (and designs.parquet with pyarrow), pareto.png, feasibility.png and
        design_report.md, written into a staging folder and moved into ``out`` together."""
        out = Path(out)
        with staging_folder(out) as stage:
            names = list(OUTPUT_FILES)
            atomic_write_text(stage / "designs.csv", self.csv())
            if _parquet(self, stage / "designs.parquet"):
                names.append("designs.parquet")
            save_figure(self.pareto_figure(), stage / "pareto.png")
            save_figure(self.feasibility_figure(), stage / "feasibility.png")
            atomic_write_text(stage / "design_report.md", self.report())
            for fname, text in self.extra_files():
                atomic_write_text(stage / fname, text)
                names.append(fname)
            move_into(stage, out, names)
        return out

    def extra_files(self) -> list[tuple[str, str]]:
        """Further text files to write beside the others: (name, text) (a system study's
        ``cases.csv``)."""
        return []

    def _objective_labels(self) -> tuple[dict, dict]:
        s, e = self.study, self.evaluation
        vals, labels = {}, {}
        names = [v.name for v in s.variables]
        objs = list(s.objectives) or [Objective("max", "smallest_margin")]
        for k, o in enumerate(objs):
            if o.name == "smallest_margin":
                vals[o.name] = e.smallest_margin
                labels[o.name] = ("smallest margin", "")
                continue
            v = e.objectives[:, k]
            if o.name in names:
                unit = s.variables[names.index(o.name)].unit
            else:
                unit = METRICS[o.name][0]
            vals[o.name] = v
            labels[o.name] = (
                f"{o.name} ({'worst case, ' if o.name in METRICS else ''}{o.sense})",
                unit,
            )
        return vals, labels

    def pareto_figure(self):
        vals, labels = self._objective_labels()
        return pareto_figure(
            vals, labels, self.feasible, self.pareto, title=f"{self.study.name}: objectives"
        )

    def feasibility_figure(self):
        s, e = self.study, self.evaluation
        vals = {v.name: e.x[:, i] for i, v in enumerate(s.variables)}
        labels = {v.name: (v.name, v.unit) for v in s.variables}
        logs = [v.name for v in s.variables if v.log]
        return feasibility_figure(
            vals, labels, self.feasible, self.pareto, log=logs, title=f"{s.name}: feasibility"
        )

    def _variables_and_recommendation(self, lines: list[str], rerun: str) -> list[int]:
        """Append the report's "Design variables" (each range, feasible span) and the head of
        "Recommended designs" to ``lines``; return the designs to list (the recommended
        ones, or the closest to feasible). ``rerun``: a sentence on re-running one."""
        s, e = self.study, self.evaluation
        nf = int(self.feasible.sum())
        lines += ["", "## Design variables", ""]
        feas = self.feasible
        for i, v in enumerate(s.variables):
            u, f = display(v.unit)
            fr = (
                f"feasible from {e.x[feas, i].min() * f:.4g} to {e.x[feas, i].max() * f:.4g} {u}"
                if nf
                else "no feasible design"
            )
            lines.append(
                f"- {v.name}: {v.low * f:.4g} … {v.high * f:.4g} {u}"
                f"{' (log scale)' if v.log else ''}; {fr}".replace("  ", " ")
            )
        lines += ["", "## Recommended designs", ""]
        rec = self.recommended()
        if not rec:
            best = int(np.argmax(np.nan_to_num(e.smallest_margin, nan=-np.inf, neginf=-1e300)))
            lines.append(
                f"No design meets every requirement. Closest: design {best + 1} (smallest "
                f"margin {e.smallest_margin[best]:+.3f})."
            )
            rec = [best]
        else:
            lines.append(
                ("The Pareto designs" if self.pareto.any() else "The feasible designs")
                + " with the largest smallest margin (margin: signed fraction of the limit)."
                + (f" {rerun}" if rerun else "")
            )
        lines.append("")
        return rec

    def report(self) -> str:
        s, e = self.study, self.evaluation
        n = len(e.x)
        nf = int(self.feasible.sum())
        lines = [
            f"# Design study: {s.name}",
            "",
            f"{n} designs ({s.samples} scrambled Sobol points, seed {s.seed}"
            + (f", {n - s.samples} from the refinement" if n > s.samples else "")
            + f") × {len(s.cases)} load cases ({self.scenarios} saturation tests on the batch "
            f"engine); {nf} feasible, {int(self.pareto.sum())} on the Pareto front.",
            "",
            f"Time: {self.elapsed_s:.2f} s in all, start-up included ({self.evaluation_s:.2f} s "
            "evaluating; counted from the command's start: reading the file and loading the "
            "compiled kernels in, Python's own start and writing these files out); "
            f"{self.throughput():.3g} designs·cases per second, "
            f"{self.scenarios / self.elapsed_s:.3g} saturation tests per second.",
            "",
            "## Requirements",
            "",
        ]
        lines += [f"- `{r.label}`" for r in s.requirements]
        lines += ["", "## Load cases", ""]
        lines += [
            f"- {c.name}: {c.load.name} (W = {c.load.weight:.4g} N at X = {c.load.arm:.4g} m), "
            f"{', '.join(c.directions)}"
            for c in s.cases
        ]
        rec = self._variables_and_recommendation(lines, "")
        vu = [display(v.unit) for v in s.variables]
        ru = [display(r.unit) for r in s.requirements]
        head = ["design"] + [_head(v.name, u) for v, (u, _) in zip(s.variables, vu, strict=True)]
        head += [_head(r.metric, u) for r, (u, _) in zip(s.requirements, ru, strict=True)]
        head += [f"margin {r.metric}" for r in s.requirements]
        lines += ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
        for i in rec:
            cells = [str(i + 1)] + [f"{v * f:.4g}" for v, (_, f) in zip(e.x[i], vu, strict=True)]
            cells += [f"{v * f:.4g}" for v, (_, f) in zip(e.worst[i], ru, strict=True)]
            cells += [f"{m:+.3f}" for m in e.margins[i]]
            lines.append("| " + " | ".join(cells) + " |")
        if s.refine is not None:
            ref = s.refine
            names = [o.name for o in s.objectives]
            k = names.index(ref.objective.name) if ref.objective in s.objectives else None
            lines += ["", "## Refinement", ""]
            src = np.array(e.source)
            top = _best(self, ref.objective, k)
            lines.append(
                f"Differential evolution ({ref.generations} generations, population "
                f"{ref.population}, seed {ref.seed}) on `{ref.objective.label}`, feasibility as "
                f"a penalty: {int((src == 'refine').sum())} designs evaluated."
                + (f" Best feasible: design {top + 1}." if top is not None else "")
            )
        lines += ["", "![Pareto front](pareto.png)", "", "![Feasibility](feasibility.png)", ""]
        return "\n".join(lines)


def _head(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit else name


def _best(res: DesignResult, o: Objective, k) -> int | None:
    feas = np.nonzero(res.feasible)[0]
    if not len(feas) or k is None:
        return None
    v = res.evaluation.objectives[feas, k]
    return int(feas[np.argmax(v) if o.sense == "max" else np.argmin(v)])


def _suffix(study: DesignStudy, i: int) -> str:
    """``_2`` ... for a metric named by more than one requirement."""
    metric = study.requirements[i].metric
    same = [k for k, r in enumerate(study.requirements) if r.metric == metric]
    return "" if len(same) == 1 else f"_{same.index(i) + 1}"


def _objective_unit(study, o: Objective) -> str:
    """The SI unit of an objective's value: its design variable's, or its metric's."""
    for v in study.variables:
        if v.name == o.name:
            return v.unit
    unit_of = getattr(study, "unit_of", None)  # a system study's metrics
    if unit_of is not None:
        return unit_of(o.name)
    return METRICS[o.name][0] if o.name in METRICS else ""


def column_name(name: str, unit: str) -> str:
    """``piston_area_m2``, ``supply_pressure_pa``, ``flow_coefficient_m2_per_s_per_pa_sqrt``:
    the SI unit in the name, spelled as every result spells it (docs/model.md "Units in
    names")."""
    suffix = unit_suffix(unit)
    return f"{name}_{suffix}" if suffix and not name.endswith(f"_{suffix}") else name


def _parquet(res: DesignResult, path: Path) -> bool:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return False
    cols = res.columns()
    rows = res.rows()
    table = pa.table({c: [r[c] for r in rows] for c in cols})
    buf = io.BytesIO()
    pq.write_table(table, buf)
    atomic_write_bytes(path, buf.getvalue())
    return True


# ------------------------------------------------------------------ the study ---
def search(study: SearchStudy, progress=None) -> tuple[DesignEvaluation, np.ndarray, float]:
    """The designs of any study (the joint's, a system's): its Sobol designs, then the
    refinement, each batch one ``progress`` line; (evaluation, Pareto mask, seconds spent
    evaluating)."""
    chunks = -(-study.samples // study.chunk)
    gens = 0 if study.refine is None else study.refine.generations + 1
    tick = progress if progress is not None else Progress(chunks + gens)
    t_eval = time.perf_counter()
    ev = study.evaluate(sobol_points(study), progress=tick)
    if study.refine is not None:
        ev = merge(ev, _refine(study, ev, progress=tick))
    evaluation_s = time.perf_counter() - t_eval
    pareto = pareto_mask(ev.objectives, [o.sense for o in study.objectives], ev.feasible)
    return ev, pareto, evaluation_s


def run_design(study: DesignStudy, progress=None, *, t0: float | None = None) -> DesignResult:
    """Evaluate the Sobol designs (and the refinement) of ``study``. ``t0``: the
    `time.perf_counter` the run's time counts from (default: now)."""
    start = time.perf_counter() if t0 is None else t0
    ev, pareto, evaluation_s = search(study, progress)
    return DesignResult(study, ev, pareto, time.perf_counter() - start, evaluation_s)


def design(
    source,
    out=None,
    *,
    samples: int | None = None,
    progress=None,
    t0: float | None = None,
) -> DesignResult:
    """Run a design study and write its results.

    Parameters
    ----------
    source : str, pathlib.Path or DesignStudy
        A design file, or a [`DesignStudy`][hydroarm.DesignStudy] already read.
    out : str or pathlib.Path, optional
        Folder written (``designs.csv``, plots, ``design_report.md``); None writes nothing.
    samples : int, optional
        Number of candidate designs [-], in place of the file's ``[design] samples``.
    progress : callable, optional
        ``progress(label)``, called as the designs are evaluated (`Progress`).
    t0 : float, optional
        The `time.perf_counter` value [s] the reported time counts from (default: now).

    Returns
    -------
    DesignResult
        The evaluated designs, their Pareto front and the study.
    """
    t0 = time.perf_counter() if t0 is None else t0
    study = source if isinstance(source, DesignStudy) else read_design_file(source, samples=samples)
    res = run_design(study, progress, t0=t0)
    if out is not None:
        res.write(out)
    return res
