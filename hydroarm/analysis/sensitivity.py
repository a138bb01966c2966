"""Global variance-based sensitivity of a joint's metrics to its uncertain parameters
(issue 17, sensitivity part): Sobol first-order and total indices, or Morris screening, with
SALib, every sample run on the batch engine.

A sensitivity file names a starting joint (``[joint]``, as in scenario files), one load case
(``load`` and ``direction``) or several (``[[case]]``), the uncertain parameters with their
distributions and the metrics (``[sensitivity]``); the format, the method and its
assumptions are in docs/sensitivity.md. [`sensitivity`][hydroarm.sensitivity] samples the parameters
(SALib's Saltelli scheme for Sobol, Morris trajectories), runs every sample of every case as the
paper's saturation test ([`saturation_test`][hydroarm.saturation_test]) on the batch
engine (`run_scenarios`, one batch per chunk) and analyses
each metric with SALib. The sampling and the analysis (`Plan`, `run_plan`) take
any evaluator ``X -> {output: values}``, so an analytic test function with known indices runs
through the same code path as the joint.

Runs that fail (leave the physical bounds) give NaN metrics; a metric that is not finite in
one run of a Saltelli group (the N(D+2) runs are N groups of D+2) or of a Morris trajectory
(D+1 runs) drops that whole group from that metric's analysis, which keeps the estimators'
structure; the report counts the failed, stalled and dropped runs.
"""

from __future__ import annotations

import math
import re
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..batch.circuit_sweep import (
    TraceMetric,
    check_observed,
    is_circuit_study,
    output_units,
    run_circuit_chunk,
)
from ..batch.circuit_sweep import read_metrics as read_trace_metrics
from ..batch.tables import UNITS_NOTE, check_export, require_xarray, write_mat, write_netcdf
from ..core.servo import LOAD_MASS, PARAMETER_INDEX
from ..display import Summarised, fmt
from ..errors import HydroarmError
from ..files import atomic_write_text, check_output_folder, csv_text, move_into, staging_folder
from ..integrators import registry
from ..integrators.stability import rate_estimate
from ..io.catalog import paper_load
from ..io.circuit import parameter_of, parameter_value, value_in
from ..io.components import (
    check_sweep_name,
    is_component_file,
    servo_from_doc,
    sweep_dimension,
    sweep_names,
    sweep_rule,
    sweep_targets,
    sweep_value,
)
from ..io.progress import Progress
from ..io.schema import parse_load
from ..io.sections import (
    FIELD_DIMENSIONS,
    JOINT_KEYS,
    PHYSICS_KEYS,
    as_table,
    field_value,
    joint_from_table,
    number_or_quantity,
    optional_table,
    parse_toml,
    read_text_file,
    reject_unknown_keys,
    text_value,
    time_value,
    unknown_name,
    whole_number,
    within,
)
from ..io.system import study_circuit
from ..io.units import SI_UNITS, unit_suffix
from ..metrics.online import METRICS, run_scenarios
from ..metrics.servo import DEFAULT_BAND
from ..metrics.servo import METRIC_INDEX as SERVO_METRIC_INDEX
from ..metrics.servo import METRICS as SERVO_METRIC_KINDS
from ..model.circuit import Circuit, CompiledCircuit, build, row_initial_states
from ..model.joint import Load, ServoJoint
from ..model.scenario import Scenario, format_time, saturation_test
from ..model.servo import ServoScenario, servo_metrics_table
from ..plotting.joint import save_figure
from ..plotting.sensitivity import morris_figure, sobol_figure

# ServoJoint fields that can be uncertain (numbers; the stiffness is given through the volume)
UNCERTAIN = tuple(k for k in (*JOINT_KEYS, *PHYSICS_KEYS) if k != "hydraulic_stiffness")
METHODS = ("sobol", "morris")
SECTIONS = {"name", "description", "joint", "physics", "load", "direction", "case", "sensitivity"}
SENSITIVITY_KEYS = {
    "method",
    "samples",
    "seed",
    "metrics",
    "parameters",
    "levels",
    "resamples",
    "chunk",
    "solver",
}
CASE_KEYS = {"name", "load", "direction"}
SOLVER_KEYS = {"method", "step", "duration"}
DEFAULT_METRICS = ("saturation_velocity",)
JOINT_METRICS = tuple(m for m in METRICS if m != "failed")
DEFAULT_CHUNK = 1024  # scenarios per batch
MAX_RUNS = 2**20  # scenarios of one study
# Morris grid levels: 4 to 10 are usual; 100 already splits each range into 1 % steps, and
# SALib's sampler works on the grid (10⁹ levels ran until killed, issue 31)
MAX_LEVELS = 100
# bootstrap resamples of the indices: 1000 give 95 % intervals to about 1 % (Efron &
# Tibshirani); each one re-estimates every index from all the runs
MAX_RESAMPLES = 10_000
MAX_WORK = 10**12  # scenario-steps of one study (about 3 hours at 9·10⁷ scenario-steps/s)
GOVERNING = 10  # scenarios per case whose step is checked in full (the stiffest ones)
# the unit of each metric of the batch engine
METRIC_UNITS = {
    "saturation_velocity": "m/s",
    "time_constant_start": "s",
    "time_constant_start_velocity": "s",
    "time_constant_end": "s",
    "stalled": "",
    "reach": "m",
    "peak_pressure": "Pa",
    "final_x": "m",
    "failed": "",
}
SOBOL_COLUMNS = ("metric", "parameter", "S1", "S1_conf", "ST", "ST_conf")
MORRIS_COLUMNS = ("metric", "parameter", "mu_star", "mu_star_conf", "sigma")


# --------------------------------------------------------------- the plan ---
@dataclass(frozen=True)
class Parameter:
    """One uncertain input: uniform on [a, b] or normal with mean a and sd b [SI]."""

    name: str
    distribution: str  # "uniform" | "normal"
    a: float
    b: float
    unit: str = ""

    def describe(self) -> str:
        u = f" {self.unit}" if self.unit else ""
        if self.distribution == "uniform":
            return f"uniform {self.a:.4g} … {self.b:.4g}{u}"
        return f"normal, mean {self.a:.4g}{u}, sd {self.b:.3g}{u}"


