"""Fit a joint's parameters to measured saturation-test traces (issue 16, first part).

A fit file names a starting joint (``[joint]``, as in scenario files), the free parameters
(``[fit]``) and the measured traces (``[[trace]]``): CSV files with ``t_s`` and ``x_mm`` or
``theta_deg`` (as ``hydroarm simulate --out`` writes them), each with its load and the direction
of the saturation test that produced it. :func:`fit` runs a bounded least-squares fit and
reports the estimates with standard errors, 95 % intervals, the correlation matrix and the
singular values of the scaled Jacobian, and names parameter pairs the data cannot separate.
The statistics and their assumptions are in docs/fit.md.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..batch.traces import THETA, P, X, scenario_traces
from ..core.servo import PARAMETER_INDEX, S_Q
from ..errors import HydroarmError
from ..files import atomic_write_text, check_output_folder, move_into, staging_folder
from ..io.catalog import paper_load
from ..io.components import (
    LOAD_MASS,
    SWEEP_PARAMETERS,
    check_sweep_name,
    is_component_file,
    servo_from_doc,
    sweep_dimension,
    sweep_value,
)
from ..io.components import SECTIONS as COMPONENT_SECTIONS
from ..io.report import to_html, to_markdown
from ..io.schema import parameter_set, parse_load
from ..io.sections import (
    FIELD_DIMENSIONS,
    JOINT_KEYS,
    PHYSICS_KEYS,
    as_table,
    field_value,
    joint_from_table,
    optional_table,
    parse_toml,
    read_csv_columns,
    read_text_file,
    reject_unknown_keys,
    require_keys,
    text_value,
    time_value,
    unknown_name,
    whole_number,
)
from ..io.units import SI_UNITS, length_or_angle, quantity
from ..model.joint import Load, ServoJoint
from ..model.lever import LeverInput
from ..model.rules import FIELD_RULES, NONNEGATIVE, POSITIVE
from ..model.scenario import DEFAULT_STEP, Scenario, default_duration, saturation_test, simulate
from ..model.servo import ServoScenario, run_servos
from ..plotting.fit import fit_trace_figure
from ..plotting.joint import save_figure

# ServoJoint fields that can be fitted (numbers; the stiffness is given through the volume)
FITTABLE = tuple(k for k in (*JOINT_KEYS, *PHYSICS_KEYS) if k != "hydraulic_stiffness")
FIT_SECTIONS = {"joint", "physics", "fit", "trace", "name", "description"}
SERVO_FIT_SECTIONS = {"fit", "trace", *COMPONENT_SECTIONS}
SERVO_TRACE_KEYS = {"csv", "columns", "window", "weight", "delay", "name"}
TRACE_KEYS = {"csv", "load", "direction", "lever", "columns", "window", "weight", "delay", "name"}
MIN_SAMPLES = 3
# the files of DIR besides the plots
OUTPUT_FILES = ("fit.csv", "correlation.csv", "fitted.toml", "fit_report.md", "fit_report.html")
CORRELATION_LIMIT = 0.95
SERVO_Q = 0  # the component servo's position state: column 0 of its samples
# a fitted column -> (column of the model's samples, SI -> the column's unit)
COLUMNS = {
    "x_mm": (X, 1e3),
    "theta_deg": (THETA, 180.0 / math.pi),
    "p_bar": (P, 1e-5),
    "position_m": (SERVO_Q, 1.0),  # a component servo (as its run's CSV)
    "angle_deg": (SERVO_Q, 180.0 / math.pi),
}
DELAY = "trigger_delay"  # the shared delay parameter; a trace's own: trigger_delay_<n>
DELAY_SCALE = 1e-3  # [s] the scale of a delay starting at 0 (the fit's z is in ms)
ENGINES = ("batch", "serial")
JACOBIANS = ("forward", "central")
DIFF_STEP = 1e-4  # relative finite-difference step in the scaled parameters
PENALTY = 10.0  # residual of every sample of a failed run (residuals are fractions of ranges)
CACHE_SIZE = 4096  # residual vectors kept (the starts' prefilled ones must survive)


@dataclass(frozen=True)
class Trace:
    """One measured run: samples ``values`` of ``column`` (``x_mm`` [mm] or ``theta_deg``
    [deg]) at times ``t`` [s], optionally the load pressure ``pressure`` [bar] at the same
    times; the input is the paper's saturation test (``direction``) or a measured lever
    ``lever`` [m, or rad when ``lever_angle``] at times ``lever_t`` [s]. ``delay`` [s]: a known
    shift of the model's response (measured time = model time + delay; None: the shared
    ``trigger_delay`` when fitted, else none); ``fit_delay``: the trace has its own fitted
    delay (parameter ``trigger_delay_<n>``)."""

    t: np.ndarray
    values: np.ndarray
    column: str
    load: Load
    direction: str | None = None
    weight: float = 1.0
    name: str = "trace"
    pressure: np.ndarray | None = None
    lever_t: np.ndarray | None = None
    lever: np.ndarray | None = None
    lever_angle: bool = False
    delay: float | None = None  # None: the shared trigger_delay if fitted, else 0
    fit_delay: bool = False

    @property
    def scale(self) -> float:
        """Residual scale: the trace's range (so every trace counts in relative terms)."""
        return max(float(np.ptp(self.values)), 1e-12)

    def blocks(self) -> list[tuple[str, np.ndarray, float]]:
        """The measured columns fitted: (column, values, residual scale = its range)."""
        out = [(self.column, self.values, self.scale)]
        if self.pressure is not None:
            out.append(("p_bar", self.pressure, max(float(np.ptp(self.pressure)), 1e-12)))
        return out

    def lever_positions(self, joint: ServoJoint) -> np.ndarray:
        """The measured lever in jack coordinates [m] for ``joint`` (an angle through its
        crank geometry, eq. (4))."""
        assert self.lever is not None
        if not self.lever_angle:
            return self.lever
        return np.array([joint.jack_position(float(a)) for a in self.lever])


@dataclass(frozen=True)
class FitProblem:
    """A starting joint (or a component ``servo``), the parameters to fit (joint or servo
    fields and trigger delays, with initial values and bounds), the traces, and the fit's
    options (multi-start ``starts``/``seed``, the finite-difference ``jacobian``)."""

    joint: ServoJoint
    parameters: tuple[str, ...]
    traces: tuple[Trace, ...]
    initial: dict = field(default_factory=dict)
    bounds: dict = field(default_factory=dict)
    name: str = "fit"
    # a component servo (its file's sections) fitted instead of ``joint`` (then unused)
    servo: ServoScenario | None = None
    targets: tuple = ()  # scalar-metric targets (hydroarm/analysis/targets.py), after the traces
    starts: int = 1  # multi-start: this many Sobol points inside the (finite) bounds
    seed: int = 0  # of the scrambled Sobol sequence
    jacobian: str = "forward"  # finite differences: "forward" (N runs) or "central" (2N)

    def start(self) -> np.ndarray:
        return np.array(
            [self.initial.get(k, 0.0 if is_delay(k) else self.value(k)) for k in self.parameters]
        )

    def value(self, key: str) -> float:
        """A parameter's value in the model fitted (the joint, or the servo's vector)."""
        if self.servo is not None:
            return float(self.servo.vector()[PARAMETER_INDEX[key]])
        return getattr(self.joint, key)

    @property
    def joint_parameters(self) -> tuple[str, ...]:
        return tuple(k for k in self.parameters if not is_delay(k))

    def delays(self, values: np.ndarray) -> np.ndarray:
        """Each trace's delay [s] for parameter values ``values`` (SI, in ``parameters``'
        order): its own fitted one, else its fixed ``delay``, else the shared
        ``trigger_delay`` if fitted, else 0."""
        v = dict(zip(self.parameters, map(float, values), strict=True))
        return np.array(
            [
                v[f"{DELAY}_{i + 1}"]
                if tr.fit_delay
                else (tr.delay if tr.delay is not None else v.get(DELAY, 0.0))
                for i, tr in enumerate(self.traces)
            ]
        )


