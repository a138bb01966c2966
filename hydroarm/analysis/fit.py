"""Fit a joint's parameters to measured traces and scalar targets (issue 16).

A fit file names a starting joint (``[joint]``, as in scenario files), the free parameters
(``[fit]``, with ``[fit.tied]`` fields that follow from them and ``[fit.solve]`` fields
solved for a stall target) and the data: measured traces (``[[trace]]``: CSV files with
``t_s`` and ``x_mm`` or ``theta_deg``, as ``hydroarm simulate --out`` writes them, each with
its load and input) and/or scalar targets (``[[target]]``, `hydroarm.analysis.targets`).
[`fit`][hydroarm.fit] runs a bounded least-squares fit and reports the estimates with standard
errors, 95 % intervals, the correlation matrix and the singular values of the scaled Jacobian, and
names parameter pairs the data cannot separate. The statistics and their assumptions are in
docs/fit.md.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..batch.traces import THETA, P, X, scenario_traces
from ..core.servo import PARAMETER_INDEX, S_Q
from ..display import Summarised, fmt
from ..errors import HydroarmError
from ..files import (
    atomic_write_text,
    check_output_folder,
    checked_path,
    move_into,
    staging_folder,
)
from ..io.catalog import paper_load, parameter_set_names
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
from ..model.circuit import Circuit
from ..model.joint import Load, ServoJoint
from ..model.lever import LeverInput
from ..model.rules import FIELD_RULES, NONNEGATIVE, POSITIVE
from ..model.scenario import DEFAULT_STEP, Scenario, default_duration, saturation_test, simulate
from ..model.servo import ServoScenario, run_servos
from ..plotting.fit import fit_profile_figure, fit_targets_figure, fit_trace_figure
from ..plotting.joint import save_figure
from .fit_intervals import (
    INTERVAL_KINDS,
    IntervalChecks,
    Profile,
    ProfileRun,
    check_profile_budget,
    interval_checks,
    linear_ends,
    profile_intervals,
    profile_refits_default,
)
from .fit_system import (
    SystemSource,
    SystemTrace,
    check_trace,
    column_spec,
    cut_to,
    default_bounds,
    fitted_system_toml,
    read_system,
    read_system_trace,
    system_samples,
)
from .systems import is_system_study
from .targets import (
    apply_ties,
    loo_groups,
    read_solves,
    read_target,
    read_ties,
    solve_fields,
    solved_sensitivity,
    target_residuals,
    target_values,
)
from .targets import (
    leave_one_out as leave_one_out_rows,
)

# ServoJoint fields that can be fitted (numbers; the stiffness is given through the volume)
FITTABLE = tuple(k for k in (*JOINT_KEYS, *PHYSICS_KEYS) if k != "hydraulic_stiffness")
FIT_SECTIONS = {"joint", "physics", "fit", "trace", "target", "name", "description"}
SERVO_FIT_SECTIONS = {"fit", "trace", *COMPONENT_SECTIONS}
SERVO_TRACE_KEYS = {"csv", "columns", "window", "weight", "delay", "name"}
TRACE_KEYS = {
    "csv",
    "load",
    "direction",
    "lever",
    "columns",
    "window",
    "weight",
    "delay",
    "name",
    "group",
}
FIT_KEYS = {
    "parameters",
    "bounds",
    "initial",
    "starts",
    "seed",
    "jacobian",
    "tied",
    "solve",
    "leave_one_out",
    "bootstrap",
    "intervals",
    "profile_refits",
}
# a fit of any system named by file (docs/fit.md "Any system")
SYSTEM_FIT_SECTIONS = {"name", "description", "system", "fit", "trace"}
# the joint's fit keys less what only the joint's metrics have (ties, solved fields,
# leave-one-out over its load cases)
SYSTEM_FIT_KEYS = FIT_KEYS - {"tied", "solve", "leave_one_out"}
# [fit] bootstrap = N: refits on resampled residuals. At least MIN_BOOTSTRAP, so that the
# 2.5 % and 97.5 % quantiles fall between draws; at most MAX_BOOTSTRAP refits (each a
# whole fit from the estimate: a few engine runs)
MIN_BOOTSTRAP = 20
MAX_BOOTSTRAP = 1000
# multi-start: each start is a whole least-squares fit (tens to hundreds of runs); 1000
# Sobol points already cover a 10-parameter box at ~2 points per axis pair
MAX_STARTS = 1000
STARTS_WHY = "starts, each a whole fit"
# refits of intervals = "bootstrap" without bootstrap = N (the example's number)
DEFAULT_BOOTSTRAP = 100
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
TRACE_TOL = 1e-10  # least_squares' ftol, xtol, gtol of a fit of traces only
TARGET_TOL = 1e-6  # least_squares' ftol, xtol, gtol when there are targets (docs/fit.md)
# a fit with targets stops once Σ residual² is below this (targets met to 1 % of their
# uncertainty, as when there are as many targets as parameters)
CHI2_FLOOR = 1e-4


@dataclass(frozen=True)
class Trace:
    """One measured run, fitted (docs/fit.md).

    The input is the paper's saturation test (``direction``) or a measured lever ``lever``
    at times ``lever_t``.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times [s].
    values : numpy.ndarray
        The samples of ``column``.
    column : str
        ``"x_mm"`` (jack position [mm]) or ``"theta_deg"`` (joint angle [deg]).
    load : Load
        The load of the run.
    direction : str, optional
        ``"raise"`` or ``"lower"``: the paper's saturation test.
    weight : float
        Weight of the trace's residuals [-].
    name : str
        Label.
    pressure : numpy.ndarray, optional
        Load pressure [bar] at the same times.
    lever_t : numpy.ndarray, optional
        Times of the measured lever [s].
    lever : numpy.ndarray, optional
        Measured lever [m, or rad when ``lever_angle``].
    lever_angle : bool
        The lever is given as a joint angle [rad].
    delay : float, optional
        A known shift of the model's response [s] (measured time = model time + delay; None:
        the shared ``trigger_delay`` when fitted, else none).
    fit_delay : bool
        The trace has its own fitted delay (parameter ``trigger_delay_<n>``).
    group : str
        Leave-one-out group ("": the trace's name).
    """

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
    group: str = ""  # leave-one-out group ("": the trace's name)

    def __post_init__(self):
        if not self.group:
            object.__setattr__(self, "group", self.name)

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
    """A fit problem (a fit file, docs/fit.md).

    A starting joint (or a component ``servo``, or a ``system``), the parameters to fit
    (fields and trigger delays, with initial values and bounds), the traces and targets, and
    the fit's options.

    Parameters
    ----------
    joint : ServoJoint
        The starting joint.
    parameters : tuple of str
        The names of the parameters fitted (fields, ``trigger_delay``).
    traces : tuple of Trace
        The measured runs.
    initial : dict
        Name → initial value (SI; default: the model's).
    bounds : dict
        Name → (low, high) (SI).
    name : str
        Label.
    servo : ServoScenario, optional
        A component servo fitted instead of ``joint`` (then unused).
    targets : tuple of Target
        Scalar-metric targets, after the traces.
    starts : int
        Multi-start: this many Sobol points inside the (finite) bounds [-].
    seed : int
        Seed of the scrambled Sobol sequence.
    jacobian : str
        Finite differences: ``"forward"`` (N runs) or ``"central"`` (2N).
    tied : tuple of Tie
        Fields set from the parameters.
    solves : tuple of Solve
        Fields solved for a stall target.
    leave_one_out : bool or tuple of str
        True (every group) or the groups to leave out in turn.
    system : SystemSource, optional
        A system named by file (a circuit, a mechanism, a component servo) fitted instead of
        ``joint``.
    bootstrap : int
        Refits on resampled residuals [-] (0: none).
    intervals : tuple of str
        The intervals reported beside the Jacobian's (``"bootstrap"``, ``"profile"``).
    profile_refits : int
        The profile's budget of refits in all [-] (0: the default).
    """

    joint: ServoJoint
    parameters: tuple[str, ...]
    traces: tuple[Trace, ...] = ()
    initial: dict = field(default_factory=dict)
    bounds: dict = field(default_factory=dict)
    name: str = "fit"
    # a component servo (its file's sections) fitted instead of ``joint`` (then unused)
    servo: ServoScenario | None = None
    targets: tuple = ()  # scalar-metric targets (hydroarm/analysis/targets.py), after the traces
    starts: int = 1  # multi-start: this many Sobol points inside the (finite) bounds
    seed: int = 0  # of the scrambled Sobol sequence
    jacobian: str = "forward"  # finite differences: "forward" (N runs) or "central" (2N)
    tied: tuple = ()  # fields set from the parameters (`Tie`)
    solves: tuple = ()  # fields solved for a stall target (`Solve`)
    leave_one_out: bool | tuple = False  # True (every group) or the groups to leave out
    # any system named by file (a circuit, a mechanism, a component servo) fitted instead
    # of ``joint`` (hydroarm/analysis/fit_system.py)
    system: SystemSource | None = None
    bootstrap: int = 0  # refits on resampled residuals (0: none)
    # the intervals reported beside the Jacobian's ("bootstrap", "profile"; docs/fit.md)
    intervals: tuple[str, ...] = ("jacobian",)
    profile_refits: int = 0  # the profile's budget of refits in all (0: the default)

    @property
    def profile_budget(self) -> int:
        """The profile's refits in all: ``profile_refits``, else its default."""
        return self.profile_refits or profile_refits_default(len(self.parameters))

    @property
    def met(self) -> tuple[str, ...]:
        """Names of the targets met by a solved field."""
        return tuple(sv.target for sv in self.solves)

    def joint_at(self, values) -> ServoJoint:
        """The joint with the parameters at ``values`` (SI), the tied and solved fields."""
        return self.joints_at([values])[0]

    def joints_at(self, points) -> list[ServoJoint]:
        """[`joint_at`][hydroarm.FitProblem.joint_at] of several points (the solved fields searched
        side by side)."""
        joints = []
        for v in points:
            values = dict(zip(self.parameters, map(float, v), strict=True))
            changes = {k: values[k] for k in self.joint_parameters}
            joints.append(apply_ties(self.joint, changes, self.tied))
        return solve_fields(joints, self.solves, self.targets)

    def start(self) -> np.ndarray:
        return np.array(
            [self.initial.get(k, 0.0 if is_delay(k) else self.value(k)) for k in self.parameters]
        )

    def value(self, key: str) -> float:
        """A parameter's value in the model fitted (the joint, or the servo's vector)."""
        if self.system is not None:
            return self.system.runner.current(key)
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


@dataclass(repr=False)
class FitResult(Summarised):
    """Estimates (SI) with their uncertainty and the traces measured versus fitted.

    Parameters
    ----------
    problem : FitProblem
        The problem fitted.
    initial : numpy.ndarray
        The parameters' initial values (SI).
    estimate : numpy.ndarray
        The estimate (SI).
    std_error : numpy.ndarray
        Standard errors (SI).
    ci95_low, ci95_high : numpy.ndarray
        The 95 % intervals' bounds (SI).
    correlation : numpy.ndarray
        Correlation matrix of the estimate [-].
    singular_values : numpy.ndarray
        Singular values of the scaled Jacobian [-].
    residual_sd : float
        Standard deviation of the scaled residuals [-].
    dof : int
        Degrees of freedom [-].
    evaluations : int
        Model evaluations [-].
    elapsed_s : float
        Wall-clock time [s].
    joint : ServoJoint or ServoScenario
        The fitted model (a servo's scenario for a servo fit).
    fitted : list
        Simulated values at the measured times, per trace.
    fitted_pressure : list
        Simulated pressure [bar] per trace, or None.
    delays : numpy.ndarray, optional
        Each trace's delay at the estimate [s].
    warnings : list
        Identifiability and convergence warnings.
    engine_runs : int
        Calls of the engine [-] (a batch of parameter vectors counts once).
    starts : list
        Per start: start, estimate, cost, evaluations.
    best_start : int
        Index of the best start.
    target_model : numpy.ndarray
        The model's value of each target (SI).
    chi2 : float
        Σ of the squared target residuals [-].
    chi2_dof : int
        Targets − solved fields − parameters (targets only; 0 with traces) [-].
    loo : list
        The leave-one-out rows.
    covariance : numpy.ndarray
        Covariance of the estimate (SI).
    quantile : float
        Quantile of the 95 % intervals (t or normal) [-].
    boot : numpy.ndarray, optional
        The bootstrap refits' estimates (rows, SI); None without.
    boot_failed : int
        Bootstrap refits that failed [-].
    profiles : list of Profile, optional
        Profile-likelihood intervals; None without.
    profile_delta : float
        The profiles' threshold Δ in cost Σr² [-].
    cost : float
        Cost Σr² at the estimate [-].
    checks : IntervalChecks, optional
        Why each Jacobian interval is not to be trusted.
    """

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
    target_model: np.ndarray = field(default_factory=lambda: np.zeros(0))  # SI, per target
    chi2: float = math.nan  # Σ of the squared target residuals
    chi2_dof: int = 0  # targets − solved fields − parameters (targets only); 0 with traces
    loo: list = field(default_factory=list)  # leave_one_out rows
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # SI
    quantile: float = 1.96  # of the 95 % intervals (t or normal)
    # the bootstrap (``[fit] bootstrap``): the refits' estimates (rows, SI) and how many
    # failed; None without
    boot: np.ndarray | None = None
    boot_failed: int = 0
    # the profile-likelihood intervals (``[fit] intervals = "profile"``), None without;
    # their threshold Δ in cost Σr² and the cost at the estimate
    profiles: list[Profile] | None = None
    profile_delta: float = math.nan
    cost: float = math.nan
    # why each Jacobian interval is not to be trusted (fit_intervals.interval_checks)
    checks: IntervalChecks | None = None
    _solved: list | None = None

    def _summary(self) -> list[tuple[str, str]]:
        rows = [
            (f"{k} [{u}]", f"{fmt(v)} ± {fmt(s, '', 2)}")
            for k, u, v, s in zip(
                self.parameters, self.units(), self.estimate, self.std_error, strict=False
            )
        ]
        rows += [
            ("residual sd", fmt(self.residual_sd, "", 3)),
            ("evaluations", f"{self.evaluations} in {fmt(self.elapsed_s, 's', 3)}"),
        ]
        if self.warnings:
            rows.append(("warnings", str(len(self.warnings))))
        return rows

    @property
    def boot_std_error(self) -> np.ndarray:
        """The bootstrap refits' standard deviation per parameter (SI)."""
        assert self.boot is not None
        return np.std(self.boot, axis=0, ddof=1)

    @property
    def boot_interval(self) -> tuple[np.ndarray, np.ndarray]:
        """The bootstrap's percentile 95 % interval: the refits' 2.5 % and 97.5 %
        quantiles (SI)."""
        assert self.boot is not None
        lo, hi = np.percentile(self.boot, [2.5, 97.5], axis=0)
        return lo, hi

    @property
    def chi2_p(self) -> float:
        """P(χ² ≥ the one seen) for ``chi2_dof`` degrees of freedom (NaN without)."""
        from scipy import stats

        if self.chi2_dof <= 0 or not math.isfinite(self.chi2):
            return math.nan
        return float(stats.chi2.sf(self.chi2, self.chi2_dof))

    @property
    def solved(self) -> list[dict]:
        """Rows of [`table`][hydroarm.FitResult.table] for the solved fields, their standard errors
        propagated (computed when first asked for: a few more stall searches)."""
        if self._solved is None:
            j = self.joint
            self._solved = (
                solved_rows(self.problem, self.estimate, self.covariance, j, self.quantile)
                if isinstance(j, ServoJoint)
                else []
            )
        return self._solved

    def target_rows(self) -> list[dict]:
        """One row per target: value, uncertainty, the fitted model's value (SI)."""
        return [
            {
                "target": tg.name,
                "metric": tg.metric,
                "group": tg.group,
                "value": tg.value,
                "uncertainty": tg.uncertainty,
                "model": float(m),
                "residual": float((m - tg.value) / tg.uncertainty),
                "unit": tg.unit,
            }
            for tg, m in zip(self.problem.targets, self.target_model, strict=True)
        ]

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.problem.parameters

    def units(self) -> list[str]:
        source = self.problem.system
        if source is not None:
            return ["s" if is_delay(k) else (source.runner.unit(k) or "1") for k in self.parameters]
        servo = self.problem.servo
        if servo is not None:
            return [servo_unit(k, servo) for k in self.parameters]
        return [parameter_unit(k) for k in self.parameters]

    def table(self) -> list[dict]:
        """One row per fitted parameter, then one per solved field (SI units); with a
        bootstrap, its standard error and percentile interval too."""
        rows = [
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
        if self.boot is not None:
            se, (lo, hi) = self.boot_std_error, self.boot_interval
            for i, r in enumerate(rows):
                r.update(boot_std_error=float(se[i]), boot_low=float(lo[i]), boot_high=float(hi[i]))
        if self.profiles is not None:
            for r, pf in zip(rows, self.profiles, strict=True):
                r.update(profile_low=pf.low, profile_high=pf.high, profile_ends=pf.ends)
        if self.checks is not None:
            for i, r in enumerate(rows):
                r["jacobian_warning"] = self.checks.flag(i)
        return rows + list(self.solved)

    def write(self, out) -> Path:
        """Write fit.csv, correlation.csv, fitted.toml, the plots (trace<n>.png, with a
        measured pressure trace<n>_p.png), fit_report.md and fit_report.html into the folder
        ``out``: made in a staging folder beside it and moved into place at the end."""
        out = check_output_folder("--out", out)
        with staging_folder(out) as stage:
            atomic_write_text(stage / "fit.csv", self.csv_text())
            atomic_write_text(stage / "correlation.csv", self.correlation_csv())
            atomic_write_text(stage / "fitted.toml", self.fitted_toml(out))
            plots = [n for i in range(len(self.problem.traces)) for n in self._plots(stage, i)]
            extra = []
            if self.problem.targets:
                atomic_write_text(
                    stage / "targets.csv", rows_csv(TARGET_COLUMNS, self.target_rows())
                )
                plots.append(self._targets_plot(stage))
                extra.append("targets.csv")
            if self.loo:
                atomic_write_text(stage / "leave_one_out.csv", rows_csv(LOO_COLUMNS, self.loo))
                extra.append("leave_one_out.csv")
            if self.profiles is not None:
                fig = fit_profile_figure(
                    self.profiles, self.cost, self.profile_delta,
                    (self.ci95_low, self.ci95_high), title=f"{self.problem.name}: profiles",
                    units=dict(zip(self.problem.parameters, self.units(), strict=True)),
                )  # fmt: skip
                save_figure(fig, stage / "profile.png")
                plots.append("profile.png")
            blocks = self.blocks(plots)
            atomic_write_text(stage / "fit_report.md", to_markdown(blocks))
            title = f"hydroarm fit: {self.problem.name}"
            atomic_write_text(stage / "fit_report.html", to_html(blocks, stage, title))
            names = [*OUTPUT_FILES, *extra, *plots]
            move_into(stage, out, names)
        return out

    def fitted_toml(self, out: Path) -> str:
        """fitted.toml: the fitted model as a file that loads back (a joint's ``[joint]``,
        a system file; a component servo fitted through its sections: ``[fitted]``)."""
        pr = self.problem
        if pr.system is not None:
            keys = pr.joint_parameters
            values = {k: float(self.estimate[pr.parameters.index(k)]) for k in keys}
            units = dict(zip(pr.parameters, self.units(), strict=True))
            header = "\n".join(
                [
                    f"fitted by hydroarm fit ({pr.name}) from {pr.system.path.name}:",
                    *(f"  {k} = {values[k]:.9g} {units[k]}" for k in keys),
                    *self.delays_text(),
                ]
            )
            return fitted_system_toml(pr.system, values, units, header, out)
        if isinstance(self.joint, ServoJoint):
            return fitted_toml(self.joint, pr.name, self.delays_text())
        assert isinstance(self.joint, ServoScenario)
        return servo_toml(self.joint, pr, self.estimate)

    def csv_text(self) -> str:
        """fit.csv: one row per parameter (SI); with a bootstrap, its columns after the
        linearised ones, then the profile's; then ``jacobian_warning`` (why the Jacobian's
        interval is not to be trusted: codes joined by ``;``, or ``none``) and the unit."""
        cols = ["initial", "estimate", "std_error", "ci95_low", "ci95_high"]
        extra = ["boot_std_error", "boot_low", "boot_high"] if self.boot is not None else []
        extra += ["profile_low", "profile_high"] if self.profiles is not None else []
        text = ["profile_ends"] if self.profiles is not None else []
        head = ",".join(["parameter", *cols, *extra, *text, "jacobian_warning", "unit"])
        lines = [head] + [
            ",".join(
                [r["parameter"]]
                + [f"{r[c]:.9g}" for c in cols]
                + [f"{r.get(c, math.nan):.9g}" for c in extra]
                + [r.get(c, "") for c in text]
                + [r.get("jacobian_warning", ""), r["unit"]]
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
        if isinstance(tr, SystemTrace):  # one figure per fitted output
            names = []
            for k, (o, v) in enumerate(zip(tr.outputs, tr.values, strict=True)):
                fig = fit_trace_figure(tr.t, v, self.fitted[i][:, k], o, title=tr.name)
                names.append(f"trace{i + 1}.png" if k == 0 else f"trace{i + 1}_{o}.png")
                save_figure(fig, out / names[-1])
            return names
        fig = fit_trace_figure(tr.t, tr.values, self.fitted[i], tr.column, title=tr.name)
        names = [f"trace{i + 1}.png"]
        save_figure(fig, out / names[0])
        if tr.pressure is not None:
            fp = self.fitted_pressure[i]
            fig = fit_trace_figure(tr.t, tr.pressure, fp, "p_bar", title=tr.name)
            names.append(f"trace{i + 1}_p.png")
            save_figure(fig, out / names[1])
        return names

    def _targets_plot(self, out: Path) -> str:
        rows = self.target_rows()
        pred = None
        if self.loo:
            left = {r["item"]: r["prediction_z"] for r in self.loo if r["kind"] == "target"}
            pred = [left.get(r["target"], math.nan) for r in rows]
        fig = fit_targets_figure(
            [r["target"] for r in rows],
            [r["residual"] for r in rows],
            pred,
            title=f"{self.problem.name}: targets",
        )
        save_figure(fig, out / "targets.png")
        return "targets.png"

    def _parameter_table(self) -> tuple:
        """The report's table of the parameters (with the bootstrap's and the profile's
        columns when run, and why a Jacobian interval is not to be trusted)."""
        boot = self.boot is not None
        prof = self.profiles is not None
        head = ["parameter", "initial", "estimate", "std error", "95 % interval"]
        if boot or prof:
            head = [*head[:3], "std error (Jacobian)", "95 % interval (Jacobian)"]
        if boot:
            head += ["std error (bootstrap)", "95 % interval (bootstrap)"]
        if prof:
            head += ["95 % interval (profile)"]
        if self.checks is not None:
            head += ["Jacobian interval"]
        rows = []
        for r in self.table():
            row = [
                r["parameter"],
                f"{r['initial']:.5g}",
                f"{r['estimate']:.5g}",
                f"{r['std_error']:.3g}",
                f"{r['ci95_low']:.5g} … {r['ci95_high']:.5g}",
            ]
            if boot:
                row += (
                    [f"{r['boot_std_error']:.3g}", f"{r['boot_low']:.5g} … {r['boot_high']:.5g}"]
                    if "boot_low" in r
                    else ["", ""]
                )
            if prof:
                by_name = {p.parameter: p for p in self.profiles or ()}
                pf = by_name.get(r["parameter"])
                row.append(pf.describe() if pf is not None else "")
            if self.checks is not None:
                flag = r.get("jacobian_warning", "")
                row.append("trusted" if flag == "none" else flag.replace(";", ", "))
            rows.append([*row, r["unit"]])
        return ("table", [*head, "unit"], rows)

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
        """The report as blocks of `hydroarm.io.report` (Markdown and HTML)."""
        names = self.parameters
        pr = self.problem
        samples = sum(len(v) for t in pr.traces for _, v, _ in t.blocks())
        data = []
        if pr.traces:
            data.append(
                f"{len(pr.traces)} traces, {samples} samples (residual standard deviation "
                f"{self.residual_sd:.4g} of each trace's range)"
            )
        if pr.targets:
            chi = f"χ² = {self.chi2:.4g}"
            if self.chi2_dof > 0:
                chi += f" for {self.chi2_dof} degrees of freedom, P(≥) = {self.chi2_p:.3g}"
            data.append(f"{len(pr.targets)} targets ({chi})")
        b: list = [
            ("h", 1, f"Fit: {pr.name}"),
            (
                "p",
                f"{'; '.join(data)}; {len(names)} parameters, {self.dof} degrees of freedom; "
                f"{self.evaluations} model evaluations ({self.engine_runs} engine runs) in "
                f"{self.elapsed_s:.2f} s.",
            ),
            self._parameter_table(),
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
        if self.boot is not None:
            n = len(self.boot)
            b.append(
                (
                    "p",
                    f"Bootstrap: {n} refits (seed {pr.seed}) from the estimate, each to the "
                    "fitted model's values plus the residuals resampled with replacement "
                    "within each measured column (the residuals divided by √(1 − leverage) "
                    "and centred: Davison & Hinkley 1997, algorithm 6.3); the interval is "
                    "the refits' 2.5 % and 97.5 % quantiles, the standard error their "
                    "standard deviation"
                    + (
                        f"; {self.boot_failed} refits failed and are left out"
                        if self.boot_failed
                        else ""
                    )
                    + ". The linearised (Jacobian) interval beside it assumes the model "
                    "linear in its parameters over the interval.",
                )
            )
        if self.profiles is not None:
            refits = sum(p.refits for p in self.profiles)
            failed = sum(p.failed for p in self.profiles)
            b.append(
                (
                    "p",
                    f"Profile likelihood: each parameter held on each side of its estimate, the "
                    "others re-optimised (the fit's optimiser and residuals), until the cost "
                    f"Σr² rose by Δ = t²₀.₉₇₅({self.dof})·s² = {self.profile_delta:.4g} above "
                    f"its minimum {self.cost:.6g} (Gaussian residuals of one variance s² "
                    "estimated from the fit; Venzon & Moolgavkar 1988, Raue et al. 2009); "
                    f"{refits} refits ({failed} failed), at most {self.problem.profile_budget} "
                    "(fit.profile_refits). An end at a bound is the bound (the cost stays "
                    "below the threshold down to it); an end marked open was not reached (the "
                    "side's refits spent, or the model fails beyond): the value is the "
                    "furthest profiled. Plot: profile.png.",
                )
            )
        if pr.solves:
            b.append(("p", "Solved fields (each trial: the target met exactly; rows above):"))
            b.append(
                ("p", "\n".join(f"- {sv.field}: so that {sv.target!r} is met" for sv in pr.solves))
            )
        if pr.tied:
            b.append(("p", "Tied fields (set from the fitted parameters):"))
            b.append(
                (
                    "p",
                    "\n".join(
                        f"- {t.field} = {t.text} = {getattr(self.joint, t.field):.6g}"
                        for t in pr.tied
                    ),
                )
            )
        if pr.targets:
            b.append(("p", "Targets (SI units; residual = (model − value)/uncertainty):"))
            b.append(
                (
                    "table",
                    ["target", "value", "uncertainty", "model", "residual", "unit"],
                    [
                        [
                            r["target"],
                            f"{r['value']:.6g}",
                            f"{r['uncertainty']:.3g}",
                            f"{r['model']:.6g}",
                            f"{r['residual']:+.2f}",
                            r["unit"],
                        ]
                        for r in self.target_rows()
                    ],
                )
            )
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
        if self.loo:
            b += loo_blocks(self.loo)
        b += [
            (
                "fig",
                p,
                f"{p}: each target's residual in standard deviations"
                if p == "targets.png"
                else f"{p}: the cost with the others re-optimised, against each parameter "
                "held; the 95 % threshold and both intervals"
                if p == "profile.png"
                else f"{p}: measured and fitted, residuals below",
            )
            for p in plots
        ]
        return b


# ------------------------------------------------------------------- the fit ---
def is_delay(name: str) -> bool:
    """Whether a parameter is a trigger delay (shared, or ``trigger_delay_<trace>``)."""
    return name == DELAY or name.startswith(DELAY + "_")


def servo_unit(name: str, servo: ServoScenario) -> str:
    """The SI unit of a component servo's parameter as a servo sweep reads it
    (`hydroarm.io.components.sweep_dimension`; angular for an angular load)."""
    if is_delay(name):
        return "s"
    if name == "spool_frequency":
        return "rad/s"
    return SI_UNITS[sweep_dimension(name, servo.parameters)] or "1"


def parameter_unit(name: str) -> str:
    """The SI unit of a parameter as fit.csv writes it."""
    return "s" if is_delay(name) else SI_UNITS[FIELD_DIMENSIONS[name]] or "1"


def check_informed(names, J: np.ndarray) -> None:
    """Refuse, before a fit runs, a parameter that no trace or target informs: its column of
    the Jacobian at the start is zero (the residuals do not move with it), so the fit could
    only report its start with an infinite standard error (e.g. ``trigger_delay`` fitted
    from targets alone)."""
    dead = [n for k, n in enumerate(names) if not np.any(J[:, k])]
    if dead:
        raise HydroarmError(
            "fit.parameters",
            f"{', '.join(dead)}: no trace or target informs "
            f"{'it' if len(dead) == 1 else 'them'} (the residuals do not change with "
            f"{'it' if len(dead) == 1 else 'them'} at the start): leave "
            f"{'it' if len(dead) == 1 else 'them'} out or add a trace that depends on "
            f"{'it' if len(dead) == 1 else 'them'}",
        )


def fit(
    source,
    out=None,
    *,
    engine: str = "batch",
    starts: int | None = None,
    leave_one_out: bool | tuple | None = None,
    progress=None,
) -> FitResult:
    """Fit the parameters of a fit problem and write the result.

    Parameters
    ----------
    source : str, pathlib.Path or FitProblem
        A fit file, or a [`FitProblem`][hydroarm.FitProblem] already read.
    out : str or pathlib.Path, optional
        Folder written (the estimate, its intervals, plots and report); None writes nothing.
    engine : str
        ``"batch"``: every trace's run together on the batch engine; ``"serial"``: one
        [`simulate`][hydroarm.simulate] each (the same numbers bit for bit).
    starts : int, optional
        Number of starts [-] (multi-start from Sobol points), in place of the file's
        ``[fit] starts``.
    leave_one_out : bool or tuple of str, optional
        True, or the groups to leave out (default: the problem's): also refit without each
        group of traces or targets in turn and report the prediction of the one left out
        (``result.loo``).
    progress : callable, optional
        ``progress(label)``, called after each start and before each leave-one-out refit
        (`Progress`).

    Returns
    -------
    FitResult
        The estimate, its statistics and every start.
    """
    problem = source if isinstance(source, FitProblem) else read_fit_file(source)
    if out is not None:
        check_output_folder("--out", out)  # before any work
    if starts is not None:
        starts = whole_number("fit.starts", starts, 1, MAX_STARTS, STARTS_WHY)
        problem = dataclasses.replace(problem, starts=starts)
    problem_bounds(problem, problem.start())  # finite bounds for a multi-start: before work
    loo = problem.leave_one_out if leave_one_out is None else leave_one_out
    if loo and (problem.servo is not None or problem.system is not None):  # before work
        what = "a servo's" if problem.servo is not None else "a system's"
        raise HydroarmError("fit.leave_one_out", f"is for a joint's fit, not {what}")
    # the user's problem: every parameter informed (a leave-one-out refit may leave one
    # without its trace, and reports that as it always has)
    result = run_fit(problem, engine=engine, progress=progress, informed=True)
    if loo:
        assert isinstance(result.joint, ServoJoint)
        result.loo = leave_one_out_rows(
            problem,
            result.joint,
            None if loo is True else loo,
            run=lambda p: run_fit(p, engine=engine),
            simulate=simulate_trace,
            progress=progress,
        )
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
    """θ₂, x, p (columns of `hydroarm.batch.traces`) of every joint's model of every
    trace at the trace's times less its delay (``delays[joint, trace]`` [s]; default each
    trace's fixed ``delay``): ``[joint][trace] -> (len(t), 3)``.

    ``engine``: ``"batch"`` runs them all together (`scenario_traces`),
    ``"serial"`` one [`simulate`][hydroarm.simulate] each, interpolated by ``np.interp``; the two
    give the same numbers bit for bit (tests/test_fit.py). A run that cannot be made (a step
    too large for the joint) or that leaves the physical bounds raises its error
    (``strict``), or gets NaN samples. ``check_step``: check the step's stability for every
    run first, as [`simulate`][hydroarm.simulate] does (the fit checks it at the starts and at
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
    trace's times less its delay: ``[servo][trace] -> (len(t), 1)`` (column `SERVO_Q`).

    All servos run together on the batch path
    ([`hydroarm.model.servo.run_servos`][hydroarm.run_servos], each row the single run's), up to the
    last time needed, keeping the file's ``record_every``-th step; the position is linearly
    interpolated between the kept steps. A failing run raises (``strict``) or gets NaN samples.
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


def trace_model_values(samples: np.ndarray, tr: Trace | SystemTrace) -> np.ndarray:
    """The model's values of a trace's fitted columns, in order
    ([`Trace.blocks`][hydroarm.Trace.blocks])."""
    if isinstance(tr, SystemTrace):  # samples: (times, outputs) in the trace's order
        return samples.T.ravel()
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
    # the residual rows' factors: the trace block divided by its estimated noise when targets
    # are fitted beside traces (docs/fit.md, statistics); None: all 1
    row_scale: np.ndarray | None = None
    note: Any = None  # progress(label) within a start (throttled), or None
    best: float = math.inf  # the lowest cost seen

    def __post_init__(self):
        traces = self.problem.traces
        self.measured = np.concatenate(
            [v for tr in traces for _, v, _ in tr.blocks()] or [np.zeros(0)]
        )
        self.weights = np.concatenate(
            [np.full(len(v), tr.weight / sc) for tr in traces for _, v, sc in tr.blocks()]
            or [np.zeros(0)]
        )

    def joint_at(self, z) -> ServoJoint | ServoScenario | Circuit:
        """The model at ``z``: the joint, the component servo's scenario, or the system."""
        values = dict(zip(self.problem.parameters, np.asarray(z) * self.scale, strict=True))
        changes = {k: float(values[k]) for k in self.problem.joint_parameters}
        if self.problem.system is not None:
            return self.problem.system.runner.with_values(changes)
        if self.problem.servo is not None:
            return self.problem.servo.replace(check_stability=False, **changes)
        return apply_ties(self.problem.joint, changes, self.problem.tied)

    def many(self, Z: np.ndarray) -> np.ndarray:
        """Residual vectors (rows) of the scaled parameter vectors ``Z`` (rows), all simulated
        in one run of the engine; the blocks: trace residuals, then the targets' residuals."""
        Z = np.atleast_2d(Z)
        if self.problem.system is not None:  # the runs of every row on the batch engine
            return self._many_system(Z)
        joints: list = [self.joint_at(z) for z in Z]
        if self.problem.solves:  # the solved fields, the points side by side
            joints = solve_fields(joints, self.problem.solves, self.problem.targets)
        delays = np.array([self.problem.delays(z * self.scale) for z in Z])
        traces = self.problem.traces
        self.evaluations += len(Z)
        self.runs += 1
        if traces:
            samples = model_samples(
                joints, traces, self.engine, strict=False, delays=delays, check_step=False
            )
            sim = np.array(
                [
                    np.concatenate(
                        [trace_model_values(s, tr) for s, tr in zip(row, traces, strict=True)]
                    )
                    for row in samples
                ]
            )
            r = (sim - self.measured) * self.weights
            # a joint whose run failed (unstable, out of the physical bounds): a cost far
            # above any fit's, so that the optimiser steps back
            r[~np.all(np.isfinite(r), axis=1)] = PENALTY
        else:
            r = np.zeros((len(Z), 0))
        if self.problem.targets:  # scalar metrics (hydroarm/analysis/targets.py)
            r = np.hstack([r, target_residuals(joints, self.problem.targets, self.problem.met)])
        if self.row_scale is not None:
            r = r * self.row_scale
        return self._keep(Z, r)

    def _keep(self, Z, r: np.ndarray) -> np.ndarray:
        """Cache the residual rows ``r`` of the points ``Z``, say the progress, return r."""
        for z, row in zip(Z, r, strict=True):
            self._cache[np.asarray(z, float).tobytes()] = row
        if self.note is not None:
            self.note(
                f"fit: {self.evaluations} model evaluations, lowest cost so far "
                f"{self.lowest(r):.6g}"
            )
        return r

    def system_values(self, Z) -> np.ndarray:
        """The system's parameter values [SI] (rows, ``joint_parameters``' order) of ``Z``."""
        pr = self.problem
        cols = [pr.parameters.index(k) for k in pr.joint_parameters]
        return (np.atleast_2d(Z) * self.scale)[:, cols]

    def _many_system(self, Z: np.ndarray) -> np.ndarray:
        """`many` of a system (`system_samples`)."""
        pr = self.problem
        assert pr.system is not None
        delays = np.array([pr.delays(z * self.scale) for z in Z])
        self.evaluations += len(Z)
        self.runs += 1
        samples = system_samples(
            pr.system.runner, pr.joint_parameters, self.system_values(Z), pr.traces, delays,
            strict=False,
        )  # fmt: skip
        sim = np.array(
            [
                np.concatenate(
                    [trace_model_values(s, tr) for s, tr in zip(row, pr.traces, strict=True)]
                )
                for row in samples
            ]
        )
        r = (sim - self.measured) * self.weights
        r[~np.all(np.isfinite(r), axis=1)] = PENALTY  # a failed run: the optimiser steps back
        return self._keep(Z, r)

    def lowest(self, r: np.ndarray) -> float:
        """The lowest cost Σr² seen (kept for the progress lines)."""
        c = float(np.min(np.sum(r * r, axis=1))) if len(r) else math.inf
        self.best = min(self.best, c)
        return self.best

    def __call__(self, z) -> np.ndarray:
        key = np.asarray(z, float).tobytes()
        if key not in self._cache:
            if len(self._cache) > CACHE_SIZE:
                self._cache.clear()
            self.many(z)
        return self._cache[key]

    def jacobian(self, z, lo, hi, central: bool = False, free=None) -> np.ndarray:
        """Finite differences of the residuals at ``z``, the perturbed vectors (N forward, or
        2N central) run together; the steps and formulas are scipy's
        ``least_squares(diff_step=DIFF_STEP, jac="2-point" or "3-point")`` (relative step,
        adjusted at a bound), so that the batch and serial fits take the same path.
        ``free`` (a boolean mask): only those parameters' columns (a profile's refit, the
        others held)."""
        z = np.asarray(z, float)
        f0 = self(z)
        Z, derivative = fd_points(z, lo, hi, central, free)
        F = np.array([self._cache[x.tobytes()] for x in Z]) if self._has(Z) else self.many(Z)
        return derivative(f0, F)

    def step_ok(self, z) -> bool:
        """Whether the fixed step is stable for every trace's run at ``z``."""
        j, d = self.joint_at(z), self.problem.delays(np.asarray(z) * self.scale)
        try:
            if isinstance(j, Circuit):  # a failed run is caught by its bounds
                return True
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


def fd_points(z, lo, hi, central: bool, free=None):
    """The perturbed points (rows) of a finite-difference Jacobian at ``z`` and the function
    ``derivative(f0, F)`` that makes the Jacobian (residuals × parameters) of the residuals
    ``f0`` at ``z`` and ``F`` at the points: scipy's ``_dense_difference`` ("2-point":
    (f(z + h) − f0)/h; "3-point": (f(z + h) − f(z − h))/2h, or at a bound one-sided
    (−3f0 + 4f(z + h) − f(z + 2h))/2h). ``free`` (a boolean mask, default all): only those
    parameters' columns (each column's step is its own, so a column is the same either way)."""
    n = len(z)
    cols = np.arange(n) if free is None else np.flatnonzero(free)
    if not central:
        Z = (z + np.diag(fd_steps(z, lo, hi)))[cols]
        dx = Z[np.arange(len(cols)), cols] - z[cols]
        return Z, lambda f0, F: ((F - f0) / dx[:, None]).T
    h, one_sided = central_steps(z, lo, hi)
    h, one_sided = h[cols], one_sided[cols]
    rows, dx = [], np.empty(len(cols))
    for k, i in enumerate(cols):
        a, b = z.copy(), z.copy()
        if one_sided[k]:
            a[i], b[i] = z[i] + h[k], z[i] + 2 * h[k]
            dx[k] = b[i] - z[i]
        else:
            a[i], b[i] = z[i] - h[k], z[i] + h[k]
            dx[k] = b[i] - a[i]
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


def least_squares(fun, z0, jac, lo_z, hi_z, tol: float):
    """The fit's optimiser, one call for the fit, its bootstrap refits and its profile's
    refits: ``scipy.optimize.least_squares`` (trust-region reflective, bounded) on scaled
    parameters ``z`` from ``z0``, the Jacobian ``jac`` (a function, or scipy's "2-point" or
    "3-point" with `DIFF_STEP`), tolerances ``tol`` (docs/fit.md "Optimiser")."""
    from scipy import optimize

    return optimize.least_squares(
        fun, z0, jac=jac, bounds=(lo_z, hi_z), diff_step=DIFF_STEP, x_scale=1.0,
        method="trf", ftol=tol, xtol=tol, gtol=tol,
    )  # fmt: skip


def run_fit(
    problem: FitProblem, engine: str = "batch", progress=None, *, informed: bool = False
) -> FitResult:
    """Fit ``problem`` (docs/fit.md). ``engine``: ``"batch"`` (the Jacobian's perturbed runs
    together on the batch engine) or ``"serial"`` (one simulation per evaluation, scipy's
    forward differences): the same steps and the same estimate. With ``problem.starts`` > 1
    the fit starts from that many scrambled Sobol points inside the bounds
    (`start_points`) and keeps the lowest cost. ``informed``: refuse a parameter that
    no trace or target informs at the first start (`check_informed`)."""
    from scipy import stats

    if engine not in ENGINES:
        raise HydroarmError("engine", f"must be one of {', '.join(ENGINES)}, got {engine!r}")
    if problem.bootstrap and problem.targets:
        raise HydroarmError(
            "fit.bootstrap", "resamples the residuals of traces; a fit with targets has none"
        )
    if "profile" in problem.intervals and problem.targets:
        raise HydroarmError(
            "fit.intervals", '"profile" is for a fit of traces; a fit with targets has none yet'
        )
    if "profile" in problem.intervals:
        check_profile_budget("fit.profile_refits", problem.profile_budget, len(problem.parameters))
    if problem.jacobian not in JACOBIANS:
        raise HydroarmError(
            "fit.jacobian", f"must be one of {', '.join(JACOBIANS)}, got {problem.jacobian!r}"
        )
    names = problem.parameters
    p0 = problem.start()
    scale = np.where(p0 != 0, np.abs(p0), [DELAY_SCALE if is_delay(k) else 1.0 for k in names])
    lo, hi = (np.array(b) for b in zip(*problem_bounds(problem, p0), strict=True))
    lo_z, hi_z = lo / scale, hi / scale
    tick = progress or (lambda label: None)
    model = _Model(problem, scale, engine, note=getattr(progress, "note", None))
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

    targets = problem.targets
    # with targets the cost is known to the stall search's resolution, not to 1e-10
    tol = TARGET_TOL if targets else TRACE_TOL

    def fun(z):
        r = model(z)
        if targets and float(r @ r) < CHI2_FLOOR:
            raise _Converged(np.array(z, float))  # the data met: nothing left to improve
        return r

    def solve(z_start):
        try:
            return least_squares(fun, z_start, jac, lo_z, hi_z, tol)
        except _Converged as met:
            z = met.args[0]
            return SimpleNamespace(x=z, fun=model(z), jac=model.jacobian(z, lo_z, hi_z, central))

    t0 = time.perf_counter()
    sols: list = []
    start_rows: list[dict] = []
    for z0 in starts:
        before = model.evaluations
        if not model.step_ok(z0) or np.all(model(z0) == PENALTY):  # the model fails here
            if len(starts) == 1:  # the run's own error
                d = problem.delays(z0 * scale)[None, :]
                if problem.system is not None:
                    system_samples(
                        problem.system.runner, problem.joint_parameters,
                        model.system_values(z0), problem.traces, d, strict=True,
                    )  # fmt: skip
                else:
                    model_samples([model.joint_at(z0)], problem.traces, engine, delays=d)
            sols.append(None)
            tick(f"start {len(sols)}/{len(starts)}: the model fails there")
            start_rows.append(
                {"start": z0 * scale, "estimate": z0 * scale, "cost": math.inf, "evaluations": 1}
            )
            continue
        if informed and all(s is None for s in sols):  # the first start that runs
            check_informed(names, model.jacobian(z0, lo_z, hi_z, central))  # (cached)
        sol = solve(z0)
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
    m_tr, n = len(model.measured), len(names)
    if problem.traces and targets:  # the traces' noise, then the fit weighted by it
        s_tr = math.sqrt(float(sol.fun[:m_tr] @ sol.fun[:m_tr]) / max(m_tr - n, 1))
        model.row_scale = np.ones(m_tr + len(targets))
        model.row_scale[:m_tr] = 1.0 / max(s_tr, 1e-300)
        model._cache.clear()  # rows cached unweighted
        sol = solve(sol.x)
        elapsed = time.perf_counter() - t0
    row_scale = np.ones(len(sol.fun)) if model.row_scale is None else model.row_scale
    fun_si = np.asarray(sol.fun) / row_scale  # unweighted: trace fractions, target sigmas
    chi2 = float(fun_si[m_tr:] @ fun_si[m_tr:]) if targets else math.nan
    jac_sol = np.asarray(sol.jac)
    sv = np.linalg.svd(jac_sol, compute_uv=False)
    if problem.traces:
        dof = max(m_tr - n, 1)
        s2 = float(fun_si[:m_tr] @ fun_si[:m_tr]) / dof
        tq = float(stats.t.ppf(0.975, dof))
    else:  # stated uncertainties: absolute (no rescaling by the misfit)
        dof = len(targets) - len(problem.solves) - n
        s2 = math.nan
        tq = float(stats.norm.ppf(0.975))
    # with targets the trace rows of the Jacobian are already divided by s
    cov_z = np.linalg.pinv(jac_sol.T @ jac_sol) * (s2 if not targets else 1.0)
    cov = cov_z * np.outer(scale, scale)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    d = np.sqrt(np.clip(np.diag(cov_z), 1e-300, None))
    corr = np.clip(cov_z / np.outer(d, d), -1.0, 1.0)
    if sv[-1] <= 1e-10 * sv[0]:  # rank deficient: no finite standard errors
        se = np.full(n, math.inf)
        cov = np.full_like(cov, math.inf)  # nor for the solved fields (solved_rows)
    est = sol.x * scale
    delays = problem.delays(est)
    joint: Any
    if problem.system is not None:  # the fitted system (its whole run) and its samples
        src = problem.system
        x_sys = model.system_values(sol.x)[0]
        joint = src.with_values(dict(zip(problem.joint_parameters, x_sys, strict=True)))
        fitted: list = system_samples(
            src.runner, problem.joint_parameters, model.system_values(sol.x), problem.traces,
            delays[None, :], strict=True,
        )[0]  # fmt: skip
        fitted_p: list = [None] * len(fitted)
    else:
        joint = problem.joint_at(est) if problem.servo is None else model.joint_at(sol.x)
        samples = (
            model_samples([joint], problem.traces, engine, delays=delays[None, :])[0]
            if problem.traces
            else []
        )
        fitted = [
            column_values(s, tr.column) for s, tr in zip(samples, problem.traces, strict=True)
        ]
        fitted_p = [
            column_values(s, "p_bar") if tr.pressure is not None else None
            for s, tr in zip(samples, problem.traces, strict=True)
        ]
    result = FitResult(
        problem=problem,
        initial=start_rows[best]["start"],
        estimate=est,
        std_error=se,
        ci95_low=est - tq * se,
        ci95_high=est + tq * se,
        correlation=corr,
        singular_values=sv,
        residual_sd=math.sqrt(s2) if problem.traces else math.nan,
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
        target_model=(target_values([joint], targets, problem.met)[0] if targets else np.zeros(0)),
        chi2=chi2,
        chi2_dof=dof if not problem.traces else 0,
        covariance=cov,
        quantile=tq,
    )
    if problem.bootstrap and not targets:
        result.boot, result.boot_failed = bootstrap(
            problem, model, sol, scale, lo_z, hi_z, central, tick
        )
        result.elapsed_s = time.perf_counter() - t0
    # Δ: the cost's rise at the 95 % threshold, t²·s² (traces) or t² (targets' stated
    # sigmas, and the trace rows divided by s when both are fitted)
    result.cost = float(np.asarray(sol.fun) @ np.asarray(sol.fun))
    result.profile_delta = tq**2 * (s2 if not targets else 1.0)
    if "profile" in problem.intervals and not targets:
        run = ProfileRun(
            model=model, least_squares=least_squares, z_hat=np.asarray(sol.x, float),
            cost_min=result.cost, cov_z=cov_z, delta=result.profile_delta, quantile=tq,
            lo_z=lo_z, hi_z=hi_z, scale=scale, central=central, tol=tol, penalty=PENALTY,
            names=names,
        )  # fmt: skip
        model.note = None  # the profile's own progress notes (refits) instead
        result.profiles = profile_intervals(run, problem.profile_budget, tick)
        result.elapsed_s = time.perf_counter() - t0
    result.checks = interval_checks(
        names, jac_sol, est, result.ci95_low, result.ci95_high, (lo, hi),
        starts=start_rows if not (problem.traces and targets) else (),
        delta=result.profile_delta, profiles=result.profiles,
        boot_interval=result.boot_interval if result.boot is not None else None, cov=cov,
        end_q=end_costs(model, sol.x, cov_z, tq, lo_z, hi_z, result.cost, result.profile_delta)
        if result.profiles is None and not targets else None,
    )  # fmt: skip
    result.warnings += result.checks.warnings
    p = result.chi2_p
    if math.isfinite(p) and p < 0.05:
        result.warnings.append(
            f"the targets' χ² is {chi2:.4g} for {dof} degrees of freedom (P = {p:.2g}): the "
            "model does not meet them within their stated uncertainties, so the intervals, "
            "which take those uncertainties as they are, are too narrow (scaled by the misfit "
            f"they would be {math.sqrt(chi2 / dof):.3g} times wider)"
        )
    return result


def end_costs(model, z_hat, cov_z, tq, lo_z, hi_z, cost_min, delta) -> np.ndarray:
    """The cost's rise over Δ at each Jacobian interval's ends as the linear theory places
    them (`linear_ends`), all 2p points in one engine run: the
    curvature check of a fit without a profile (parameter × low/high; NaN where a point
    lies beyond a bound, infinite where the model fails)."""
    out = np.full((len(z_hat), 2), math.nan)
    if not (math.isfinite(delta) and delta > 0):
        return out
    points, where = linear_ends(np.asarray(z_hat, float), cov_z, tq, lo_z, hi_z)
    if not len(points):
        return out
    r = model.many(points)
    for (i, side), row in zip(where, r, strict=True):
        failed = np.all(row == PENALTY) or not np.all(np.isfinite(row))
        out[i, side] = math.inf if failed else (float(row @ row) - cost_min) / delta
    return out


def bootstrap(problem, model, sol, scale, lo_z, hi_z, central, tick) -> tuple[np.ndarray, int]:
    """The residual bootstrap of a trace fit (docs/fit.md "Intervals"): ``problem.bootstrap``
    refits, each from the estimate to the fitted model's values plus the fit's residuals
    resampled with replacement within each measured column (seeded by ``problem.seed``), the
    residuals first divided by √(1 − h) (h: the leverage of the linearised fit, J(JᵀJ)⁻¹Jᵀ)
    and centred (Davison & Hinkley 1997, *Bootstrap methods*, algorithm 6.3). Returns the
    refits' estimates (rows, SI) and how many refits failed (left out)."""
    rng = np.random.default_rng(problem.seed)
    w = model.weights
    fun = np.asarray(sol.fun, float)
    fitted = model.measured + fun / w  # the model's values at the estimate
    J = np.asarray(sol.jac, float)
    h = np.einsum("ij,ij->i", J @ np.linalg.pinv(J.T @ J), J)
    e = -fun / w / np.sqrt(np.clip(1.0 - h, 1e-6, None))
    sizes = [len(v) for tr in problem.traces for _, v, _ in tr.blocks()]
    edges = np.cumsum([0, *sizes])
    blocks = [slice(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    for b in blocks:
        e[b] -= e[b].mean()
    out, failed = [], 0
    for k in range(problem.bootstrap):
        y = fitted.copy()
        for b in blocks:
            y[b] += rng.choice(e[b], size=b.stop - b.start, replace=True)
        m = _Model(problem, scale, model.engine)
        m.measured = y
        jac_mode: Any = "3-point" if central else "2-point"
        if model.engine == "batch":
            jac_mode = lambda z, m=m: m.jacobian(z, lo_z, hi_z, central)  # noqa: E731
        try:
            r = least_squares(m, sol.x, jac_mode, lo_z, hi_z, TRACE_TOL)
            ok = bool(np.all(np.isfinite(r.fun))) and not np.all(r.fun == PENALTY)
        except HydroarmError:
            ok = False
        if ok:
            out.append(r.x * scale)
        else:
            failed += 1
        tick_note = getattr(tick, "note", None)
        if tick_note is not None:
            tick_note(f"bootstrap: {k + 1}/{problem.bootstrap} refits")
    tick(f"bootstrap: {problem.bootstrap} refits, {failed} failed")
    if len(out) < MIN_BOOTSTRAP:
        raise HydroarmError(
            "fit.bootstrap",
            f"only {len(out)} of {problem.bootstrap} refits succeeded (the model fails "
            "near the estimate): no bootstrap interval",
        )
    return np.array(out), failed


def solved_rows(problem: FitProblem, est, cov, joint: ServoJoint, tq: float) -> list[dict]:
    """Rows of [`FitResult.table`][hydroarm.FitResult.table] for the solved fields: the value at the
    estimate; its variance gᵀ·Cov·g + (σ_target/(∂m/∂v))², g = ∂v/∂parameters by forward differences
    of the solve, ∂m/∂v the stall mass's sensitivity (the target's uncertainty moves v)."""
    if not problem.solves:
        return []
    n = len(est)
    h = DIFF_STEP * np.maximum(np.abs(est), 1e-300)
    moved = problem.joints_at([est + h[i] * np.eye(n)[i] for i in range(n)])
    by_name = {tg.name: tg for tg in problem.targets}
    rows = []
    for sv in problem.solves:
        v = getattr(joint, sv.field)
        g = np.array([(getattr(j, sv.field) - v) / h[i] for i, j in enumerate(moved)])
        tg = by_name[sv.target]
        dm = solved_sensitivity(joint, sv, tg.value)
        spread = float(g @ cov @ g) if np.all(np.isfinite(cov)) else math.inf
        var = spread + (tg.uncertainty / dm) ** 2 if dm else math.inf
        se = math.sqrt(max(var, 0.0))
        rows.append(
            {
                "parameter": sv.field,
                "initial": float(getattr(problem.joint, sv.field)),
                "estimate": float(v),
                "std_error": se,
                "ci95_low": float(v - tq * se),
                "ci95_high": float(v + tq * se),
                "unit": SI_UNITS[FIELD_DIMENSIONS[sv.field]] or "1",
            }
        )
    return rows


class _Converged(Exception):
    """Raised by a fit's residuals once the targets are met (`CHI2_FLOOR`)."""


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
    if problem.system is not None:
        return default_bounds(problem.system.runner, key, start)
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
    """Read a fit file; every problem is a one-line error before any simulation.

    Parameters
    ----------
    path : str or pathlib.Path
        The fit file (docs/fit.md).

    Returns
    -------
    FitProblem
        The problem, checked.
    """
    text, path = read_text_file(path)
    return fit_problem_from_doc(parse_toml(text, path.name), path.parent, path.stem)


def fit_problem_from_doc(doc: dict, base_dir: Path = Path("."), name: str = "fit") -> FitProblem:
    if is_system_study(doc):  # any system: [system] file = "…"
        return system_fit_problem(doc, base_dir, name)
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
            base_dir=base_dir,
        )
        known = (*FITTABLE, DELAY)
    section = as_table("fit", doc.get("fit", {}))
    reject_unknown_keys("fit", section, FIT_KEYS)
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
    entries = doc.get("trace", [])
    goals = doc.get("target", [])
    for key, v in (("trace", entries), ("target", goals)):
        if not isinstance(v, list):
            raise HydroarmError(key, f"must be [[{key}]] entries")
    if not entries and not goals:
        raise HydroarmError(
            "trace",
            "is missing (give [[trace]] entries with csv, load, direction or lever, "
            "and/or [[target]] entries with metric, value, uncertainty)",
        )
    targets = tuple(
        read_target(f"target[{i + 1}]", as_table(f"target[{i + 1}]", e), i)
        for i, e in enumerate(goals)
    )
    seen: dict[str, int] = {}
    for i, tg in enumerate(targets):  # a name says which target a report row, a solve is
        if tg.name in seen:
            raise HydroarmError(
                f"target[{i + 1}].name",
                f"{tg.name!r} is the name of target[{seen[tg.name] + 1}] too: give each "
                "target a name of its own",
            )
        seen[tg.name] = i
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
    if traces and sum(sum(len(v) for _, v, _ in t.blocks()) for t in traces) <= len(params):
        raise HydroarmError("trace", "fewer samples than parameters")
    tied: tuple = ()
    solves: tuple = ()
    for key in ("tied", "solve"):
        if servo is not None and key in section:
            raise HydroarmError(f"fit.{key}", "is for a joint's fields, not a component servo")
    if servo is not None and targets:
        raise HydroarmError("target", "targets are a joint's metrics, not a component servo's")
    if servo is None:
        tied = read_ties(as_table("fit.tied", section.get("tied", {})), params, joint)
        solves = read_solves(as_table("fit.solve", section.get("solve", {})), params, tied, targets)
    if not traces and len(targets) - len(solves) < len(params):
        raise HydroarmError(
            "target", "fewer targets (not counting those met by a solved field) than parameters"
        )
    if targets and section.get("bootstrap", 0):
        raise HydroarmError(
            "fit.bootstrap", "resamples the residuals of traces; a fit with targets has none"
        )
    chosen = read_intervals(section, len(params))
    if targets and len(chosen["intervals"]) > 1:
        raise HydroarmError(
            "fit.intervals",
            "bootstrap and profile intervals are for a fit of traces; a fit with targets "
            'has the Jacobian\'s only (intervals = "jacobian")',
        )
    problem = FitProblem(
        joint=joint,
        parameters=tuple(params),
        traces=traces,
        initial=initial,
        bounds=bounds,
        name=text_value("name", doc.get("name", name)),
        starts=whole_number("fit.starts", section.get("starts", 1), 1, MAX_STARTS, STARTS_WHY),
        seed=whole_number("fit.seed", section.get("seed", 0), minimum=0),
        servo=servo,
        jacobian=text_value("fit.jacobian", section.get("jacobian", "forward"), JACOBIANS),
        targets=targets,
        tied=tied,
        solves=solves,
        **chosen,
    )
    problem_bounds(problem, problem.start())  # a multi-start needs finite bounds
    loo = read_leave_one_out(section.get("leave_one_out", False), problem)
    return dataclasses.replace(problem, leave_one_out=loo)


def read_intervals(section: dict, n_parameters: int) -> dict:
    """``[fit] intervals``, ``bootstrap`` and ``profile_refits`` -> the FitProblem's
    ``intervals``, ``bootstrap`` and ``profile_refits`` (docs/fit.md "Which intervals").

    ``intervals``: one of `INTERVAL_KINDS` or a list of them; the
    Jacobian's are always computed. ``bootstrap = N`` alone means ``intervals =
    "bootstrap"`` (N refits); ``intervals`` naming "bootstrap" without N takes
    `DEFAULT_BOOTSTRAP`; N with an ``intervals`` that does not name "bootstrap", and
    ``profile_refits`` without "profile", are refused, as a budget too small to profile
    every parameter."""
    f = "fit.intervals"
    raw = section.get("intervals")
    names = [raw] if isinstance(raw, str) else raw
    if raw is not None and (
        not isinstance(names, list) or not names or not all(isinstance(k, str) for k in names)
    ):
        raise HydroarmError(f, 'must be "jacobian", "bootstrap", "profile" or a list of them')
    for k in names or ():
        if k not in INTERVAL_KINDS:
            raise unknown_name(f, "interval kind", k, INTERVAL_KINDS)
    if names is not None and len(set(names)) != len(names):
        raise HydroarmError(f, "names a kind twice")
    n_boot = read_bootstrap(section)
    if names is None:
        names = ["jacobian", *(["bootstrap"] if n_boot else [])]
    elif n_boot and "bootstrap" not in names:
        raise HydroarmError(
            "fit.bootstrap",
            f'{n_boot} refits asked for, but fit.intervals does not name "bootstrap" (add '
            "it, or leave bootstrap out)",
        )
    elif "bootstrap" in names and not n_boot:
        n_boot = DEFAULT_BOOTSTRAP
    refits = 0
    if "profile_refits" in section:
        if "profile" not in names:
            raise HydroarmError(
                "fit.profile_refits", 'is the profile\'s budget: fit.intervals must name "profile"'
            )
        refits = whole_number("fit.profile_refits", section["profile_refits"], minimum=1)
        check_profile_budget("fit.profile_refits", refits, n_parameters)
    kinds = tuple(k for k in INTERVAL_KINDS if k == "jacobian" or k in names)
    return {"intervals": kinds, "bootstrap": n_boot, "profile_refits": refits}


def read_bootstrap(section: dict) -> int:
    """``[fit] bootstrap``: 0 (none, the default) or the number of refits, in
    [`MIN_BOOTSTRAP`, `MAX_BOOTSTRAP`]."""
    f = "fit.bootstrap"
    n = whole_number(f, section.get("bootstrap", 0), minimum=0)
    if n and not MIN_BOOTSTRAP <= n <= MAX_BOOTSTRAP:
        raise HydroarmError(
            f,
            f"{n} refits: give 0 (none) or {MIN_BOOTSTRAP} to {MAX_BOOTSTRAP} (each refit "
            "is a whole fit; fewer cannot place the 2.5 % and 97.5 % quantiles)",
        )
    return n


def system_fit_problem(doc: dict, base_dir: Path, name: str) -> FitProblem:
    """A fit of any system named by ``[system] file`` (docs/fit.md "Any system"): its
    parameters by a study's names, traces of its named outputs; every problem a one-line
    error before any run."""
    reject_unknown_keys("", doc, SYSTEM_FIT_SECTIONS)
    source = read_system(doc, base_dir)
    runner = source.runner
    section = as_table("fit", doc.get("fit", {}))
    reject_unknown_keys("fit", section, SYSTEM_FIT_KEYS)
    require_keys("fit", section, ("parameters",))
    raw = section["parameters"]
    if not isinstance(raw, list) or not raw:
        raise HydroarmError("fit.parameters", "must be a non-empty list of parameter names")

    def key_of(field: str, k) -> str:
        if not isinstance(k, str):
            raise HydroarmError(field, f"must be a parameter name, got {k!r}")
        if is_delay(k):
            return k
        key = runner.key(field, k)
        if runner.rule(key) == "integer":
            raise HydroarmError(field, f"{k}: a whole number or a choice, not fitted")
        return key

    params = [key_of("fit.parameters", k) for k in raw]
    if any(is_delay(k) and k != DELAY for k in params):
        raise HydroarmError("fit.parameters", 'a trace\'s own delay is given by delay = "fit"')
    if len(set(params)) != len(params):
        raise HydroarmError("fit.parameters", "names a parameter twice")
    entries = doc.get("trace", [])
    if not isinstance(entries, list) or not entries:
        raise HydroarmError(
            "trace", "is missing (give [[trace]] entries with csv and columns of outputs)"
        )
    traces = tuple(
        read_system_trace(f"trace[{i + 1}]", as_table(f"trace[{i + 1}]", e), base_dir, runner,
                          trace_delay)
        for i, e in enumerate(entries)
    )  # fmt: skip
    source = cut_to(source, traces)
    params += [f"{DELAY}_{i + 1}" for i, tr in enumerate(traces) if tr.fit_delay]
    keys = set(params) | ({DELAY} if any(is_delay(k) for k in params) else set())

    def value(field: str, k: str, v) -> float:
        return quantity(field, v, "time") if is_delay(k) else runner.value(field, k, v)

    initial: dict[str, float] = {}
    for k, v in as_table("fit.initial", section.get("initial", {})).items():
        f = f"fit.initial.{k}"
        kk = key_of(f, k)
        if kk not in keys:
            raise HydroarmError(f, "is not one of fit.parameters")
        initial[kk] = value(f, kk, v)
    for k in params:
        if is_delay(k) and k not in initial:
            initial[k] = initial.get(DELAY, 0.0)
    bounds: dict[str, tuple[float, float]] = {}
    for k, v in as_table("fit.bounds", section.get("bounds", {})).items():
        f = f"fit.bounds.{k}"
        kk = key_of(f, k)
        if kk not in keys:
            raise HydroarmError(f, "is not one of fit.parameters")
        if not isinstance(v, list) or len(v) != 2:
            raise HydroarmError(f, "must be [low, high] with units")
        low, high = (value(f, kk, x) for x in v)
        if not low < high:
            raise HydroarmError(f, "low must be below high")
        for k2 in [kk] if kk in params else [x for x in params if is_delay(x)]:
            start = initial.get(k2, 0.0 if is_delay(k2) else runner.current(k2))
            if not low <= start <= high:
                raise HydroarmError(f, "does not contain the initial value")
        bounds[kk] = (low, high)
    if sum(sum(len(v) for _, v, _ in t.blocks()) for t in traces) <= len(params):
        raise HydroarmError("trace", "fewer samples than parameters")
    problem = FitProblem(
        joint=parameter_set("paper-calibrated"),  # unused
        parameters=tuple(params),
        traces=traces,  # type: ignore[arg-type]
        initial=initial,
        bounds=bounds,
        name=text_value("name", doc.get("name", name)),
        starts=whole_number("fit.starts", section.get("starts", 1), 1, MAX_STARTS, STARTS_WHY),
        seed=whole_number("fit.seed", section.get("seed", 0), minimum=0),
        jacobian=text_value("fit.jacobian", section.get("jacobian", "forward"), JACOBIANS),
        system=source,
        **read_intervals(section, len(params)),
    )
    problem_bounds(problem, problem.start())  # a multi-start needs finite bounds
    return problem


def read_leave_one_out(raw, problem: FitProblem) -> bool | tuple:
    """``[fit] leave_one_out``: true (every group that holds no target met by a solved
    field), false, or a list of group names."""
    f = "fit.leave_one_out"
    if raw is not False and problem.servo is not None:
        raise HydroarmError(f, "is for a joint's fit, not a component servo's")
    groups = loo_groups(problem)
    if isinstance(raw, bool):
        if raw and len(groups) < 2:
            raise HydroarmError(f, "needs at least two groups of traces or targets")
        return raw
    if not isinstance(raw, list) or not raw:
        raise HydroarmError(f, "must be true, false or a list of group names")
    for g in raw:
        if not isinstance(g, str) or g not in groups:
            raise unknown_name(f, "group (one without a target met by a solved field)", g, groups)
    return tuple(raw)


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
    path = checked_path(field_csv, text_value(field_csv, table["csv"]), base_dir)
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
    check_trace(section, path.name, t, delay)
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
        group=text_value(f"{section}.group", table.get("group", name)),
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
    path = checked_path(field_csv, text_value(field_csv, table["csv"]), base_dir)
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
    check_trace(section, path.name, t, delay)
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
    `hydroarm.core.servo.PARAMETERS`: set them in the file's sections (docs/fit.md)."""
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
    if joint.name in parameter_set_names():
        # the fields left unset (None: no stops, stiction equal to Coulomb friction …) are
        # those of the set the fit started from, whichever command reads the file
        lines.append(f'parameter_set = "{joint.name}"')
    for k, v in joint.as_dict().items():
        if v is None or k == "name":
            continue
        if isinstance(v, str):
            lines.append(f'{k} = "{v}"')
            continue
        unit = SI_UNITS[FIELD_DIMENSIONS[k]]
        lines.append(f'{k} = "{v!r} {unit}"' if unit else f"{k} = {v!r}")
    return "\n".join(lines) + "\n"


TARGET_COLUMNS = ["target", "metric", "group", "value", "uncertainty", "model", "residual", "unit"]
LOO_COLUMNS = [
    "group",
    "item",
    "kind",
    "measured",
    "fitted",
    "predicted",
    "fit_error",
    "prediction_error",
    "prediction_z",
    "unit",
]


def rows_csv(columns, rows) -> str:
    """CSV text of ``rows`` (numbers to 9 significant figures)."""

    def cell(v):
        return f"{v:.9g}" if isinstance(v, float) else str(v)

    lines = [",".join(columns)] + [",".join(cell(r[c]) for c in columns) for r in rows]
    return "\n".join(lines) + "\n"


def loo_blocks(rows) -> list:
    """The leave-one-out table of a fit report (SI units; a trace: RMS error)."""
    table = []
    for r in rows:
        z = "" if math.isnan(r["prediction_z"]) else f"{r['prediction_z']:+.2f}"
        meas = "" if math.isnan(r["measured"]) else f"{r['measured']:.6g}"
        table.append(
            [
                r["group"],
                r["item"],
                meas,
                f"{r['fit_error']:+.4g}",
                f"{r['prediction_error']:+.4g}",
                z,
                r["unit"],
            ]
        )
    return [
        (
            "p",
            "Leave one out: each group refitted without, then predicted "
            "(error = model − measured; a trace: RMS error):",
        ),
        (
            "table",
            [
                "left out",
                "item",
                "measured",
                "fit error",
                "prediction error",
                "prediction / σ",
                "unit",
            ],
            table,
        ),
    ]