@dataclass(frozen=True)
class Plan:
    """The sampling and the analysis, independent of the model: ``samples`` is the base
    sample N of Sobol (a power of 2; N(D+2) runs) or the number of Morris trajectories
    (N(D+1) runs); ``resamples`` bootstrap resamples give the 95 % confidence intervals."""

    parameters: tuple[Parameter, ...]
    method: str = "sobol"
    samples: int = 256
    seed: int = 0
    levels: int = 4  # Morris grid levels
    resamples: int = 100

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def group(self) -> int:
        """Runs per Saltelli group (D+2) or Morris trajectory (D+1)."""
        d = len(self.parameters)
        return d + 2 if self.method == "sobol" else d + 1

    @property
    def runs(self) -> int:
        return self.samples * self.group

    def problem(self) -> dict:
        return {
            "num_vars": len(self.parameters),
            "names": self.names,
            "bounds": [[p.a, p.b] for p in self.parameters],
            "dists": ["unif" if p.distribution == "uniform" else "norm" for p in self.parameters],
        }

    def sample(self) -> np.ndarray:
        """The (runs, D) inputs [SI]: Saltelli's scheme on a scrambled Sobol' sequence, or
        Morris trajectories."""
        if self.method == "sobol":
            from SALib.sample import sobol

            return sobol.sample(
                self.problem(), self.samples, calc_second_order=False, seed=self.seed
            )
        from SALib.sample import morris

        return morris.sample(self.problem(), self.samples, num_levels=self.levels, seed=self.seed)

    def analyse(self, X: np.ndarray, y: np.ndarray) -> tuple[dict, int]:
        """SALib's indices of one output ``y`` (one value per row of ``X``): groups with a
        non-finite value are left out. Returns (indices by name, groups used)."""
        g = self.group
        ok = np.isfinite(y).reshape(-1, g).all(axis=1)
        used = int(ok.sum())
        keep = np.repeat(ok, g)
        d = len(self.parameters)
        nan = np.full(d, math.nan)
        yk = y[keep]
        if used < 2 or np.ptp(yk) == 0.0:  # nothing to apportion
            keys = (
                ("S1", "S1_conf", "ST", "ST_conf") if self.method == "sobol" else MORRIS_COLUMNS[2:]
            )
            return {k: nan.copy() for k in keys}, used
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if self.method == "sobol":
                from SALib.analyze import sobol

                r = sobol.analyze(
                    self.problem(),
                    yk,
                    calc_second_order=False,
                    num_resamples=self.resamples,
                    conf_level=0.95,
                    seed=self.seed,
                )
                return {k: np.asarray(r[k], float) for k in SOBOL_COLUMNS[2:]}, used
            from SALib.analyze import morris

            r = morris.analyze(
                self.problem(),
                X[keep],
                yk,
                num_resamples=self.resamples,
                conf_level=0.95,
                num_levels=self.levels,
                seed=self.seed,
            )
            return {k: np.asarray(r[k], float) for k in MORRIS_COLUMNS[2:]}, used


Evaluator = Callable[[np.ndarray], dict]