@dataclass
class FitResult:
    """Estimates (SI) with their uncertainty and the traces measured versus fitted."""

    problem: FitProblem
    initial: np.ndarray
    estimate: np.ndarray
    std_error: np.ndarray
    ci95_low: np.ndarray
    ci95_high: np.ndarray
    correlation: np.ndarray
    singular_values: np.ndarray
    residual_sd: float
    dof: int
    evaluations: int
    elapsed_s: float
    joint: ServoJoint | ServoScenario  # the fitted model (a servo's scenario for a servo fit)
    fitted: list = field(default_factory=list)  # simulated values at the measured times
    fitted_pressure: list = field(default_factory=list)  # [bar] per trace, or None
    delays: np.ndarray | None = None  # each trace's delay at the estimate [s]
    warnings: list = field(default_factory=list)
    engine_runs: int = 0  # calls of the engine (a batch of parameter vectors counts once)
    starts: list = field(default_factory=list)  # per start: start, estimate, cost, evaluations
    best_start: int = 0

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.problem.parameters

    def units(self) -> list[str]:
        servo = self.problem.servo
        if servo is not None:
            return [servo_unit(k, servo) for k in self.parameters]
        return [parameter_unit(k) for k in self.parameters]

    def table(self) -> list[dict]:
        return [
            {
                "parameter": k,
                "initial": float(self.initial[i]),
                "estimate": float(self.estimate[i]),
                "std_error": float(self.std_error[i]),
                "ci95_low": float(self.ci95_low[i]),
                "ci95_high": float(self.ci95_high[i]),
                "unit": u,
            }
            for i, (k, u) in enumerate(zip(self.parameters, self.units(), strict=True))
        ]

    def write(self, out) -> Path:
        """Write fit.csv, correlation.csv, fitted.toml, the plots (trace<n>.png, with a
        measured pressure trace<n>_p.png), fit_report.md and fit_report.html into the folder
        ``out``: made in a staging folder beside it and moved into place at the end."""
        out = check_output_folder("--out", out)
        with staging_folder(out) as stage:
            atomic_write_text(stage / "fit.csv", self.csv_text())
            atomic_write_text(stage / "correlation.csv", self.correlation_csv())
            atomic_write_text(
                stage / "fitted.toml",
                fitted_toml(self.joint, self.problem.name, self.delays_text())
                if isinstance(self.joint, ServoJoint)
                else servo_toml(self.joint, self.problem, self.estimate),
            )
            plots = [n for i in range(len(self.problem.traces)) for n in self._plots(stage, i)]
            blocks = self.blocks(plots)
            atomic_write_text(stage / "fit_report.md", to_markdown(blocks))
            title = f"hydroarm fit: {self.problem.name}"
            atomic_write_text(stage / "fit_report.html", to_html(blocks, stage, title))
            names = [*OUTPUT_FILES, *plots]
            move_into(stage, out, names)
        return out

    def csv_text(self) -> str:
        """fit.csv: one row per parameter (SI)."""
        head = "parameter,initial,estimate,std_error,ci95_low,ci95_high,unit"
        lines = [head] + [
            ",".join(
                [r["parameter"]]
                + [f"{r[c]:.9g}" for c in ("initial", "estimate", "std_error")]
                + [f"{r[c]:.9g}" for c in ("ci95_low", "ci95_high")]
                + [r["unit"]]
            )
            for r in self.table()
        ]
        return "\n".join(lines) + "\n"

    def correlation_csv(self) -> str:
        """correlation.csv: the correlation matrix with the parameter names as header and as
        first column."""
        names = self.parameters
        lines = [",".join(["parameter", *names])]
        for i, k in enumerate(names):
            lines.append(",".join([k, *(f"{c:.6f}" for c in self.correlation[i])]))
        return "\n".join(lines) + "\n"

    def _plots(self, out: Path, i: int) -> list[str]:
        """trace<i>.png (the position) and, with a measured pressure, trace<i>_p.png."""
        tr = self.problem.traces[i]
        fig = fit_trace_figure(tr.t, tr.values, self.fitted[i], tr.column, title=tr.name)
        names = [f"trace{i + 1}.png"]
        save_figure(fig, out / names[0])
        if tr.pressure is not None:
            fp = self.fitted_pressure[i]
            fig = fit_trace_figure(tr.t, tr.pressure, fp, "p_bar", title=tr.name)
            names.append(f"trace{i + 1}_p.png")
            save_figure(fig, out / names[1])
        return names

    def delays_text(self) -> list[str]:
        """One line per trace with a delay (fixed or fitted) [ms]."""
        if self.delays is None or not np.any(self.delays):
            return []
        return [
            f"trace {i + 1} ({tr.name}): delay {d * 1e3:.4g} ms"
            for i, (tr, d) in enumerate(zip(self.problem.traces, self.delays, strict=True))
        ]

    def report(self, plots=()) -> str:
        """The report in Markdown (fit_report.md)."""
        return to_markdown(self.blocks(plots))

    def blocks(self, plots=()) -> list:
        """The report as blocks of :mod:`hydroarm.io.report` (Markdown and HTML)."""
        names = self.parameters
        samples = sum(len(v) for t in self.problem.traces for _, v, _ in t.blocks())
        b: list = [
            ("h", 1, f"Fit: {self.problem.name}"),
            (
                "p",
                f"{len(self.problem.traces)} traces, {samples} samples, {len(names)} "
                f"parameters, {self.dof} degrees of freedom; {self.evaluations} model "
                f"evaluations ({self.engine_runs} engine runs) in {self.elapsed_s:.2f} s; "
                f"residual standard deviation {self.residual_sd:.4g} (fraction of each "
                "trace's range).",
            ),
            (
                "table",
                ["parameter", "initial", "estimate", "std error", "95 % interval", "unit"],
                [
                    [
                        r["parameter"],
                        f"{r['initial']:.5g}",
                        f"{r['estimate']:.5g}",
                        f"{r['std_error']:.3g}",
                        f"{r['ci95_low']:.5g} … {r['ci95_high']:.5g}",
                        r["unit"],
                    ]
                    for r in self.table()
                ],
            ),
            ("p", "Correlation matrix:"),
            (
                "table",
                ["", *names],
                [[k, *(f"{c:+.3f}" for c in self.correlation[i])] for i, k in enumerate(names)],
            ),
            (
                "p",
                "Singular values of the scaled Jacobian: "
                + ", ".join(f"{s:.4g}" for s in self.singular_values),
            ),
        ]
        if self.delays_text():
            b.append(("p", "Model response delays (measured time = model time + delay):"))
            b.append(("p", "\n".join(f"- {d}" for d in self.delays_text())))
        b += [("p", f"**Warning:** {w}") for w in self.warnings] or [
            ("p", "No identifiability warning.")
        ]
        if len(self.starts) > 1:
            b.append(
                (
                    "p",
                    f"Multi-start: {len(self.starts)} scrambled Sobol points inside the bounds "
                    f"(seed {self.problem.seed}); kept start {self.best_start + 1}. Final cost "
                    "Σr² of each start:",
                )
            )
            rows = []
            for i, r in enumerate(self.starts):
                mark = " (kept)" if i == self.best_start else ""
                if not math.isfinite(r["cost"]):
                    mark = " (the model fails there)"
                rows.append(
                    [f"{i + 1}{mark}", *(f"{v:.4g}" for v in r["start"])]
                    + [f"{r['cost']:.6g}", str(r["evaluations"])]
                )
            b.append(
                ("table", ["start", *(f"{k} (start)" for k in names), "cost", "evaluations"], rows)
            )
        b += [("fig", p, f"{p}: measured and fitted, residuals below") for p in plots]
        return b


# ------------------------------------------------------------------- the fit ---
def is_delay(name: str) -> bool:
    """Whether a parameter is a trigger delay (shared, or ``trigger_delay_<trace>``)."""
    return name == DELAY or name.startswith(DELAY + "_")


def servo_unit(name: str, servo: ServoScenario) -> str:
    """The SI unit of a component servo's parameter as a servo sweep reads it
    (:func:`hydroarm.io.components.sweep_dimension`; angular for an angular load)."""
    if is_delay(name):
        return "s"
    if name == "spool_frequency":
        return "rad/s"
    return SI_UNITS[sweep_dimension(name, servo.parameters)] or "1"


def parameter_unit(name: str) -> str:
    """The SI unit of a parameter as fit.csv writes it."""
    return "s" if is_delay(name) else SI_UNITS[FIELD_DIMENSIONS[name]] or "1"


def fit(
    source, out=None, *, engine: str = "batch", starts: int | None = None, progress=None
) -> FitResult:
    """Fit the parameters of a fit file (path) or :class:`FitProblem`; write into ``out``.
    ``starts`` replaces the file's ``[fit] starts`` (multi-start from Sobol points);
    ``progress(label)`` is called after each start (:class:`~hydroarm.io.progress.Progress`)."""
    problem = source if isinstance(source, FitProblem) else read_fit_file(source)
    if out is not None:
        check_output_folder("--out", out)  # before any work
    if starts is not None:
        problem = dataclasses.replace(problem, starts=whole_number("fit.starts", starts))
    problem_bounds(problem, problem.start())  # finite bounds for a multi-start: before work
    result = run_fit(problem, engine=engine, progress=progress)
    if out is not None:
        result.write(out)
    return result


def trace_scenario(joint: ServoJoint, tr: Trace, delay: float = 0.0) -> Scenario:
    """The scenario that models a trace: its saturation test, or its measured lever, run at
    least to its last time (shifted by ``delay`` [s])."""
    need = float(tr.t[-1]) - delay
    if tr.lever is None:
        assert tr.direction is not None
        sc = saturation_test(joint, tr.load, tr.direction)
        if sc.duration < need + 10 * sc.step:
            dur = max(need + 10 * sc.step, default_duration(joint, 0.0))
            sc = sc.replace(duration=round(dur, 6))
        return sc
    assert tr.lever_t is not None
    y = tr.lever_positions(joint)
    t0 = float(tr.lever_t[0])
    return Scenario(
        joint=joint,
        load=tr.load,
        lever=LeverInput(tr.lever_t, y, description=f"lever of {tr.name}"),
        initial_angle=joint.joint_angle(float(y[0])),
        t0=t0,
        duration=round(max(need, float(tr.lever_t[-1])) - t0 + 10 * DEFAULT_STEP, 6),
        name=tr.name,
    )


def simulate_trace(joint: ServoJoint, tr: Trace) -> np.ndarray:
    """The model's value of ``tr.column`` at the trace's times (same input and delay)."""
    return column_values(model_samples([joint], (tr,), "serial")[0][0], tr.column)


def column_values(samples: np.ndarray, column: str) -> np.ndarray:
    """A column (in its unit) of model samples (θ₂ [rad], x [m], p [Pa] per row)."""
    index, factor = COLUMNS[column]
    return samples[:, index] * factor


def model_samples(
    joints: list,
    traces,
    engine: str = "batch",
    *,
    strict: bool = True,
    delays: np.ndarray | None = None,
    check_step: bool = True,
) -> list[list]:
    """θ₂, x, p (columns of :mod:`hydroarm.batch.traces`) of every joint's model of every
    trace at the trace's times less its delay (``delays[joint, trace]`` [s]; default each
    trace's fixed ``delay``): ``[joint][trace] -> (len(t), 3)``.

    ``engine``: ``"batch"`` runs them all together (:func:`~hydroarm.batch.traces.scenario_traces`),
    ``"serial"`` one :func:`~hydroarm.simulate` each, interpolated by ``np.interp``; the two
    give the same numbers bit for bit (tests/test_fit.py). A run that cannot be made (a step
    too large for the joint) or that leaves the physical bounds raises its error
    (``strict``), or gets NaN samples. ``check_step``: check the step's stability for every
    run first, as :func:`~hydroarm.simulate` does (the fit checks it at the starts and at
    the estimate; in between a run that diverges is caught by its bounds).
    """
    if delays is None:
        delays = np.array([[tr.delay or 0.0 for tr in traces] for _ in joints])
    if any(isinstance(j, ServoScenario) for j in joints):
        return servo_samples(joints, traces, strict=strict, delays=delays, check_step=check_step)
    jobs = []  # (scenario or None, query times)
    for j, row in zip(joints, delays, strict=True):
        for tr, d in zip(traces, row, strict=True):
            try:
                sc = trace_scenario(j, tr, float(d))
                if check_step:
                    sc.check_step()  # as simulate() checks every run
            except HydroarmError:
                if strict:
                    raise
                sc = None
            jobs.append((sc, tr.t - d))
    nan = [np.full((len(q), 3), np.nan) for _, q in jobs]
    if engine == "batch":
        ok = [(sc, q) for sc, q in jobs if sc is not None]
        flat = scenario_traces([sc for sc, _ in ok], [q for _, q in ok], strict=strict)
        it = iter(np.split(flat, np.cumsum([len(q) for _, q in ok])[:-1]))
        parts = [nan[i] if sc is None else next(it) for i, (sc, _) in enumerate(jobs)]
    else:
        parts = []
        for i, (sc, q) in enumerate(jobs):
            try:
                if sc is None:
                    raise HydroarmError("solver.step", "the run cannot be made")
                res = simulate(sc, check_stability=False)
                cols = (res.theta, res.x, res.p)
                parts.append(np.column_stack([np.interp(q, res.t, v) for v in cols]))
            except HydroarmError:
                if strict:
                    raise
                parts.append(nan[i])
    k = len(traces)
    return [parts[i * k : (i + 1) * k] for i in range(len(joints))]