@dataclass(repr=False)
class SensitivityResult(Summarised):
    """Inputs, outputs and indices of a sensitivity study.

    Parameters
    ----------
    plan : Plan
        The sampling plan.
    X : numpy.ndarray
        The samples, one row per sample (SI).
    outputs : dict
        Output label → values (NaN: failed or not measured).
    rows : list
        The indices: the table of ``sensitivity.csv`` (Sobol) or ``morris.csv`` (Morris).
    used : dict
        Output label → the groups used in its analysis.
    elapsed_s : float
        Wall-clock time of the runs [s].
    total_s : float
        Wall-clock time of the sampling, the runs and the analysis [s].
    name : str
        Label.
    units : dict
        Output label → unit.
    notes : list
        Failed or stalled runs and their treatment.
    extra : dict
        More columns of ``samples.csv``.
    description : list
        Lines about the model (the report).
    per_sample : int
        Scenarios run per sample (one per load case) [-].
    """

    plan: Plan
    X: np.ndarray
    outputs: dict  # output label -> values (NaN: failed or not measured)
    rows: list
    used: dict  # output label -> groups used in its analysis
    elapsed_s: float  # evaluation (the runs)
    total_s: float  # sampling, runs and analysis
    name: str = "sensitivity"
    units: dict = field(default_factory=dict)  # output label -> unit
    notes: list = field(default_factory=list)  # failed / stalled runs and their treatment
    extra: dict = field(default_factory=dict)  # more columns of samples.csv
    description: list = field(default_factory=list)  # lines about the model (the report)
    per_sample: int = 1  # scenarios run per sample (one per load case)

    def _summary(self) -> list[tuple[str, str]]:
        return [
            ("study", self.name),
            ("method", f"{self.plan.method}, {self.plan.samples} samples"),
            ("parameters", ", ".join(self.plan.names)),
            ("outputs", ", ".join(self.outputs)),
            ("runs", f"{self.runs} in {fmt(self.total_s, 's', 3)}"),
        ]

    @property
    def runs(self) -> int:
        """Samples (rows of ``X``)."""
        return int(self.X.shape[0])

    @property
    def scenarios(self) -> int:
        return self.runs * self.per_sample

    @property
    def rate(self) -> float:
        """Scenarios per second of the evaluation."""
        return self.scenarios / self.elapsed_s if self.elapsed_s > 0 else math.inf

    @property
    def columns(self) -> tuple[str, ...]:
        return SOBOL_COLUMNS if self.plan.method == "sobol" else MORRIS_COLUMNS

    @property
    def table_name(self) -> str:
        return "sensitivity.csv" if self.plan.method == "sobol" else "morris.csv"

    def index(self, output: str, parameter: str, key: str) -> float:
        """One index (e.g. ``ST``) of one output and parameter."""
        for r in self.rows:
            if r["metric"] == output and r["parameter"] == parameter:
                return float(r[key])
        raise KeyError((output, parameter))

    def table_text(self) -> str:
        return csv_text(self.columns, self.rows)

    def sample_columns(self) -> dict[str, str]:
        """samples.csv's column of each parameter and output: its name with its SI unit
        (``flow_coefficient_m2_per_s_per_pa_sqrt``, ``saturation_velocity_m_s``; a circuit
        output's name has its unit already; docs/model.md "Units in names")."""
        units = {**{p.name: p.unit for p in self.plan.parameters}, **self.units}
        out = {}
        for k in (*self.plan.names, *self.outputs):
            suffix = unit_suffix(units.get(k, ""))
            out[k] = f"{k}_{suffix}" if suffix else k
        return out

    def samples_text(self) -> str:
        named = self.sample_columns()
        header = ["run", *(named[k] for k in (*self.plan.names, *self.outputs)), *self.extra]
        cols = {**dict(zip(self.plan.names, self.X.T, strict=True)), **self.outputs}
        lines = [",".join(header)]
        for i in range(self.runs):
            vals = [str(i)]
            vals += [_num(cols[k][i]) for k in (*self.plan.names, *self.outputs)]
            vals += [str(self.extra[k][i]) for k in self.extra]
            lines.append(",".join(vals))
        return "\n".join(lines) + "\n"

    def index_arrays(self) -> tuple[list[str], list[str], dict[str, np.ndarray]]:
        """(metrics, parameters, {index: metrics × parameters array}) of `rows`."""
        metrics = list(dict.fromkeys(r["metric"] for r in self.rows))
        params = list(self.plan.names)
        arrays = {c: np.full((len(metrics), len(params)), np.nan) for c in self.columns[2:]}
        for r in self.rows:
            i, j = metrics.index(r["metric"]), params.index(r["parameter"])
            for c in arrays:
                arrays[c][i, j] = r[c]
        return metrics, params, arrays

    def sample_arrays(self) -> dict[str, np.ndarray]:
        """samples.csv's columns (its names, with units) as arrays: the run numbers, each
        parameter's samples, each output's values, the extra columns."""
        named = self.sample_columns()
        cols: dict[str, np.ndarray] = {"run": np.arange(self.runs)}
        for i, k in enumerate(self.plan.names):
            cols[named[k]] = self.X[:, i]
        for k, v in self.outputs.items():
            cols[named[k]] = np.asarray(v, float)
        for k, v in self.extra.items():
            cols[k] = np.asarray(v)
        return cols

    def to_xarray(self):
        """The study as one xarray dataset: the samples along ``run`` (samples.csv's columns)
        and the indices (``S1``, ``S1_conf``, ``ST``, ``ST_conf`` or ``mu_star``,
        ``mu_star_conf``, ``sigma``) along ``metric`` × ``parameter``. Needs xarray."""
        xr = require_xarray("to_xarray")
        metrics, params, arrays = self.index_arrays()
        samples = self.sample_arrays()
        run = samples.pop("run")
        data: dict = {k: ("run", _text_or_values(v)) for k, v in samples.items()}
        data.update({k: (("metric", "parameter"), v) for k, v in arrays.items()})
        attrs = {
            "title": self.name,
            "method": self.plan.method,
            "samples": self.plan.samples,
            "seed": self.plan.seed,
            "units": UNITS_NOTE,
            "metric_units": "; ".join(f"{k}: {u or '1'}" for k, u in self.units.items()),
        }
        coords = {"run": run, "metric": metrics, "parameter": params}
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def to_netcdf(self, path) -> Path:
        return write_netcdf(path, self.to_xarray())

    def to_mat(self, path) -> Path:
        """The samples (one variable per column of samples.csv) and the indices (one
        metrics × parameters matrix each, ``metric`` and ``parameter`` as cell arrays)."""
        metrics, params, arrays = self.index_arrays()
        variables = {
            **self.sample_arrays(),
            "metric": np.array(metrics, dtype=object),
            "parameter": np.array(params, dtype=object),
            **arrays,
        }
        return write_mat(path, variables, header=f"{self.name} ({self.plan.method}): {UNITS_NOTE}")

    def write(self, out, export=()) -> Path:
        """Write the table, samples.csv, one bar chart per output and sensitivity_report.md
        into ``out`` (staged, then moved in: the folder never holds half a study); ``export``
        (``"netcdf"``, ``"mat"``): also sensitivity.nc, sensitivity.mat."""
        formats = check_export(export)
        out = check_output_folder("--out", out)
        with staging_folder(out) as stage:
            atomic_write_text(stage / self.table_name, self.table_text())
            atomic_write_text(stage / "samples.csv", self.samples_text())
            plots = [self._plot(stage, i, k) for i, k in enumerate(self.outputs)]
            atomic_write_text(stage / "sensitivity_report.md", self.report(plots))
            extra = []
            if "netcdf" in formats:
                extra.append(self.to_netcdf(stage / "sensitivity.nc").name)
            if "mat" in formats:
                extra.append(self.to_mat(stage / "sensitivity.mat").name)
            move_into(
                stage,
                out,
                [self.table_name, "samples.csv", *plots, "sensitivity_report.md", *extra],
            )
        return out

    def _plot(self, stage: Path, i: int, output: str) -> str:
        rows = [r for r in self.rows if r["metric"] == output]
        names = [r["parameter"] for r in rows]

        def col(k):
            return np.array([r[k] for r in rows], float)

        if self.plan.method == "sobol":
            fig = sobol_figure(
                names,
                col("S1"),
                col("S1_conf"),
                col("ST"),
                col("ST_conf"),
                metric=output,
                runs=self.runs,
            )
        else:
            fig = morris_figure(
                names,
                col("mu_star"),
                col("mu_star_conf"),
                col("sigma"),
                metric=output,
                unit=self.units.get(output, ""),
                runs=self.runs,
            )
        name = f"sensitivity_{i + 1}_{_slug(output)}.png"
        save_figure(fig, stage / name)
        return name

    def report(self, plots=()) -> str:
        p = self.plan
        method = (
            "Sobol first-order and total indices (SALib: Saltelli's scheme on a scrambled "
            "Sobol' sequence; first order by Saltelli et al. 2010, total by Jansen 1999)"
            if p.method == "sobol"
            else f"Morris screening ({p.levels} levels, SALib)"
        )
        size = (
            f"base sample N = {p.samples}, D = {len(p.parameters)} parameters: "
            f"N·(D+2) = {self.runs} runs"
            if p.method == "sobol"
            else f"{p.samples} trajectories, D = {len(p.parameters)}: N·(D+1) = {self.runs} runs"
        )
        lines = [
            f"# Sensitivity: {self.name}",
            "",
            f"Method: {method}; seed {p.seed}; 95 % confidence intervals from "
            f"{p.resamples} bootstrap resamples.",
            "",
            f"Sample size: {size}.",
            "",
            f"Time: {self.elapsed_s:.2f} s for the {self.scenarios} scenarios "
            f"({self.rate:.4g} scenarios per second), "
            f"{self.total_s:.2f} s in all (sampling, runs, analysis).",
            "",
            *self.description,
            "## Parameters",
            "",
            "| parameter | distribution |",
            "|---|---|",
            *(f"| {q.name} | {q.describe()} |" for q in p.parameters),
            "",
            "## Runs",
            "",
        ]
        dropped = [
            f"- {k}: {p.samples - u} of {p.samples} groups left out (a non-finite value in "
            f"the group); the indices use {u}."
            for k, u in self.used.items()
            if u < p.samples
        ]
        lines += [*self.notes, *dropped] or ["Every run finished and every metric was measured."]
        lines += ["", "## Indices", ""]
        cols = self.columns[1:]
        lines += ["| metric | " + " | ".join(cols) + " |", "|---" * (len(cols) + 1) + "|"]
        for r in self.rows:
            lines.append(
                f"| {r['metric']} | {r['parameter']} | "
                + " | ".join(_num(r[c], 3) for c in cols[1:])
                + " |"
            )
        if p.method == "morris":
            lines += ["", "μ* and σ are in the metric's unit (per full range of the parameter)."]
        units = ", ".join(f"{k} [{u or '1'}]" for k, u in self.units.items())
        lines += ["", f"Metric units: {units}."]
        lines += [""] + [f"![{q}]({q})" for q in plots]
        return "\n".join(lines) + "\n"


def _text_or_values(v) -> np.ndarray:
    a = np.asarray(v)
    return a.astype(str) if a.dtype.kind == "O" else a


def _num(v, digits: int = 9) -> str:
    v = float(v)
    return "" if math.isnan(v) else f"{v:.{digits}g}"


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_") or "output"