def servo_samples(servos, traces, *, strict=True, delays=None, check_step=True) -> list[list]:
    """The position of every component servo (scenarios differing only in parameters) at every
    trace's times less its delay: ``[servo][trace] -> (len(t), 1)`` (column :data:`SERVO_Q`).

    All servos run together on the batch path (:func:`hydroarm.model.servo.run_servos`, each
    row the single run's), up to the last time needed, keeping the file's ``record_every``-th
    step; the position is linearly interpolated between the kept steps. A failing run raises
    (``strict``) or gets NaN samples.
    """
    if delays is None:
        delays = np.zeros((len(servos), len(traces)))
    first = servos[0]
    last = max(float(np.max(tr.t[-1] - delays[:, i])) for i, tr in enumerate(traces))
    every = first.step * first.record_every
    duration = min(first.duration, (math.ceil(max(last, 0.0) / every) + 1) * every)
    runs = [
        sv.replace(duration=duration, check_stability=check_step and sv.check_stability)
        for sv in servos
    ]
    try:
        results: list = run_servos(runs)
    except HydroarmError:
        if strict:
            raise
        results = []
        for sv in runs:  # find the failing ones
            try:
                results.append(run_servos([sv])[0])
            except HydroarmError:
                results.append(None)
    out = []
    for res, row in zip(results, delays, strict=True):
        per = []
        for tr, d in zip(traces, row, strict=True):
            if res is None:
                per.append(np.full((len(tr.t), 1), np.nan))
            else:
                q = np.interp(tr.t - d, res.t, res.states[:, S_Q])
                per.append(q[:, None])
        out.append(per)
    return out


def trace_model_values(samples: np.ndarray, tr: Trace) -> np.ndarray:
    """The model's values of a trace's fitted columns, in order (:meth:`Trace.blocks`)."""
    return np.concatenate([column_values(samples, c) for c, _, _ in tr.blocks()])


@dataclass
class _Model:
    """The residuals of a problem as a function of scaled parameters z (p = z·scale)."""

    problem: FitProblem
    scale: np.ndarray
    engine: str = "batch"
    evaluations: int = 0  # parameter vectors simulated
    runs: int = 0  # calls of the engine (a batch counts once)
    _cache: dict = field(default_factory=dict)

    def __post_init__(self):
        traces = self.problem.traces
        self.measured = np.concatenate([v for tr in traces for _, v, _ in tr.blocks()])
        self.weights = np.concatenate(
            [np.full(len(v), tr.weight / sc) for tr in traces for _, v, sc in tr.blocks()]
        )

    def joint_at(self, z) -> ServoJoint | ServoScenario:
        """The model at ``z``: the joint, or the component servo's scenario."""
        values = dict(zip(self.problem.parameters, np.asarray(z) * self.scale, strict=True))
        changes = {k: float(values[k]) for k in self.problem.joint_parameters}
        if self.problem.servo is not None:
            return self.problem.servo.replace(check_stability=False, **changes)
        return self.problem.joint.replace(**changes)

    def many(self, Z: np.ndarray) -> np.ndarray:
        """Residual vectors (rows) of the scaled parameter vectors ``Z`` (rows), all simulated
        in one run of the engine; the blocks: trace residuals, then the targets' residuals."""
        Z = np.atleast_2d(Z)
        joints = [self.joint_at(z) for z in Z]
        delays = np.array([self.problem.delays(z * self.scale) for z in Z])
        traces = self.problem.traces
        samples = model_samples(
            joints, traces, self.engine, strict=False, delays=delays, check_step=False
        )
        self.evaluations += len(Z)
        self.runs += 1
        sim = np.array(
            [
                np.concatenate(
                    [trace_model_values(s, tr) for s, tr in zip(row, traces, strict=True)]
                )
                for row in samples
            ]
        )
        r = (sim - self.measured) * self.weights
        # a joint whose run failed (unstable, out of the physical bounds): a cost far above
        # any fit's, so that the optimiser steps back
        r[~np.all(np.isfinite(r), axis=1)] = PENALTY
        if self.problem.targets:  # scalar metrics (hydroarm/analysis/targets.py)
            targets = importlib.import_module(f"{__package__}.targets")
            r = np.hstack([r, targets.target_residuals(joints, self.problem.targets)])
        for z, row in zip(Z, r, strict=True):
            self._cache[np.asarray(z, float).tobytes()] = row
        return r

    def __call__(self, z) -> np.ndarray:
        key = np.asarray(z, float).tobytes()
        if key not in self._cache:
            if len(self._cache) > CACHE_SIZE:
                self._cache.clear()
            self.many(z)
        return self._cache[key]

    def jacobian(self, z, lo, hi, central: bool = False) -> np.ndarray:
        """Finite differences of the residuals at ``z``, the perturbed vectors (N forward, or
        2N central) run together; the steps and formulas are scipy's
        ``least_squares(diff_step=DIFF_STEP, jac="2-point" or "3-point")`` (relative step,
        adjusted at a bound), so that the batch and serial fits take the same path."""
        z = np.asarray(z, float)
        f0 = self(z)
        Z, derivative = fd_points(z, lo, hi, central)
        F = np.array([self._cache[x.tobytes()] for x in Z]) if self._has(Z) else self.many(Z)
        return derivative(f0, F)

    def step_ok(self, z) -> bool:
        """Whether the fixed step is stable for every trace's run at ``z``."""
        j, d = self.joint_at(z), self.problem.delays(np.asarray(z) * self.scale)
        try:
            if isinstance(j, ServoScenario):
                j.check_step()
                return True
            for tr, dt in zip(self.problem.traces, d, strict=True):
                trace_scenario(j, tr, float(dt)).check_step()
        except HydroarmError:
            return False
        return True

    def _has(self, Z) -> bool:
        return all(x.tobytes() in self._cache for x in Z)

    def prefill(self, starts: np.ndarray, lo, hi, central: bool = False) -> None:
        """The residuals at every start and at its Jacobian's perturbed points, in one run."""
        Z = [np.asarray(z, float) for z in starts]
        Z += [x for z in starts for x in fd_points(np.asarray(z, float), lo, hi, central)[0]]
        self.many(np.array(Z))


def fd_points(z, lo, hi, central: bool):
    """The perturbed points (rows) of a finite-difference Jacobian at ``z`` and the function
    ``derivative(f0, F)`` that makes the Jacobian (residuals × parameters) of the residuals
    ``f0`` at ``z`` and ``F`` at the points: scipy's ``_dense_difference`` ("2-point":
    (f(z + h) − f0)/h; "3-point": (f(z + h) − f(z − h))/2h, or at a bound one-sided
    (−3f0 + 4f(z + h) − f(z + 2h))/2h)."""
    n = len(z)
    if not central:
        Z = z + np.diag(fd_steps(z, lo, hi))
        dx = np.diag(Z) - z
        return Z, lambda f0, F: ((F - f0) / dx[:, None]).T
    h, one_sided = central_steps(z, lo, hi)
    rows, dx = [], np.empty(n)
    for i in range(n):
        a, b = z.copy(), z.copy()
        if one_sided[i]:
            a[i], b[i] = z[i] + h[i], z[i] + 2 * h[i]
            dx[i] = b[i] - z[i]
        else:
            a[i], b[i] = z[i] - h[i], z[i] + h[i]
            dx[i] = b[i] - a[i]
        rows += [a, b]

    def derivative(f0, F):
        f1, f2 = F[0::2], F[1::2]
        df = np.where(one_sided[:, None], -3.0 * f0 + 4 * f1 - f2, f2 - f1)
        return (df / dx[:, None]).T

    return np.array(rows), derivative


def central_steps(z, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """The 3-point steps of ``scipy.optimize.approx_derivative`` with ``rel_step =
    DIFF_STEP`` and which parameters take the one-sided formula at a bound
    (``_compute_absolute_step``, ``_adjust_scheme_to_bounds`` 2-sided)."""
    sign = (z >= 0).astype(float) * 2 - 1
    h = DIFF_STEP * sign * np.abs(z)
    dx = (z + h) - z
    h = np.where(dx == 0, np.finfo(float).eps ** (1 / 3) * sign * np.maximum(1.0, np.abs(z)), h)
    h = np.abs(h)
    one_sided = np.zeros(len(z), bool)
    if np.all((lo == -np.inf) & (hi == np.inf)):
        return h, one_sided
    lower, upper = z - lo, hi - z
    central = (lower >= h) & (upper >= h)
    forward = (upper >= lower) & ~central
    h[forward] = np.minimum(h[forward], 0.5 * upper[forward])
    one_sided[forward] = True
    backward = (upper < lower) & ~central
    h[backward] = -np.minimum(h[backward], 0.5 * lower[backward])
    one_sided[backward] = True
    min_dist = np.minimum(upper, lower)
    adjusted = ~central & (np.abs(h) <= min_dist)
    h[adjusted] = min_dist[adjusted]
    one_sided[adjusted] = False
    return h, one_sided


def fd_steps(z, lo, hi) -> np.ndarray:
    """The 2-point finite-difference steps of ``scipy.optimize.approx_derivative`` with
    ``rel_step = DIFF_STEP`` inside the bounds (``_compute_absolute_step``,
    ``_adjust_scheme_to_bounds`` with one 1-sided step)."""
    sign = (z >= 0).astype(float) * 2 - 1
    h = DIFF_STEP * sign * np.abs(z)
    dx = (z + h) - z
    h = np.where(dx == 0, np.finfo(float).eps ** 0.5 * sign * np.maximum(1.0, np.abs(z)), h)
    if np.all((lo == -np.inf) & (hi == np.inf)):
        return h
    x = z + h
    lb_dist, ub_dist = z - lo, hi - z
    fitting = np.abs(h) <= np.maximum(lb_dist, ub_dist)
    h = h.copy()
    h[((x < lo) | (x > hi)) & fitting] *= -1
    forward = (ub_dist >= lb_dist) & ~fitting
    h[forward] = ub_dist[forward]
    backward = (ub_dist < lb_dist) & ~fitting
    h[backward] = -lb_dist[backward]
    return h


def run_fit(problem: FitProblem, engine: str = "batch", progress=None) -> FitResult:
    """Fit ``problem`` (docs/fit.md). ``engine``: ``"batch"`` (the Jacobian's perturbed runs
    together on the batch engine) or ``"serial"`` (one simulation per evaluation, scipy's
    forward differences): the same steps and the same estimate. With ``problem.starts`` > 1
    the fit starts from that many scrambled Sobol points inside the bounds
    (:func:`start_points`) and keeps the lowest cost."""
    from scipy import optimize, stats

    if engine not in ENGINES:
        raise HydroarmError("engine", f"must be one of {', '.join(ENGINES)}, got {engine!r}")
    if problem.jacobian not in JACOBIANS:
        raise HydroarmError(
            "fit.jacobian", f"must be one of {', '.join(JACOBIANS)}, got {problem.jacobian!r}"
        )
    names = problem.parameters
    p0 = problem.start()
    scale = np.where(p0 != 0, np.abs(p0), [DELAY_SCALE if is_delay(k) else 1.0 for k in names])
    lo, hi = (np.array(b) for b in zip(*problem_bounds(problem, p0), strict=True))
    lo_z, hi_z = lo / scale, hi / scale
    model = _Model(problem, scale, engine)
    if problem.starts > 1:
        starts = start_points(lo, hi, problem.starts, problem.seed) / scale
    else:
        starts = np.clip(p0 / scale, lo_z, hi_z)[None, :]
    central = problem.jacobian == "central"
    if engine == "batch" and len(starts) > 1:  # every start's first residuals and Jacobian
        model.prefill(starts, lo_z, hi_z, central)  # at once
    jac: Any = "3-point" if central else "2-point"
    if engine == "batch":
        jac = lambda z: model.jacobian(z, lo_z, hi_z, central)  # noqa: E731

    tick = progress or (lambda label: None)
    t0 = time.perf_counter()
    sols: list = []
    start_rows: list[dict] = []
    for z0 in starts:
        before = model.evaluations
        if not model.step_ok(z0) or np.all(model(z0) == PENALTY):  # the model fails here
            if len(starts) == 1:  # the run's own error
                d = problem.delays(z0 * scale)[None, :]
                model_samples([model.joint_at(z0)], problem.traces, engine, delays=d)
            sols.append(None)
            tick(f"start {len(sols)}/{len(starts)}: the model fails there")
            start_rows.append(
                {"start": z0 * scale, "estimate": z0 * scale, "cost": math.inf, "evaluations": 1}
            )
            continue
        sol = optimize.least_squares(
            model,
            z0,
            jac=jac,
            bounds=(lo_z, hi_z),
            diff_step=DIFF_STEP,
            x_scale=1.0,
            method="trf",
            ftol=1e-10,
            xtol=1e-10,
            gtol=1e-10,
        )
        sols.append(sol)
        tick(f"start {len(sols)}/{len(starts)}: cost {float(sol.fun @ sol.fun):.6g}")
        start_rows.append(
            {
                "start": z0 * scale,
                "estimate": sol.x * scale,
                "cost": float(sol.fun @ sol.fun),
                "evaluations": model.evaluations - before,
            }
        )
    elapsed = time.perf_counter() - t0
    best = int(np.argmin([r["cost"] for r in start_rows]))
    sol = sols[best]
    if sol is None:
        raise HydroarmError("fit.starts", "the model fails (unstable) at every start")
    m, n = len(sol.fun), len(names)
    dof = max(m - n, 1)
    s2 = float(sol.fun @ sol.fun) / dof
    jac_sol = np.asarray(sol.jac)
    sv = np.linalg.svd(jac_sol, compute_uv=False)
    cov_z = np.linalg.pinv(jac_sol.T @ jac_sol) * s2
    cov = cov_z * np.outer(scale, scale)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if sv[-1] <= 1e-10 * sv[0]:  # rank deficient: no finite standard errors
        se = np.full(n, math.inf)
    d = np.sqrt(np.clip(np.diag(cov_z), 1e-300, None))
    corr = np.clip(cov_z / np.outer(d, d), -1.0, 1.0)
    tq = float(stats.t.ppf(0.975, dof))
    est = sol.x * scale
    joint = model.joint_at(sol.x)
    delays = problem.delays(est)
    samples = model_samples([joint], problem.traces, engine, delays=delays[None, :])[0]
    fitted = [column_values(s, tr.column) for s, tr in zip(samples, problem.traces, strict=True)]
    fitted_p = [
        column_values(s, "p_bar") if tr.pressure is not None else None
        for s, tr in zip(samples, problem.traces, strict=True)
    ]
    return FitResult(
        problem=problem,
        initial=start_rows[best]["start"],
        estimate=est,
        std_error=se,
        ci95_low=est - tq * se,
        ci95_high=est + tq * se,
        correlation=corr,
        singular_values=sv,
        residual_sd=math.sqrt(s2),
        dof=dof,
        evaluations=model.evaluations,
        elapsed_s=elapsed,
        joint=joint,
        fitted=fitted,
        fitted_pressure=fitted_p,
        delays=delays,
        warnings=identifiability_warnings(names, corr, sv),
        engine_runs=model.runs,
        starts=start_rows,
        best_start=best,
    )


def problem_bounds(problem: FitProblem, start: np.ndarray) -> list[tuple[float, float]]:
    """Each parameter's [low, high] (SI); a multi-start fit needs them finite."""
    out = [bounds_of(problem, k, start[i]) for i, k in enumerate(problem.parameters)]
    if problem.starts > 1:
        for k, (a, b) in zip(problem.parameters, out, strict=True):
            if not (math.isfinite(a) and math.isfinite(b)):
                raise HydroarmError(
                    f"fit.bounds.{k}",
                    f"a multi-start fit (starts = {problem.starts}) needs finite bounds: "
                    "give [low, high] with units",
                )
    return out


def start_points(lo: np.ndarray, hi: np.ndarray, n: int, seed: int = 0) -> np.ndarray:
    """``n`` scrambled Sobol points (seeded) inside finite bounds [lo, hi] (SI, one row per
    point): log-uniform for a parameter whose positive bounds span a decade or more
    (hi/lo ≥ 10), uniform otherwise."""
    from scipy.stats import qmc

    d = len(lo)
    sobol = qmc.Sobol(d, scramble=True, rng=np.random.default_rng(seed))
    u = sobol.random_base2(max(0, math.ceil(math.log2(n))))[:n]
    log = (lo > 0) & (hi >= 10 * lo)
    out = lo + u * (hi - lo)
    with np.errstate(divide="ignore", invalid="ignore"):
        out_log = np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo)))
    return np.where(log, out_log, out)