def run_plan(
    plan: Plan, evaluate: Evaluator, *, name: str = "sensitivity", units=None
) -> SensitivityResult:
    """Sample ``plan``, evaluate the samples (``evaluate(X) -> {output: values}``; NaN for a
    value that could not be measured) and analyse every output."""
    t0 = time.perf_counter()
    X = plan.sample()
    t1 = time.perf_counter()
    outputs = {k: np.asarray(v, float) for k, v in evaluate(X).items()}
    t2 = time.perf_counter()
    rows, used = [], {}
    for k, y in outputs.items():
        if y.shape != (X.shape[0],):
            raise HydroarmError("evaluate", f"{k}: one value per sample needed, got {y.shape}")
        ind, used[k] = plan.analyse(X, y)
        for i, q in enumerate(plan.names):
            rows.append({"metric": k, "parameter": q, **{c: float(v[i]) for c, v in ind.items()}})
    return SensitivityResult(
        plan=plan,
        X=X,
        outputs=outputs,
        rows=rows,
        used=used,
        elapsed_s=t2 - t1,
        total_s=time.perf_counter() - t0,
        name=name,
        units=dict(units or {}),
    )


# ------------------------------------------------------------- the joint ---
@dataclass(frozen=True)
class Case:
    """One saturation test: a load and a direction."""

    name: str
    load: Load
    direction: str


@dataclass(frozen=True)
class SensitivityStudy:
    """A sensitivity file (docs/sensitivity.md): the joint, its cases, the plan and the metrics.

    Parameters
    ----------
    joint : ServoJoint
        The base joint.
    cases : tuple of Case
        The load cases (one run each per sample).
    plan : Plan
        The sampling plan: method (Sobol or Morris), samples, the parameters and their ranges.
    metrics : tuple of str
        The outputs: step metrics of each case.
    method : str
        Fixed-step integration method.
    step : float, optional
        Fixed step [s] (None: the scenario's default).
    duration : float, optional
        Simulated time [s] (None: the longest default of the samples).
    chunk : int
        Samples per batch run [-].
    name : str
        Label.
    """

    joint: ServoJoint
    cases: tuple[Case, ...]
    plan: Plan
    metrics: tuple[str, ...] = DEFAULT_METRICS
    method: str = "euler"  # integration method
    step: float | None = None  # [s]; None: the scenario's default
    duration: float | None = None  # [s]; None: the longest default of the samples
    chunk: int = DEFAULT_CHUNK
    name: str = "sensitivity"

    def label(self, case: Case, metric: str) -> str:
        """An output's name: the metric, prefixed by the case when there are several."""
        return metric if len(self.cases) == 1 else f"{case.name}:{metric}"


class JointModel:
    """The evaluator of a [`SensitivityStudy`][hydroarm.SensitivityStudy]: every sample of every
    case as a saturation test on the batch engine, one batch per chunk, with progress. Every
    sample's joint and scenario are built (and so validated) and the step checked before the first
    run; the scenarios are built again chunk by chunk, so memory does not grow with N."""

    def __init__(self, study: SensitivityStudy, progress=None):
        self.study = study
        self.progress = progress
        self.failed: dict = {}  # case name -> {reason: count}
        self.stalled: dict = {}  # case name -> count
        self.extra: dict = {}  # samples.csv columns: why a run failed
        self.duration = math.nan

    def joint(self, X: np.ndarray, i: int) -> ServoJoint:
        """Sample ``i``'s joint (a bad value: one error naming the parameter and sample)."""
        st = self.study
        names = st.plan.names
        try:
            return st.joint.replace(**dict(zip(names, map(float, X[i]), strict=True)))
        except HydroarmError as exc:
            key = exc.field.rsplit(".", 1)[-1]
            where = "sensitivity.parameters" + (f".{key}" if key in names else "")
            values = ", ".join(f"{k} = {v:.4g}" for k, v in zip(names, X[i], strict=True))
            raise HydroarmError(
                where, f"sample {i} ({values}): {exc.problem} (narrow the range or distribution)"
            ) from None

    def scenario(self, X: np.ndarray, i: int, case: Case, joint=None) -> Scenario:
        """Sample ``i`` in ``case`` (with the study's duration once it is known)."""
        st = self.study
        kw: dict = {"method": st.method}
        if st.step is not None:
            kw["step"] = st.step
        if not math.isnan(self.duration):
            kw["duration"] = self.duration
        try:
            return saturation_test(
                self.joint(X, i) if joint is None else joint, case.load, case.direction, **kw
            )
        except HydroarmError as exc:
            if exc.field.startswith("solver"):
                raise HydroarmError(f"sensitivity.{exc.field}", exc.problem) from None
            raise HydroarmError(
                "sensitivity.parameters", f"sample {i}, case {case.name}: {exc}"
            ) from None

    def prepare(self, X: np.ndarray) -> None:
        """Build every sample's joint and scenario, fix the common duration (the given one,
        or the longest default), bound the work and check the step on the stiffest samples
        of each case (`rate_estimate`, then the check
        ``simulate`` makes): everything before the first run."""
        st = self.study
        n = X.shape[0]
        longest = 0.0
        rates = np.empty((len(st.cases), n))
        for i in range(n):
            j = self.joint(X, i)
            for k, c in enumerate(st.cases):
                sc = self.scenario(X, i, c, j)
                longest = max(longest, sc.duration)
                rates[k, i] = rate_estimate(
                    j.piston_area,
                    j.trapped_volume,
                    j.bulk_modulus,
                    j.crank_radius,
                    j.gear_ratio,
                    c.load.inertia,
                    j.leakage_coefficient,
                    j.viscous_friction,
                )
        self.duration = st.duration if st.duration is not None else longest
        runs = n * len(st.cases)
        steps = self.scenario(X, 0, st.cases[0]).nsteps
        if runs * steps > MAX_WORK:
            raise HydroarmError(
                "sensitivity.samples",
                f"{runs} runs × {steps} steps = {runs * steps:.3g} scenario-steps "
                f"(at most {MAX_WORK:.0e}): fewer samples, parameters or a shorter duration",
            )
        for k, c in enumerate(st.cases):
            for i in np.argsort(-rates[k], kind="stable")[:GOVERNING]:
                try:
                    self.scenario(X, int(i), c).check_step()
                except HydroarmError as exc:
                    raise HydroarmError(
                        "sensitivity.solver.step", f"sample {int(i)}, case {c.name}: {exc.problem}"
                    ) from None

    def __call__(self, X: np.ndarray) -> dict:
        st = self.study
        self.prepare(X)
        n = X.shape[0]
        jobs = [(k, i) for k in range(len(st.cases)) for i in range(n)]
        values = {m: np.full((len(st.cases), n), math.nan) for m in st.metrics}
        stalled = np.zeros((len(st.cases), n), bool)
        reasons = [[""] * n for _ in st.cases]
        chunks = range(0, len(jobs), st.chunk)
        tick = self.progress or Progress(len(chunks))
        for lo in chunks:
            part = jobs[lo : lo + st.chunk]
            scs = [self.scenario(X, i, st.cases[k]) for k, i in part]
            for (k, i), m in zip(part, run_scenarios(scs), strict=True):
                if m["failure"]:
                    reasons[k][i] = m["failure"]
                    continue
                stalled[k, i] = m["stalled"] > 0.5
                for metric in st.metrics:
                    values[metric][k, i] = m[metric]
            tick(f"{lo + len(part)}/{len(jobs)} scenarios")
        out = {}
        for k, c in enumerate(st.cases):
            fails: dict = {}
            for r in reasons[k]:
                if r:
                    fails[r] = fails.get(r, 0) + 1
            self.failed[c.name] = fails
            self.stalled[c.name] = int(stalled[k].sum())
            self.extra["failure" if len(st.cases) == 1 else f"{c.name}:failure"] = reasons[k]
            for metric in st.metrics:
                out[st.label(c, metric)] = values[metric][k]
        return out

    def notes(self) -> list[str]:
        lines = []
        for c in self.study.cases:
            f = self.failed.get(c.name, {})
            s = self.stalled.get(c.name, 0)
            if f:
                why = ", ".join(f"{v} {k}" for k, v in f.items())
                lines.append(
                    f"- {c.name}: {sum(f.values())} runs failed ({why}); their metrics are NaN "
                    "and their groups are left out of the analysis."
                )
            if s:
                lines.append(
                    f"- {c.name}: {s} runs stalled (stopped short of the target); they are "
                    "kept, with their metrics measured over the motion they made (a metric "
                    "that could not be measured is NaN and its group is left out)."
                )
        return lines