def identifiability_warnings(names, corr: np.ndarray, sv: np.ndarray) -> list[str]:
    out = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > CORRELATION_LIMIT:
                out.append(
                    f"{names[i]} and {names[j]}: correlation {corr[i, j]:+.3f}; "
                    "not separable by these data (fix one, or add a trace that tells them "
                    "apart, e.g. one covering the end of travel or another load)"
                )
    if len(sv) and sv[-1] <= 1e-6 * sv[0]:
        out.append(
            f"the scaled Jacobian is near singular (singular values {sv[0]:.3g} … {sv[-1]:.3g})"
        )
    return out


def bounds_of(problem: FitProblem, key: str, start: float) -> tuple[float, float]:
    if key in problem.bounds:
        return problem.bounds[key]
    if is_delay(key):  # a trace's own delay: the shared delay's bounds, if given
        return problem.bounds.get(DELAY, (-math.inf, math.inf))
    if problem.servo is not None:
        rule = SWEEP_PARAMETERS[key][2]
        if rule == "positive":
            return (abs(start) * 1e-3 if start else 1e-12, math.inf)
        return (0.0, math.inf) if rule == "nonnegative" else (-math.inf, math.inf)
    rule = FIELD_RULES[key][1]
    if rule == POSITIVE:
        return (abs(start) * 1e-3 if start else 1e-12, math.inf)
    if rule == NONNEGATIVE:
        return (0.0, math.inf)
    return (-math.inf, math.inf)


# ------------------------------------------------------------------ the file ---
def read_fit_file(path) -> FitProblem:
    """Read a fit file; every problem is a one-line error before any simulation."""
    text, path = read_text_file(path)
    return fit_problem_from_doc(parse_toml(text, path.name), path.parent, path.stem)


def fit_problem_from_doc(doc: dict, base_dir: Path = Path("."), name: str = "fit") -> FitProblem:
    servo = None
    known: tuple
    if is_component_file(doc):  # a component servo: its sections instead of [joint]
        reject_unknown_keys("", doc, SERVO_FIT_SECTIONS)
        servo_doc = {k: v for k, v in doc.items() if k not in ("fit", "trace")}
        servo = servo_from_doc(servo_doc, base_dir, name)
        joint = parameter_set("paper-calibrated")  # unused
        known = (*SWEEP_PARAMETERS, DELAY)
    else:
        reject_unknown_keys("", doc, FIT_SECTIONS)
        joint = joint_from_table(
            "joint",
            optional_table(doc, "joint"),
            default_set="paper-calibrated",
            physics=optional_table(doc, "physics"),
        )
        known = (*FITTABLE, DELAY)
    section = as_table("fit", doc.get("fit", {}))
    reject_unknown_keys(
        "fit", section, {"parameters", "bounds", "initial", "starts", "seed", "jacobian"}
    )
    require_keys("fit", section, ("parameters",))
    params = section["parameters"]
    if not isinstance(params, list) or not params:
        raise HydroarmError("fit.parameters", "must be a non-empty list of joint field names")
    what = "servo parameter" if servo else "joint parameter"
    for k in params:
        if not isinstance(k, str) or k not in known:
            raise unknown_name("fit.parameters", what, k, known)
        if servo is not None and k != DELAY:
            check_sweep_name("fit.parameters", k, servo.parameters)
    if len(set(params)) != len(params):
        raise HydroarmError("fit.parameters", "names a parameter twice")
    entries = doc.get("trace")
    if not isinstance(entries, list) or not entries:
        raise HydroarmError(
            "trace", "is missing (give [[trace]] entries with csv, load, direction or lever)"
        )
    traces = tuple(
        read_trace(f"trace[{i + 1}]", as_table(f"trace[{i + 1}]", e), base_dir, joint, servo)
        for i, e in enumerate(entries)
    )
    params = params + [f"{DELAY}_{i + 1}" for i, tr in enumerate(traces) if tr.fit_delay]
    # keys of [fit.initial] and [fit.bounds]: the parameters, and trigger_delay for every delay
    keys = set(params) | ({DELAY} if any(is_delay(k) for k in params) else set())
    initial = {}
    for k, v in as_table("fit.initial", section.get("initial", {})).items():
        if k not in keys:
            raise HydroarmError(f"fit.initial.{k}", "is not one of fit.parameters")
        initial[k] = parameter_value(f"fit.initial.{k}", k, v, servo)
    for k in params:
        if is_delay(k) and k not in initial:
            initial[k] = initial.get(DELAY, 0.0)
        if k not in initial and servo is None and getattr(joint, k) is None:
            raise HydroarmError(f"fit.initial.{k}", "is missing (the joint has no value)")
    bounds = {}
    for k, v in as_table("fit.bounds", section.get("bounds", {})).items():
        f = f"fit.bounds.{k}"
        if k not in keys:
            raise HydroarmError(f, "is not one of fit.parameters")
        if not isinstance(v, list) or len(v) != 2:
            raise HydroarmError(f, "must be [low, high] with units")
        low, high = (parameter_value(f, k, x, servo) for x in v)
        if not low < high:
            raise HydroarmError(f, "low must be below high")
        for kk in [k] if k in params else [x for x in params if is_delay(x)]:
            start = initial.get(kk, 0.0 if is_delay(kk) else model_value(joint, servo, kk))
            if not low <= start <= high:
                raise HydroarmError(f, "does not contain the initial value")
        bounds[k] = (low, high)
    if sum(sum(len(v) for _, v, _ in t.blocks()) for t in traces) <= len(params):
        raise HydroarmError("trace", "fewer samples than parameters")
    problem = FitProblem(
        joint=joint,
        parameters=tuple(params),
        traces=traces,
        initial=initial,
        bounds=bounds,
        name=text_value("name", doc.get("name", name)),
        starts=whole_number("fit.starts", section.get("starts", 1)),
        seed=whole_number("fit.seed", section.get("seed", 0), minimum=0),
        servo=servo,
        jacobian=text_value("fit.jacobian", section.get("jacobian", "forward"), JACOBIANS),
    )
    problem_bounds(problem, problem.start())  # a multi-start needs finite bounds
    return problem