def sensitivity(source, out=None, *, progress=None, export=()) -> SensitivityResult:
    """Run a sensitivity study and write its results.

    Parameters
    ----------
    source : str, pathlib.Path, SensitivityStudy or ServoStudy
        A sensitivity file, or a [`SensitivityStudy`][hydroarm.SensitivityStudy] or
        `ServoStudy` already read.
    out : str or pathlib.Path, optional
        Folder written (the samples, the indices, plots); None writes nothing.
    progress : callable, optional
        ``progress(label)``, called as the samples run (`Progress`).
    export : tuple of str
        ``"netcdf"`` and/or ``"mat"``: also ``sensitivity.nc`` and/or ``sensitivity.mat``
        ([`SensitivityResult.write`][hydroarm.SensitivityResult.write]).

    Returns
    -------
    SensitivityResult
        The samples, the outputs and the indices.
    """
    export = check_export(export)
    study = (
        source
        if isinstance(source, (SensitivityStudy, ServoStudy, CircuitStudy))
        else read_sensitivity_file(source)
    )
    if out is not None:
        check_output_folder("--out", out)
    if isinstance(study, (CircuitStudy, ServoStudy)):
        evaluator: CircuitModel | ServoModel = (
            CircuitModel(study, progress)
            if isinstance(study, CircuitStudy)
            else ServoModel(study, progress)
        )
        res = run_plan(study.plan, evaluator, name=study.name, units=study.units())
        res.notes, res.extra = evaluator.notes(), evaluator.extra
        res.description = [study.describe(), ""]
    else:
        model = JointModel(study, progress)
        units = {study.label(c, m): METRIC_UNITS[m] for c in study.cases for m in study.metrics}
        res = run_plan(study.plan, model, name=study.name, units=units)
        res.notes, res.extra = model.notes(), model.extra
        res.description = describe(study, model)
        res.per_sample = len(study.cases)
    if out is not None:
        res.write(out, export)
    return res


def describe(study: SensitivityStudy, model: JointModel) -> list[str]:
    cases = "; ".join(f"{c.name} ({c.load.name}, {c.direction})" for c in study.cases)
    step = study.step if study.step is not None else 10e-6
    return [
        f"Model: the joint '{study.joint.name}' in the paper's saturation test, cases: {cases}; "
        f"{study.method} at {format_time(step)} for {model.duration:g} s per run (the batch "
        "engine, hydroarm.metrics.online).",
        "",
    ]


# ------------------------------------------------------ component servos ---
SERVO_SENSITIVITY_KEYS = SENSITIVITY_KEYS - {"solver"} | {"settling_band"}
SERVO_METRICS = tuple(k for k, _ in SERVO_METRIC_KINDS if k not in ("failed", "failure_time"))
DEFAULT_SERVO_METRICS = ("settling_time", "overshoot", "peak_pressure")


@dataclass(frozen=True)
class ServoStudy:
    """A sensitivity file of a servo built from components (it has ``[actuator]``): the base
    servo (its reference and solver are those of every run), the plan and the metrics of
    `hydroarm.metrics.servo.METRICS` by name; parameters by their sweep names
    (`hydroarm.io.components.sweep_names`: ``overlap`` sets the four laps)."""

    base: ServoScenario
    plan: Plan
    metrics: tuple[str, ...] = DEFAULT_SERVO_METRICS
    band: float = DEFAULT_BAND
    chunk: int = DEFAULT_CHUNK
    name: str = "sensitivity"

    @property
    def cases(self) -> tuple:
        return ()

    def units(self) -> dict:
        linear = self.base.parameters.get("load_kind", LOAD_MASS) == LOAD_MASS
        kinds = dict(SERVO_METRIC_KINDS)
        unit = {
            "position": "m" if linear else "rad",
            "velocity": "m/s" if linear else "rad/s",
            "pressure": "Pa",
            "length": "m",
            "energy": "J",
            "time": "s",
            "fraction": "",
        }
        return {m: unit[kinds[m]] for m in self.metrics}

    def describe(self) -> str:
        b = self.base
        return (
            f"Model: the component servo '{b.name}' ({b.method} at {format_time(b.step)} for "
            f"{b.duration:g} s per run; settling band {self.band:g} of the step), on the "
            "component servos' batch path (hydroarm.model.servo_observers.servo_metrics_many)."
        )

    def scenario(self, row) -> ServoScenario:
        """The base servo with one sample's values."""
        kw = {
            t: float(v) for k, v in zip(self.plan.names, row, strict=True) for t in sweep_targets(k)
        }
        return self.base.replace(**kw)