def parameter_value(field: str, key: str, value, servo: ServoScenario | None = None) -> float:
    """A parameter's value in SI: a joint field (or a component servo's parameter) with its
    dimension and sign rule, a delay as a time of either sign."""
    if is_delay(key):
        return quantity(field, value, "time")
    if servo is not None:
        return sweep_value(field, key, value, servo.parameters)
    return field_value(field, key, value)


def model_value(joint: ServoJoint, servo: ServoScenario | None, key: str) -> float:
    if servo is not None:
        return float(servo.vector()[PARAMETER_INDEX[key]])
    return getattr(joint, key)


# quantities a trace's CSV can hold: (default column, its unit, dimension)
QUANTITIES = {
    "t": ("t_s", "s", "time"),
    "x": ("x_mm", "mm", "length"),
    "theta": ("theta_deg", "deg", "angle"),
    "p": ("p_bar", "bar", "pressure"),
    "lever": ("y_mm", "mm", "length or angle"),
}


def column_spec(field: str, value) -> tuple[str, str]:
    """``"name"`` (the unit after the last ``_``: ``p_bar``) or ``["name", "unit"]`` ->
    (column, unit)."""
    if isinstance(value, list):
        if len(value) != 2 or not all(isinstance(v, str) and v.strip() for v in value):
            raise HydroarmError(field, 'must be a column name or [column, unit], e.g. ["t", "ms"]')
        return value[0].strip(), value[1].strip()
    col = text_value(field, value)
    if "_" not in col:
        raise HydroarmError(
            field,
            f'{col!r} carries no unit in its name: give [{col!r}, unit], e.g. [{col!r}, "mm"]',
        )
    return col, col.rsplit("_", 1)[1]


def column_factor(field: str, quantity_name: str, unit: str) -> tuple[float, bool]:
    """SI value of one ``unit`` of a trace quantity, and whether it is an angle (a lever)."""
    if quantity_name == "lever":
        kind, v = length_or_angle(field, f"1 {unit}")
        return v, kind == "angle"
    dim = QUANTITIES[quantity_name][2]
    return quantity(field, f"1 {unit}", dim, positive=True), dim == "angle"


def read_trace(section: str, table: dict, base_dir: Path, joint: ServoJoint, servo=None) -> Trace:
    """A ``[[trace]]`` entry (docs/fit.md): its CSV columns in SI through their units, the
    input (saturation test or lever column), window, weight and delay. For a component servo
    (``servo``): the file's own input and load, the column ``position``."""
    if servo is not None:
        return read_servo_trace(section, table, base_dir, servo)
    reject_unknown_keys(section, table, TRACE_KEYS)
    require_keys(section, table, ("csv", "load"))
    if ("direction" in table) == ("lever" in table):
        raise HydroarmError(
            f"{section}.direction",
            "give direction (the saturation test) or lever (a lever column), one of them",
        )
    direction = None
    if "direction" in table:
        direction = text_value(f"{section}.direction", table["direction"], ("raise", "lower"))
    raw = table["load"]
    load = (
        parse_load(f"{section}.load", raw)
        if isinstance(raw, dict)
        else paper_load(raw, field=f"{section}.load")
    )
    weight = trace_weight(section, table)
    delay, fit_delay = trace_delay(section, table)
    field_csv = f"{section}.csv"
    path = (base_dir / text_value(field_csv, table["csv"])).resolve()
    if not path.is_file():
        raise HydroarmError(field_csv, f"{path.name}: no such file")
    header = read_csv_columns(field_csv, path)
    # the columns: [trace.columns] (name or [name, unit]), lever = ..., else the defaults
    mapping = as_table(f"{section}.columns", table.get("columns", {}))
    for k in mapping:
        if k not in QUANTITIES:
            raise unknown_name(f"{section}.columns", "quantity", k, tuple(QUANTITIES))
    if "lever" in table:
        if "lever" in mapping:
            raise HydroarmError(f"{section}.lever", "give lever or columns.lever, not both")
        mapping["lever"] = table["lever"]
    if "lever" in mapping and "lever" not in table:
        raise HydroarmError(f"{section}.columns.lever", "give it as lever = ... (the input)")
    specs = {k: column_spec(f"{section}.columns.{k}", v) for k, v in mapping.items()}
    specs.setdefault("t", QUANTITIES["t"][:2])
    if "x" in specs and "theta" in specs:
        raise HydroarmError(f"{section}.columns", "give x or theta, not both")
    if "x" not in specs and "theta" not in specs:
        found = next((k for k in ("x", "theta") if QUANTITIES[k][0] in header), None)
        if found is None:
            raise HydroarmError(
                field_csv,
                f"{path.name} needs the columns t_s and x_mm or theta_deg, or a "
                f"{section}.columns mapping (columns: {', '.join(header)})",
            )
        specs[found] = QUANTITIES[found][:2]
    data, angle = {}, False
    for k, (col, unit) in specs.items():
        if col not in header:
            raise HydroarmError(
                field_csv,
                f"{path.name} has no column {col!r} for {k} (columns: {', '.join(header)})",
            )
        factor, is_angle = column_factor(f"{section}.columns.{k}", k, unit)
        data[k] = header[col] * factor  # SI
        angle = angle or (k == "lever" and is_angle)
    t = data["t"]
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise HydroarmError(field_csv, f"{path.name}: times must be finite and increasing")
    for k, v in data.items():
        if not np.all(np.isfinite(v)):
            raise HydroarmError(field_csv, f"{path.name}: {specs[k][0]} values must be finite")
    lever_t = lever = None
    if "lever" in data:
        lever_t, lever = t, data["lever"]
        if angle and np.any(np.abs(lever) >= joint.max_angle):
            raise HydroarmError(
                field_csv, f"{path.name}: a lever angle is beyond the crank's reach"
            )
        if not angle and np.any(np.abs(lever) > joint.crank_radius):
            raise HydroarmError(
                field_csv, f"{path.name}: a lever position is beyond the crank radius"
            )
    if "window" in table:
        w = table["window"]
        if not isinstance(w, list) or len(w) != 2:
            raise HydroarmError(f"{section}.window", 'must be [start, end], e.g. ["0 s", "1 s"]')
        a, b = (time_value(f"{section}.window", x) for x in w)
        if not a < b:
            raise HydroarmError(f"{section}.window", "start must be before end")
        keep = (t >= a) & (t <= b)
        data = {k: v[keep] for k, v in data.items()}
        t = data["t"]
    if len(t) < MIN_SAMPLES:
        raise HydroarmError(
            field_csv, f"{path.name}: fewer than {MIN_SAMPLES} samples (in the window)"
        )
    if direction is not None and t[0] < 0:
        raise HydroarmError(field_csv, f"{path.name}: times before 0 s (the step is at 0 s)")
    pos = "x" if "x" in data else "theta"
    column = QUANTITIES[pos][0]
    values = data[pos] / (1e-3 if pos == "x" else math.pi / 180.0)  # SI -> mm, deg
    if np.ptp(values) == 0:
        raise HydroarmError(field_csv, f"{path.name}: {specs[pos][0]} does not change")
    pressure = data["p"] * 1e-5 if "p" in data else None  # Pa -> bar
    if pressure is not None and np.ptp(pressure) == 0:
        raise HydroarmError(field_csv, f"{path.name}: {specs['p'][0]} does not change")
    name = text_value(f"{section}.name", table.get("name", f"{path.stem}"))
    return Trace(
        t=t,
        values=values,
        column=column,
        load=load,
        direction=direction,
        weight=weight,
        name=name,
        pressure=pressure,
        lever_t=lever_t,
        lever=lever,
        lever_angle=angle,
        delay=delay,
        fit_delay=fit_delay,
    )


def read_servo_trace(section: str, table: dict, base_dir: Path, servo: ServoScenario) -> Trace:
    """A trace of a component servo: ``t`` and ``position`` (default ``t_s`` and
    ``position_m``, or ``angle_deg`` for an angular load, as its run's CSV), window, weight,
    delay; the run is the file's (its [input], [load], [initial])."""
    reject_unknown_keys(section, table, SERVO_TRACE_KEYS)
    require_keys(section, table, ("csv",))
    linear = int(servo.vector()[PARAMETER_INDEX["load_kind"]]) == LOAD_MASS
    column = "position_m" if linear else "angle_deg"
    mapping = as_table(f"{section}.columns", table.get("columns", {}))
    for k in mapping:
        if k not in ("t", "position"):
            raise unknown_name(f"{section}.columns", "quantity", k, ("t", "position"))
    specs = {k: column_spec(f"{section}.columns.{k}", v) for k, v in mapping.items()}
    specs.setdefault("t", ("t_s", "s"))
    specs.setdefault("position", (column, column.rsplit("_", 1)[1]))
    field_csv = f"{section}.csv"
    path = (base_dir / text_value(field_csv, table["csv"])).resolve()
    if not path.is_file():
        raise HydroarmError(field_csv, f"{path.name}: no such file")
    header = read_csv_columns(field_csv, path)
    data = {}
    for k, (col, unit) in specs.items():
        if col not in header:
            raise HydroarmError(
                field_csv,
                f"{path.name} has no column {col!r} for {k} (columns: {', '.join(header)})",
            )
        dim = "time" if k == "t" else ("length" if linear else "angle")
        f = f"{section}.columns.{k}"
        data[k] = header[col] * quantity(f, f"1 {unit}", dim, positive=True)
        if not np.all(np.isfinite(data[k])):
            raise HydroarmError(field_csv, f"{path.name}: {col} values must be finite")
    t = data["t"]
    if np.any(np.diff(t) <= 0):
        raise HydroarmError(field_csv, f"{path.name}: times must be finite and increasing")
    t, v = trace_window(section, table, t, data["position"])
    if len(t) < MIN_SAMPLES:
        raise HydroarmError(
            field_csv, f"{path.name}: fewer than {MIN_SAMPLES} samples (in the window)"
        )
    values = v if linear else np.degrees(v)
    if np.ptp(values) == 0:
        raise HydroarmError(field_csv, f"{path.name}: {specs['position'][0]} does not change")
    delay, fit_delay = trace_delay(section, table)
    return Trace(
        t=t,
        values=values,
        column=column,
        load=paper_load(1),  # unused: the servo's own load
        weight=trace_weight(section, table),
        name=text_value(f"{section}.name", table.get("name", path.stem)),
        delay=delay,
        fit_delay=fit_delay,
    )


def trace_window(section: str, table: dict, t: np.ndarray, v: np.ndarray):
    """The samples within the trace's ``window`` (all without one)."""
    if "window" not in table:
        return t, v
    w = table["window"]
    if not isinstance(w, list) or len(w) != 2:
        raise HydroarmError(f"{section}.window", 'must be [start, end], e.g. ["0 s", "1 s"]')
    a, b = (time_value(f"{section}.window", x) for x in w)
    if not a < b:
        raise HydroarmError(f"{section}.window", "start must be before end")
    keep = (t >= a) & (t <= b)
    return t[keep], v[keep]


def trace_weight(section: str, table: dict) -> float:
    weight = table.get("weight", 1.0)
    if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not weight > 0:
        raise HydroarmError(f"{section}.weight", f"must be a positive number, got {weight!r}")
    if not math.isfinite(weight):
        raise HydroarmError(f"{section}.weight", "must be finite")
    return float(weight)


def trace_delay(section: str, table: dict) -> tuple[float | None, bool]:
    """(fixed delay [s] or None, whether the trace has its own fitted delay)."""
    if "delay" not in table:
        return None, False
    if table["delay"] == "fit":
        return None, True
    return quantity(f"{section}.delay", table["delay"], "time"), False


def servo_toml(servo: ServoScenario, problem: FitProblem, estimate: np.ndarray) -> str:
    """The fitted parameters of a component servo (SI, with units), by their names in
    :data:`hydroarm.core.servo.PARAMETERS`: set them in the file's sections (docs/fit.md)."""
    lines = [
        f"# fitted by hydroarm fit ({problem.name}): component servo parameters (SI), by",
        "# their names in hydroarm.core.servo.PARAMETERS (as a servo sweep names them)",
        "[fitted]",
    ]
    for k, v in zip(problem.parameters, estimate, strict=True):
        unit = servo_unit(k, servo)
        lines.append(f'{k} = "{float(v)!r} {unit}"' if unit != "1" else f"{k} = {float(v)!r}")
    return "\n".join(lines) + "\n"


def fitted_toml(joint: ServoJoint, name: str = "fit", notes=()) -> str:
    """A ``[joint]`` table with every field of ``joint`` (SI, with units); ``notes``: comment
    lines above it (the traces' delays)."""
    lines = [f"# fitted by hydroarm fit ({name}); load as a scenario's [joint]"]
    lines += [f"# {n}" for n in notes] + ["[joint]"]
    for k, v in joint.as_dict().items():
        if v is None or k == "name":
            continue
        if isinstance(v, str):
            lines.append(f'{k} = "{v}"')
            continue
        unit = SI_UNITS[FIELD_DIMENSIONS[k]]
        lines.append(f'{k} = "{v!r} {unit}"' if unit else f"{k} = {v!r}")
    return "\n".join(lines) + "\n"