class ServoModel:
    """The evaluator of a `ServoStudy`: every sample on the component servos' batch
    path (`servo_metrics_table`: the servos' circuits observed on the system kernel,
    `hydroarm.model.servo_observers.servo_metrics_many`), one batch per chunk, with progress.
    The samples' sign rules and the step (the base and the samples at the extremes of each
    parameter) are checked before the first run."""

    def __init__(self, study: ServoStudy, progress=None):
        self.study = study
        self.progress = progress
        self.failed = 0
        self.unsettled = 0
        self.extra: dict = {}

    def scenarios(self, X: np.ndarray) -> list[ServoScenario]:
        st = self.study
        for i, k in enumerate(st.plan.names):
            rule = sweep_rule(k)
            v = X[:, i]
            bad = ~np.isfinite(v)
            if rule == "positive":
                bad |= ~(v > 0)
            elif rule == "nonnegative":
                bad |= ~(v >= 0)
            if np.any(bad):
                r = int(np.argmax(bad))
                words = {"positive": "must be positive", "nonnegative": "must not be negative"}
                raise HydroarmError(
                    f"sensitivity.parameters.{k}",
                    f"sample {r}: {words.get(rule, 'must be finite')}, got {v[r]:.6g} "
                    "(narrow the range or distribution)",
                )
        with within("solver"):
            st.base.check_step()
        rows: list[int] = []
        for i in range(X.shape[1]):
            for r in (int(np.argmin(X[:, i])), int(np.argmax(X[:, i]))):
                if r not in rows:
                    rows.append(r)
        for r in rows[:GOVERNING]:
            try:
                st.scenario(X[r]).check_step()
            except HydroarmError as exc:
                raise HydroarmError("solver.step", f"sample {r}: {exc.problem}") from None
        return [st.scenario(row) for row in X]

    def __call__(self, X: np.ndarray) -> dict:
        st = self.study
        scs = self.scenarios(X)
        chunks = range(0, len(scs), st.chunk)
        tick = self.progress or Progress(len(chunks))
        parts = []
        for lo in chunks:
            parts.append(servo_metrics_table(scs[lo : lo + st.chunk], st.band))
            tick(f"{min(lo + st.chunk, len(scs))}/{len(scs)} scenarios")
        M = np.vstack(parts)
        failed = M[:, SERVO_METRIC_INDEX["failed"]] > 0.5
        self.failed = int(failed.sum())
        self.unsettled = int(
            np.sum(~failed & ~np.isfinite(M[:, SERVO_METRIC_INDEX["settling_time"]]))
        )
        t_fail = M[:, SERVO_METRIC_INDEX["failure_time"]]
        self.extra["failure"] = [
            f"failed at {t:.6g} s" if f else "" for f, t in zip(failed, t_fail, strict=True)
        ]
        out = {}
        for m in st.metrics:
            v = M[:, SERVO_METRIC_INDEX[m]].astype(float)
            v[failed] = math.nan
            out[m] = v
        return out

    def notes(self) -> list[str]:
        lines = []
        if self.failed:
            lines.append(
                f"- {self.failed} runs failed (left the physical bounds); their metrics are "
                "NaN and their groups are left out of the analysis."
            )
        if self.unsettled and "settling_time" in self.study.metrics:
            lines.append(
                f"- {self.unsettled} runs did not settle within the band; their settling "
                "time is NaN and their groups are left out of its analysis."
            )
        return lines


def servo_study_from_doc(doc: dict, name: str, base_dir: Path) -> ServoStudy:
    servo_doc = {k: v for k, v in doc.items() if k != "sensitivity"}
    base = servo_from_doc(servo_doc, base_dir, name)
    if not registry.method(base.method).fixed_step:
        raise HydroarmError(
            "solver.method",
            f"a sensitivity study runs {' or '.join(registry.fixed_step_methods())}",
        )
    sec = sensitivity_section(doc, SERVO_SENSITIVITY_KEYS)
    metrics = read_metrics(sec.get("metrics", list(DEFAULT_SERVO_METRICS)), SERVO_METRICS)
    band = DEFAULT_BAND
    if "settling_band" in sec:
        band = number_or_quantity(
            "sensitivity.settling_band", sec["settling_band"], "dimensionless", positive=True
        )
    params = base.parameters
    vector = base.vector()
    known = sweep_names()

    def parameter(f, k, spec):
        if k not in known:
            raise unknown_name(f, "servo parameter", k, known)
        check_sweep_name(f, k, params)
        values = {float(vector[PARAMETER_INDEX[t]]) for t in sweep_targets(k)}
        if len(values) != 1:
            raise HydroarmError(
                f,
                f"sets {', '.join(sweep_targets(k))}, which differ in the base servo: "
                "vary them by name",
            )
        return read_parameter(
            f,
            k,
            spec,
            values.pop(),
            sweep_dimension(k, params),
            lambda f2, v: sweep_value(f2, k, v, params),
        )

    plan = read_plan(sec, parameter)
    return ServoStudy(
        base=base,
        plan=plan,
        metrics=metrics,
        band=band,
        chunk=whole_number("sensitivity.chunk", sec.get("chunk", DEFAULT_CHUNK)),
        name=text_value("name", doc.get("name", name)),
    )


# ---------------------------------------------------------------- circuits ---
CIRCUIT_SENSITIVITY_KEYS = SENSITIVITY_KEYS - {"solver", "metrics"}


@dataclass(frozen=True)
class CircuitStudy:
    """A sensitivity file of any circuit (``[system] file``): the circuit (its solver is that
    of every run), the plan over its parameters by ``<component>.<parameter>`` and the
    metrics, statistics of its named outputs (`TraceMetric`, the ``[metrics]`` of a circuit
    sweep)."""

    circuit: Circuit
    compiled: CompiledCircuit
    plan: Plan
    metrics: tuple[TraceMetric, ...]
    chunk: int = DEFAULT_CHUNK
    name: str = "sensitivity"

    @property
    def cases(self) -> tuple:
        return ()

    def units(self) -> dict:
        return {m.column: "" for m in self.metrics}  # the unit is in the column's name

    def describe(self) -> str:
        c = self.circuit
        return (
            f"Model: the circuit '{c.name}' ({c.method} at {format_time(c.step)} for "
            f"{c.duration:g} s per run), every sample on the batch engine "
            "(hydroarm.batch.circuit_sweep.run_circuit_chunk: observed as it runs, a "
            "settling or rise time from a probe of its output); metrics are "
            "statistics of its named outputs (hydroarm.metrics.trace) at the samples "
            "`hydroarm simulate` records."
        )


class CircuitModel:
    """The evaluator of a `CircuitStudy`: every sample checked against its
    parameters' rules, then run on the batch engine
    (`run_circuit_chunk`, the path of a sweep's and a design's rows: observed at the samples
    ``simulate`` records, a row holding its metrics' accumulators and its trace-only
    statistics' probes, not its states), one batch per chunk, with progress."""

    def __init__(self, study: CircuitStudy, progress=None):
        self.study = study
        self.progress = progress
        self.failed = 0
        self.extra: dict = {}

    def table(self, X: np.ndarray) -> np.ndarray:
        st = self.study
        cc = st.compiled
        T = np.repeat(cc.P[None, :], X.shape[0], axis=0)
        for i, k in enumerate(st.plan.names):
            p = parameter_of(k, st.circuit, k)
            v = X[:, i]
            for r in range(len(v)):
                problem = "must be finite" if not math.isfinite(v[r]) else p.check(float(v[r]))
                if problem:
                    raise HydroarmError(
                        f"sensitivity.parameters.{k}",
                        f"sample {r}: {problem}, got {v[r]:.6g} (narrow the range or distribution)",
                    )
            T[:, cc.parameter_index[k]] = v
        return T

    def __call__(self, X: np.ndarray) -> dict:
        st = self.study
        T = self.table(X)
        S0 = row_initial_states(st.compiled, st.plan.names, X, T)
        chunks = range(0, len(T), st.chunk)
        tick = self.progress or Progress(len(chunks))
        parts = []
        for lo in chunks:
            hi = min(lo + st.chunk, len(T))
            parts.append(run_circuit_chunk(st.circuit, T[lo:hi], S0[lo:hi], st.metrics))
            tick(f"{hi}/{len(T)} scenarios")
        M = np.vstack(parts)
        failed = M[:, 0] > 0.5
        self.failed = int(failed.sum())
        self.extra["failure"] = ["failed" if f else "" for f in failed]
        return {m.column: M[:, 1 + j] for j, m in enumerate(st.metrics)}

    def notes(self) -> list[str]:
        if not self.failed:
            return []
        return [
            f"- {self.failed} runs failed (left the physical bounds); their metrics are NaN "
            "and their groups are left out of the analysis."
        ]


def circuit_study_from_doc(doc: dict, name: str, base_dir: Path) -> CircuitStudy:
    """A `CircuitStudy` from a sensitivity file with ``[system] file``."""
    reject_unknown_keys("", doc, {"name", "description", "system", "sensitivity", "metrics"})
    circuit = study_circuit("system", doc["system"], base_dir)
    if circuit.method == "adaptive":
        raise HydroarmError("system.method", "a sensitivity study runs the fixed-step methods")
    compiled = build(circuit)
    sec = sensitivity_section(doc, CIRCUIT_SENSITIVITY_KEYS)
    if "metrics" not in doc:
        raise HydroarmError("metrics", "is missing: name what each run measures (docs/batch.md)")
    metrics = read_trace_metrics("metrics", doc["metrics"], output_units(compiled))
    known = compiled.sweepable

    def parameter(f, k, spec):
        p = parameter_of(f, circuit, k)
        if k not in known:
            raise HydroarmError(f, "is not a parameter a study may vary")
        return read_parameter(
            f,
            k,
            spec,
            float(compiled.P[compiled.parameter_index[k]]),
            None,
            lambda f2, v: parameter_value(f2, circuit, k, v),
            unit=p.unit,
            read_spread=lambda f2, v: value_in(f2, v, p.unit),
        )

    plan = read_plan(sec, parameter)
    check_observed(plan.runs, metrics)
    return CircuitStudy(
        circuit=circuit,
        compiled=compiled,
        plan=plan,
        metrics=metrics,
        chunk=whole_number("sensitivity.chunk", sec.get("chunk", DEFAULT_CHUNK)),
        name=text_value("name", doc.get("name", name)),
    )


# ------------------------------------------------------------------ the file ---
def read_sensitivity_file(path) -> SensitivityStudy | ServoStudy | CircuitStudy:
    """Read a sensitivity file; every problem is a one-line error before any simulation.

    Parameters
    ----------
    path : str or pathlib.Path
        The sensitivity file (docs/sensitivity.md): a joint's, a component servo's (with
        ``[actuator]``) or a circuit's.

    Returns
    -------
    SensitivityStudy, ServoStudy or CircuitStudy
        The study, checked.
    """
    text, path = read_text_file(path)
    return study_from_doc(parse_toml(text, path.name), path.stem, path.parent)


def study_from_doc(
    doc: dict, name: str = "sensitivity", base_dir: Path = Path(".")
) -> SensitivityStudy | ServoStudy | CircuitStudy:
    if is_component_file(doc):
        return servo_study_from_doc(doc, name, base_dir)
    if is_circuit_study(doc):
        return circuit_study_from_doc(doc, name, base_dir)
    reject_unknown_keys("", doc, SECTIONS)
    joint = joint_from_table(
        "joint",
        optional_table(doc, "joint"),
        default_set="paper-calibrated",
        physics=optional_table(doc, "physics"),
        base_dir=base_dir,
    )
    cases = read_cases(doc)
    sec = sensitivity_section(doc, SENSITIVITY_KEYS)
    metrics = read_metrics(sec.get("metrics", list(DEFAULT_METRICS)), JOINT_METRICS)

    def parameter(f, k, spec):
        if k not in UNCERTAIN:
            raise unknown_name(f, "joint parameter", k, UNCERTAIN)
        dim = FIELD_DIMENSIONS[k]
        return read_parameter(
            f, k, spec, getattr(joint, k), dim, lambda f2, v: field_value(f2, k, v)
        )

    plan = read_plan(sec, parameter, len(cases))
    solver = as_table("sensitivity.solver", sec.get("solver", {}))
    reject_unknown_keys("sensitivity.solver", solver, SOLVER_KEYS)
    fixed = registry.fixed_step_methods()
    smethod = text_value("sensitivity.solver.method", solver.get("method", "euler"), tuple(fixed))
    step = duration = None
    if "step" in solver:
        step = time_value("sensitivity.solver.step", solver["step"], positive=True)
    if "duration" in solver:
        duration = time_value("sensitivity.solver.duration", solver["duration"], positive=True)
        if step is not None and step > duration:
            raise HydroarmError("sensitivity.solver.step", "is longer than the duration")
    return SensitivityStudy(
        joint=joint,
        cases=cases,
        plan=plan,
        metrics=metrics,
        method=smethod,
        step=step,
        duration=duration,
        chunk=whole_number("sensitivity.chunk", sec.get("chunk", DEFAULT_CHUNK)),
        name=text_value("name", doc.get("name", name)),
    )


def sensitivity_section(doc: dict, allowed) -> dict:
    if "sensitivity" not in doc:
        raise HydroarmError("sensitivity", "section is missing (give method, samples, parameters)")
    sec = as_table("sensitivity", doc["sensitivity"])
    reject_unknown_keys("sensitivity", sec, allowed)
    return sec


def read_plan(sec: dict, parameter, cases: int = 1) -> Plan:
    """The `Plan` of a ``[sensitivity]`` table; ``parameter(field, name, spec)``
    reads one entry of ``[sensitivity.parameters]``."""
    method = text_value("sensitivity.method", sec.get("method", "sobol"), METHODS)
    if "samples" not in sec:
        raise HydroarmError("sensitivity.samples", "is missing (the base sample N, e.g. 256)")
    samples = whole_number("sensitivity.samples", sec["samples"], 2)
    if method == "sobol" and samples & (samples - 1):
        up = 1 << samples.bit_length()
        raise HydroarmError(
            "sensitivity.samples",
            f"must be a power of 2 for Sobol, got {samples} (e.g. {up >> 1} or {up})",
        )
    seed = sec.get("seed")
    if seed is None or isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise HydroarmError(
            "sensitivity.seed",
            "is missing or not a whole number ≥ 0 (a seed makes the study repeatable)",
        )
    levels = whole_number(
        "sensitivity.levels", sec.get("levels", 4), 2, MAX_LEVELS, "Morris grid levels"
    )
    if method == "sobol" and "levels" in sec:
        raise HydroarmError("sensitivity.levels", 'is for method = "morris"')
    resamples = whole_number(
        "sensitivity.resamples",
        sec.get("resamples", 100),
        10,
        MAX_RESAMPLES,
        "bootstrap resamples; 1000 give 95 % intervals to about 1 %",
    )
    f = "sensitivity.parameters"
    table = as_table(f, sec.get("parameters", {}))
    if not table:
        raise HydroarmError(f, 'is missing (give name = ["low unit", "high unit"] entries)')
    params = tuple(parameter(f"{f}.{k}", k, spec) for k, spec in table.items())
    if len(params) < 2:
        raise HydroarmError(f, "needs at least 2 parameters (indices apportion a variance)")
    if method == "morris":
        for p in params:
            if p.distribution == "normal":
                # Morris's grid has the levels 0 and 1, which a normal's inverse CDF maps to
                # ±infinity: give the range the screening should cover instead
                raise HydroarmError(
                    f"{f}.{p.name}",
                    "a normal distribution cannot be screened by Morris (its grid reaches the "
                    'tails at ±infinity): give ["low", "high"] or a uniform distribution',
                )
    plan = Plan(params, method, samples, seed, levels, resamples)
    runs = plan.runs * cases
    if runs > MAX_RUNS:
        raise HydroarmError(
            "sensitivity.samples", f"{runs} runs (at most {MAX_RUNS}): fewer samples"
        )
    return plan


def read_metrics(value, known) -> tuple[str, ...]:
    f = "sensitivity.metrics"
    if not isinstance(value, list) or not value:
        raise HydroarmError(f, "must be a non-empty list of metric names")
    for m in value:
        if not isinstance(m, str) or m not in known:
            raise unknown_name(f, "metric", m, known)
    if len(set(value)) != len(value):
        raise HydroarmError(f, "names a metric twice")
    return tuple(value)


def read_parameter(
    f: str, k: str, spec, base, dim: str | None, read, *, unit: str = "", read_spread=None
) -> Parameter:
    """``[low, high]`` (uniform) or a table: ``distribution = "uniform"`` with low/high or
    relative, ``distribution = "normal"`` with mean (default: the base value) and sd or
    relative_sd; ``read(field, value)`` reads a value of ``k`` (dimension ``dim``) in SI.
    ``dim`` None: ``k`` has the SI ``unit`` and ``read_spread(field, value)`` reads its sd
    (a circuit's parameter, whose unit its component declares)."""
    if dim is not None:
        unit = "" if dim == "dimensionless" else SI_UNITS.get(dim, "")
    if isinstance(spec, list):
        if len(spec) != 2:
            raise HydroarmError(f, 'must be ["low", "high"] with units, or a distribution table')
        lo, hi = (read(f, v) for v in spec)
        if not lo < hi:
            raise HydroarmError(f, "low must be below high")
        return Parameter(k, "uniform", lo, hi, unit)
    if not isinstance(spec, dict):
        raise HydroarmError(f, 'must be ["low", "high"] with units, or a distribution table')
    dist = spec.get("distribution")
    keys = {"normal": {"mean", "sd", "relative_sd"}, "uniform": {"low", "high", "relative"}}
    if dist not in keys:
        raise HydroarmError(f"{f}.distribution", f"must be normal or uniform, got {dist!r}")
    reject_unknown_keys(f, spec, keys[dist] | {"distribution"})
    if dist == "normal":
        if "mean" in spec:
            mean = read(f"{f}.mean", spec["mean"])
        elif base is None:
            raise HydroarmError(f"{f}.mean", "is missing (the base has no value)")
        else:
            mean = float(base)
        if ("sd" in spec) == ("relative_sd" in spec):
            raise HydroarmError(f"{f}.sd", "give sd or relative_sd (one of them)")
        if "sd" in spec:
            if dim is None:
                sd = read_spread(f"{f}.sd", spec["sd"])
                if not sd > 0:
                    raise HydroarmError(f"{f}.sd", f"must be positive, got {spec['sd']!r}")
            else:
                sd = number_or_quantity(f"{f}.sd", spec["sd"], dim, positive=True)
        else:
            rel = number_or_quantity(
                f"{f}.relative_sd", spec["relative_sd"], "dimensionless", positive=True
            )
            sd = abs(mean) * rel
            if sd == 0:
                raise HydroarmError(f"{f}.relative_sd", "gives sd 0 (the mean is 0)")
        return Parameter(k, "normal", mean, sd, unit)
    if "relative" in spec:
        if "low" in spec or "high" in spec:
            raise HydroarmError(f"{f}.relative", "give relative or low/high, not both")
        if base is None:
            raise HydroarmError(f"{f}.relative", "the base has no value to be relative to")
        r = number_or_quantity(f"{f}.relative", spec["relative"], "dimensionless", positive=True)
        lo, hi = sorted((float(base) * (1 - r), float(base) * (1 + r)))
    else:
        for key in ("low", "high"):
            if key not in spec:
                raise HydroarmError(f"{f}.{key}", "is missing (or give relative)")
        lo = read(f"{f}.low", spec["low"])
        hi = read(f"{f}.high", spec["high"])
    if not lo < hi:
        raise HydroarmError(f, "low must be below high")
    return Parameter(k, "uniform", lo, hi, unit)


def read_cases(doc: dict) -> tuple[Case, ...]:
    """``load`` and ``direction`` at the top (one case), or ``[[case]]`` entries."""
    if "case" in doc:
        for k in ("load", "direction"):
            if k in doc:
                raise HydroarmError(k, "give load and direction, or [[case]] entries, not both")
        entries = doc["case"]
        if not isinstance(entries, list) or not entries:
            raise HydroarmError("case", "must be [[case]] entries with load and direction")
        cases = []
        for i, e in enumerate(entries):
            f = f"case[{i + 1}]"
            e = as_table(f, e)
            reject_unknown_keys(f, e, CASE_KEYS)
            cases.append(read_case(f, e))
        names = [c.name for c in cases]
        if len(set(names)) != len(names):
            raise HydroarmError("case", "two cases have the same name (give each a name)")
        return tuple(cases)
    return (read_case("", doc, named=False),)


def read_case(section: str, table: dict, named: bool = True) -> Case:
    def f(k):
        return f"{section}.{k}" if section else k

    for k in ("load", "direction"):
        if k not in table:
            raise HydroarmError(
                f(k), 'is missing (e.g. load = 6 and direction = "raise", or [[case]] entries)'
            )
    direction = text_value(f("direction"), table["direction"], ("raise", "lower"))
    raw = table["load"]
    load = parse_load(f("load"), raw) if isinstance(raw, dict) else paper_load(raw, field=f("load"))
    default = f"{load.name} {direction}"
    name = text_value(f("name"), table.get("name", default)) if named else default
    return Case(name=name, load=load, direction=direction)
