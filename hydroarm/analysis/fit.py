"""Fit a joint's parameters to measured saturation-test traces and scalar targets (issue 16).

A fit file names a starting joint (``[joint]``, as in scenario files), the free parameters
(``[fit]``, with ``[fit.tied]`` fields that follow from them) and the data: measured traces
(``[[trace]]``: CSV files with ``t_s`` and ``x_mm`` or ``theta_deg``, as ``hydroarm simulate
--out`` writes them, each with its load and the direction of the saturation test that
produced it) and/or scalar targets (``[[target]]``, :mod:`hydroarm.analysis.targets`).
:func:`fit` runs a bounded least-squares fit and reports the estimates with standard errors,
95 % intervals, the correlation matrix and the singular values of the scaled Jacobian, and
names parameter pairs the data cannot separate. The statistics and their assumptions are in
docs/fit.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..errors import HydroarmError
from ..files import atomic_write_text
from ..io.catalog import paper_load
from ..io.schema import parse_load
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
)
from ..io.units import SI_UNITS
from ..model.joint import Load, ServoJoint
from ..model.rules import FIELD_RULES, NONNEGATIVE, POSITIVE
from ..model.scenario import default_duration, saturation_test, simulate
from ..plotting.fit import fit_targets_figure, fit_trace_figure
from ..plotting.joint import save_figure
from .targets import (
    Target,
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
TRACE_KEYS = {"csv", "load", "direction", "window", "weight", "name", "group"}
FIT_KEYS = {"parameters", "bounds", "initial", "tied", "solve", "leave_one_out"}
TARGET_TOL = 1e-6  # least_squares' ftol, xtol, gtol when there are targets (docs/fit.md)
# a fit with targets stops once Σ residual² is below this (targets met to 1 % of their
# uncertainty, as when there are as many targets as parameters)
CHI2_FLOOR = 1e-4
JAC_STEP = 1e-4  # relative forward-difference step of the Jacobian (scaled parameters)
MIN_SAMPLES = 3
CORRELATION_LIMIT = 0.95
# the measured quantity of each column: (simulated accessor, SI -> column unit)
COLUMNS = {"x_mm": ("x", 1e3), "theta_deg": ("theta", 180.0 / math.pi)}


@dataclass(frozen=True)
class Trace:
    """One measured saturation test: samples ``values`` of ``column`` at times ``t``."""

    t: np.ndarray
    values: np.ndarray
    column: str
    load: Load
    direction: str
    weight: float = 1.0
    name: str = "trace"
    group: str = ""  # leave-one-out group ("": the trace's name)

    def __post_init__(self):
        if not self.group:
            object.__setattr__(self, "group", self.name)

    @property
    def scale(self) -> float:
        """Residual scale: the trace's range (so every trace counts in relative terms)."""
        return max(float(np.ptp(self.values)), 1e-12)


@dataclass(frozen=True)
class FitProblem:
    """A starting joint, the parameters to fit (with initial values and bounds), traces and
    targets; ``tied``: fields set from the parameters (:class:`~.targets.Tie`);
    ``leave_one_out``: False, True (every group) or the groups to leave out in turn."""

    joint: ServoJoint
    parameters: tuple[str, ...]
    traces: tuple[Trace, ...] = ()
    initial: dict = field(default_factory=dict)
    bounds: dict = field(default_factory=dict)
    name: str = "fit"
    targets: tuple[Target, ...] = ()
    tied: tuple = ()
    leave_one_out: bool | tuple = False
    solves: tuple = ()  # fields solved for a stall target (:class:`~.targets.Solve`)

    def start(self) -> np.ndarray:
        return np.array([self.initial.get(k, getattr(self.joint, k)) for k in self.parameters])

    def joint_at(self, values) -> ServoJoint:
        """The joint with the parameters at ``values`` (SI), the tied and solved fields."""
        return self.joints_at([values])[0]

    def joints_at(self, points) -> list[ServoJoint]:
        """:meth:`joint_at` of several points (the solved fields searched side by side)."""
        joints = [
            apply_ties(
                self.joint, dict(zip(self.parameters, map(float, v), strict=True)), self.tied
            )
            for v in points
        ]
        return solve_fields(joints, self.solves, self.targets)

    @property
    def met(self) -> tuple[str, ...]:
        """Names of the targets met by a solved field."""
        return tuple(sv.target for sv in self.solves)


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
    joint: ServoJoint
    fitted: list = field(default_factory=list)  # simulated values at the measured times
    warnings: list = field(default_factory=list)
    target_model: np.ndarray = field(default_factory=lambda: np.zeros(0))  # SI, per target
    chi2: float = math.nan  # Σ of the squared target residuals
    chi2_dof: int = 0  # targets − solved fields − parameters (targets only); 0 with traces
    loo: list = field(default_factory=list)  # leave_one_out rows
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # SI
    quantile: float = 1.96  # of the 95 % intervals (t or normal)
    _solved: list | None = None

    @property
    def solved(self) -> list[dict]:
        """Rows of :meth:`table` for the solved fields, their standard errors propagated
        (computed when first asked for: a few more stall searches)."""
        if self._solved is None:
            self._solved = solved_rows(
                self.problem, self.estimate, self.covariance, self.joint, self.quantile
            )
        return self._solved

    @property
    def chi2_p(self) -> float:
        """P(χ² ≥ the one seen) for ``chi2_dof`` degrees of freedom (NaN without)."""
        from scipy import stats

        if self.chi2_dof <= 0 or not math.isfinite(self.chi2):
            return math.nan
        return float(stats.chi2.sf(self.chi2, self.chi2_dof))

    @property
    def parameters(self) -> tuple[str, ...]:
        return self.problem.parameters

    def units(self) -> list[str]:
        return [SI_UNITS[FIELD_DIMENSIONS[k]] or "1" for k in self.parameters]

    def table(self) -> list[dict]:
        """One row per fitted parameter, then one per solved field (SI units)."""
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
        ] + list(self.solved)

    def write(self, out) -> Path:
        """Write fit.csv, fitted.toml, one PNG per trace and fit_report.md into ``out``."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        rows = self.table()
        head = "parameter,initial,estimate,std_error,ci95_low,ci95_high,unit"
        lines = [head] + [
            ",".join(
                [r["parameter"]]
                + [f"{r[c]:.9g}" for c in ("initial", "estimate", "std_error")]
                + [f"{r[c]:.9g}" for c in ("ci95_low", "ci95_high")]
                + [r["unit"]]
            )
            for r in rows
        ]
        atomic_write_text(out / "fit.csv", "\n".join(lines) + "\n")
        atomic_write_text(out / "fitted.toml", fitted_toml(self.joint, self.problem.name))
        if self.problem.targets:
            atomic_write_text(out / "targets.csv", rows_csv(TARGET_COLUMNS, self.target_rows()))
        if self.loo:
            atomic_write_text(out / "leave_one_out.csv", rows_csv(LOO_COLUMNS, self.loo))
        plots = [self._plot(out, i) for i in range(len(self.problem.traces))]
        if self.problem.targets:
            plots.append(self._targets_plot(out))
        atomic_write_text(out / "fit_report.md", self.report(plots))
        return out

    def _plot(self, out: Path, i: int) -> str:
        tr = self.problem.traces[i]
        fig = fit_trace_figure(tr.t, tr.values, self.fitted[i], tr.column, title=tr.name)
        name = f"trace{i + 1}.png"
        save_figure(fig, out / name)
        return name

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

    def report(self, plots=()) -> str:
        names = self.parameters
        pr = self.problem
        data = []
        if pr.traces:
            data.append(
                f"{len(pr.traces)} traces, {sum(len(t.t) for t in pr.traces)} samples "
                f"(residual standard deviation {self.residual_sd:.4g} of each trace's range)"
            )
        if pr.targets:
            data.append(
                f"{len(pr.targets)} targets (χ² = {self.chi2:.4g}"
                + (
                    f" for {self.chi2_dof} degrees of freedom, P(≥) = {self.chi2_p:.3g})"
                    if self.chi2_dof > 0
                    else ")"
                )
            )
        lines = [
            f"# Fit: {pr.name}",
            "",
            f"{'; '.join(data)}; {len(names)} parameters, {self.dof} degrees of freedom; "
            f"{self.evaluations} model evaluations in {self.elapsed_s:.2f} s.",
            "",
            "| parameter | initial | estimate | std error | 95 % interval | unit |",
            "|---|---|---|---|---|---|",
        ]
        for r in self.table():
            lines.append(
                f"| {r['parameter']} | {r['initial']:.5g} | {r['estimate']:.5g} | "
                f"{r['std_error']:.3g} | {r['ci95_low']:.5g} … {r['ci95_high']:.5g} | "
                f"{r['unit']} |"
            )
        lines += ["", "Correlation matrix:", "", "| | " + " | ".join(names) + " |"]
        lines.append("|---" * (len(names) + 1) + "|")
        for i, k in enumerate(names):
            lines.append(f"| {k} | " + " | ".join(f"{c:+.3f}" for c in self.correlation[i]) + " |")
        sv = ", ".join(f"{s:.4g}" for s in self.singular_values)
        lines += ["", f"Singular values of the scaled Jacobian: {sv}", ""]
        if pr.solves:
            lines += ["Solved fields (each trial: the target met exactly; rows above):", ""]
            lines += [f"- {sv.field}: so that the target {sv.target!r} is met" for sv in pr.solves]
            lines += [""]
        if pr.tied:
            lines += ["Tied fields (set from the fitted parameters):", ""]
            lines += [
                f"- {t.field} = {t.text} = {getattr(self.joint, t.field):.6g}" for t in pr.tied
            ]
            lines += [""]
        if pr.targets:
            lines += [
                "Targets (SI units; residual = (model − value)/uncertainty):",
                "",
                "| target | value | uncertainty | model | residual | unit |",
                "|---|---|---|---|---|---|",
            ]
            lines += [
                f"| {r['target']} | {r['value']:.6g} | {r['uncertainty']:.3g} | "
                f"{r['model']:.6g} | {r['residual']:+.2f} | {r['unit']} |"
                for r in self.target_rows()
            ]
            lines += [""]
        lines += [f"**Warning:** {w}" for w in self.warnings] or ["No identifiability warning."]
        if self.loo:
            lines += ["", *loo_markdown(self.loo)]
        lines += [""] + [f"![{p}]({p})" for p in plots]
        return "\n".join(lines) + "\n"


# ------------------------------------------------------------------- the fit ---
def fit(source, out=None, *, leave_one_out: bool | tuple | None = None, progress=None) -> FitResult:
    """Fit the parameters of a fit file (path) or :class:`FitProblem`; write into ``out``.

    ``leave_one_out`` (default: the problem's): True, or the groups to leave out: also refit
    without each group of traces or targets in turn and report the prediction of the one
    left out (``result.loo``). ``progress``: called with a label before each stage."""
    tick = progress or (lambda label: None)
    problem = source if isinstance(source, FitProblem) else read_fit_file(source)
    loo = problem.leave_one_out if leave_one_out is None else leave_one_out
    tick(f"fit: {problem.name}")
    result = run_fit(problem)
    if loo:
        groups = None if loo is True else loo
        result.loo = leave_one_out_rows(
            problem, result.joint, groups, run=run_fit, simulate=simulate_trace, progress=tick
        )
    if out is not None:
        tick(f"writing {out}")
        result.write(out)
    return result


def simulate_trace(joint: ServoJoint, tr: Trace) -> np.ndarray:
    """The model's value of ``tr.column`` at the trace's times (same saturation test)."""
    sc = saturation_test(joint, tr.load, tr.direction)
    need = float(tr.t[-1]) + 10 * sc.step
    if sc.duration < need:
        sc = sc.replace(duration=round(max(need, default_duration(joint, 0.0)), 6))
    res = simulate(sc)
    attr, factor = COLUMNS[tr.column]
    return np.interp(tr.t, res.t, getattr(res, attr) * factor)


def run_fit(problem: FitProblem) -> FitResult:
    from scipy import optimize, stats

    names = problem.parameters
    p0 = problem.start()
    scale = np.where(p0 != 0, np.abs(p0), 1.0)
    lo, hi = zip(*(bounds_of(problem, k, p0[i]) for i, k in enumerate(names)), strict=True)
    lo_z, hi_z = np.array(lo) / scale, np.array(hi) / scale
    z0 = np.clip(p0 / scale, lo_z, hi_z)
    traces, targets = problem.traces, problem.targets
    measured = np.concatenate([tr.values for tr in traces] or [np.zeros(0)])
    weights = np.concatenate(
        [np.full(len(tr.t), tr.weight / tr.scale) for tr in traces] or [np.zeros(0)]
    )
    m_tr, n = len(measured), len(names)
    count = [0]
    # rows of the trace block are divided by the traces' estimated s when targets are
    # fitted beside them (docs/fit.md, statistics)
    row_scale = np.ones(m_tr + len(targets))

    def joint_at(z) -> ServoJoint:
        return problem.joint_at(z * scale)

    def residuals_many(zs) -> np.ndarray:
        """Residual rows of several parameter points: traces one by one, targets in one
        batch (:func:`~hydroarm.analysis.targets.target_residuals`)."""
        count[0] += len(zs)
        joints = problem.joints_at([z * scale for z in zs])
        parts = []
        if traces:
            parts.append(
                np.array(
                    [
                        (np.concatenate([simulate_trace(j, tr) for tr in traces]) - measured)
                        * weights
                        for j in joints
                    ]
                )
            )
        if targets:
            parts.append(target_residuals(joints, targets, problem.met))
        return np.hstack(parts) * row_scale

    last: list = [None, None]  # the last point evaluated and its residuals

    def residuals(z):
        last[:] = [np.array(z), residuals_many([z])[0]]
        if targets and float(last[1] @ last[1]) < CHI2_FLOOR:
            raise _Converged  # the data are met exactly: nothing left to improve
        return last[1]

    def jacobian(z):
        """Forward differences, the perturbed points evaluated together (the point itself
        is the one ``residuals`` has just evaluated)."""
        h = JAC_STEP * np.maximum(1.0, np.abs(z))
        h = np.where(z + h > hi_z, -h, h)
        zs = [z + h[i] * np.eye(n)[i] for i in range(n)]
        if last[0] is None or not np.array_equal(last[0], z):
            residuals(z)
        r = residuals_many(zs)
        return ((r - last[1]) / h[:, None]).T

    # with targets the cost is known to its stall search's resolution, not to 1e-10
    tol = TARGET_TOL if targets else 1e-10

    def solve(z_start):
        return optimize.least_squares(
            residuals,
            z_start,
            jac=jacobian if targets else "2-point",
            bounds=(lo_z, hi_z),
            diff_step=JAC_STEP,
            x_scale=1.0,
            method="trf",
            ftol=tol,
            xtol=tol,
            gtol=tol,
        )

    def solve_or_met(z_start):
        try:
            return solve(z_start)
        except _Converged:
            z = last[0]
            return SimpleNamespace(x=z, fun=last[1], jac=jacobian(z))

    t0 = time.perf_counter()
    sol = solve_or_met(z0)
    if traces and targets:  # the traces' noise, then the fit weighted by it
        s_tr = math.sqrt(float(sol.fun[:m_tr] @ sol.fun[:m_tr]) / max(m_tr - n, 1))
        row_scale[:m_tr] = 1.0 / max(s_tr, 1e-300)
        sol = solve_or_met(sol.x)
    elapsed = time.perf_counter() - t0
    fun = np.asarray(sol.fun) / row_scale  # unscaled: trace fractions, target sigmas
    jac = np.asarray(sol.jac)
    sv = np.linalg.svd(jac, compute_uv=False)
    chi2 = float(fun[m_tr:] @ fun[m_tr:]) if targets else math.nan
    if traces:
        dof = max(m_tr - n, 1)
        s2 = float(fun[:m_tr] @ fun[:m_tr]) / dof
        tq = float(stats.t.ppf(0.975, dof))
    else:  # stated uncertainties: absolute (no rescaling by the misfit)
        dof = len(targets) - len(problem.solves) - n
        s2 = math.nan
        tq = float(stats.norm.ppf(0.975))
    # the trace rows of jac are already divided by s when there are targets
    cov_z = np.linalg.pinv(jac.T @ jac) * (s2 if traces and not targets else 1.0)
    cov = cov_z * np.outer(scale, scale)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if sv[-1] <= 1e-10 * sv[0]:  # rank deficient: no finite standard errors
        se = np.full(n, math.inf)
    d = np.sqrt(np.clip(np.diag(cov_z), 1e-300, None))
    corr = np.clip(cov_z / np.outer(d, d), -1.0, 1.0)
    est = sol.x * scale
    joint = joint_at(sol.x)
    fitted = [simulate_trace(joint, tr) for tr in traces]
    model = target_values([joint], targets, problem.met)[0] if targets else np.zeros(0)
    result = FitResult(
        problem=problem,
        initial=p0,
        estimate=est,
        std_error=se,
        ci95_low=est - tq * se,
        ci95_high=est + tq * se,
        correlation=corr,
        singular_values=sv,
        residual_sd=math.sqrt(s2) if traces else math.nan,
        dof=dof,
        evaluations=count[0],
        elapsed_s=elapsed,
        joint=joint,
        fitted=fitted,
        warnings=identifiability_warnings(names, corr, sv),
        target_model=model,
        chi2=chi2,
        chi2_dof=dof if not traces else 0,
        covariance=cov,
        quantile=tq,
    )
    p = result.chi2_p
    if math.isfinite(p) and p < 0.05:
        result.warnings.append(
            f"the targets' χ² is {chi2:.4g} for {dof} degrees of freedom (P = {p:.2g}): the "
            "model does not meet them within their stated uncertainties, so the intervals, "
            "which take those uncertainties as they are, are too narrow (scaled by the misfit "
            f"they would be {math.sqrt(chi2 / dof):.3g} times wider)"
        )
    return result


def solved_rows(problem: FitProblem, est, cov, joint: ServoJoint, tq: float) -> list[dict]:
    """Rows of :meth:`FitResult.table` for the solved fields: the value at the estimate; its
    variance gᵀ·Cov·g + (σ_target/(∂m/∂v))², g = ∂v/∂parameters by forward differences of
    the solve, ∂m/∂v the stall mass's sensitivity (the target's uncertainty moves v)."""
    if not problem.solves:
        return []
    n = len(est)
    h = JAC_STEP * np.maximum(np.abs(est), 1e-300)
    moved = problem.joints_at([est + h[i] * np.eye(n)[i] for i in range(n)])
    by_name = {tg.name: tg for tg in problem.targets}
    rows = []
    for sv in problem.solves:
        v = getattr(joint, sv.field)
        g = np.array([(getattr(j, sv.field) - v) / h[i] for i, j in enumerate(moved)])
        tg = by_name[sv.target]
        dm = solved_sensitivity(joint, sv, tg.value)
        var = float(g @ cov @ g) + (tg.uncertainty / dm) ** 2 if dm else math.inf
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
    """Raised by a fit's residuals once the targets are met (:data:`CHI2_FLOOR`)."""


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
    reject_unknown_keys("", doc, FIT_SECTIONS)
    joint = joint_from_table(
        "joint",
        optional_table(doc, "joint"),
        default_set="paper-calibrated",
        physics=optional_table(doc, "physics"),
    )
    section = as_table("fit", doc.get("fit", {}))
    reject_unknown_keys("fit", section, FIT_KEYS)
    require_keys("fit", section, ("parameters",))
    params = section["parameters"]
    if not isinstance(params, list) or not params:
        raise HydroarmError("fit.parameters", "must be a non-empty list of joint field names")
    for k in params:
        if not isinstance(k, str) or k not in FITTABLE:
            raise unknown_name("fit.parameters", "joint parameter", k, FITTABLE)
    if len(set(params)) != len(params):
        raise HydroarmError("fit.parameters", "names a parameter twice")
    initial = {}
    for k, v in as_table("fit.initial", section.get("initial", {})).items():
        if k not in params:
            raise HydroarmError(f"fit.initial.{k}", "is not one of fit.parameters")
        initial[k] = field_value(f"fit.initial.{k}", k, v)
    for k in params:
        if k not in initial and getattr(joint, k) is None:
            raise HydroarmError(f"fit.initial.{k}", "is missing (the joint has no value)")
    bounds = {}
    for k, v in as_table("fit.bounds", section.get("bounds", {})).items():
        f = f"fit.bounds.{k}"
        if k not in params:
            raise HydroarmError(f, "is not one of fit.parameters")
        if not isinstance(v, list) or len(v) != 2:
            raise HydroarmError(f, "must be [low, high] with units")
        low, high = (field_value(f, k, x) for x in v)
        if not low < high:
            raise HydroarmError(f, "low must be below high")
        start = initial.get(k, getattr(joint, k))
        if not low <= start <= high:
            raise HydroarmError(f, "does not contain the initial value")
        bounds[k] = (low, high)
    tied = read_ties(as_table("fit.tied", section.get("tied", {})), params, joint)
    entries = doc.get("trace", [])
    goals = doc.get("target", [])
    for key, v in (("trace", entries), ("target", goals)):
        if not isinstance(v, list):
            raise HydroarmError(key, f"must be [[{key}]] entries")
    if not entries and not goals:
        raise HydroarmError(
            "trace",
            "is missing (give [[trace]] entries with csv, load, direction, "
            "and/or [[target]] entries with metric, value, uncertainty)",
        )
    traces = tuple(
        read_trace(f"trace[{i + 1}]", as_table(f"trace[{i + 1}]", e), base_dir)
        for i, e in enumerate(entries)
    )
    targets = tuple(
        read_target(f"target[{i + 1}]", as_table(f"target[{i + 1}]", e), i)
        for i, e in enumerate(goals)
    )
    if traces and sum(len(t.t) for t in traces) <= len(params):
        raise HydroarmError("trace", "fewer samples than parameters")
    if not traces and len(targets) < len(params):
        raise HydroarmError("target", f"fewer targets ({len(targets)}) than parameters")
    solves = read_solves(as_table("fit.solve", section.get("solve", {})), params, tied, targets)
    if not traces and len(targets) - len(solves) < len(params):
        raise HydroarmError(
            "target", "fewer targets (not counting those met by a solved field) than parameters"
        )
    problem = FitProblem(
        joint=joint,
        parameters=tuple(params),
        traces=traces,
        initial=initial,
        bounds=bounds,
        name=text_value("name", doc.get("name", name)),
        targets=targets,
        tied=tied,
        solves=solves,
    )
    loo = read_leave_one_out(section.get("leave_one_out", False), problem)
    return replace(problem, leave_one_out=loo)


def read_leave_one_out(raw, problem: FitProblem) -> bool | tuple:
    """``[fit] leave_one_out``: true (every group that holds no target met by a solved
    field), false, or a list of group names."""
    f = "fit.leave_one_out"
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


def read_trace(section: str, table: dict, base_dir: Path) -> Trace:
    reject_unknown_keys(section, table, TRACE_KEYS)
    require_keys(section, table, ("csv", "load", "direction"))
    direction = text_value(f"{section}.direction", table["direction"], ("raise", "lower"))
    raw = table["load"]
    load = (
        parse_load(f"{section}.load", raw)
        if isinstance(raw, dict)
        else paper_load(raw, field=f"{section}.load")
    )
    weight = 1.0
    if "weight" in table:
        weight = table["weight"]
        if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not weight > 0:
            raise HydroarmError(f"{section}.weight", f"must be a positive number, got {weight!r}")
        if not math.isfinite(weight):
            raise HydroarmError(f"{section}.weight", "must be finite")
    field_csv = f"{section}.csv"
    path = (base_dir / text_value(field_csv, table["csv"])).resolve()
    if not path.is_file():
        raise HydroarmError(field_csv, f"{path.name}: no such file")
    header = read_csv_columns(field_csv, path)
    column = next((c for c in COLUMNS if c in header), None)
    if "t_s" not in header or column is None:
        raise HydroarmError(
            field_csv,
            f"{path.name} needs the columns t_s and x_mm or theta_deg "
            f"(columns: {', '.join(header)})",
        )
    t, v = header["t_s"], header[column]
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise HydroarmError(field_csv, f"{path.name}: times must be finite and increasing")
    if not np.all(np.isfinite(v)):
        raise HydroarmError(field_csv, f"{path.name}: values must be finite")
    if "window" in table:
        w = table["window"]
        if not isinstance(w, list) or len(w) != 2:
            raise HydroarmError(f"{section}.window", 'must be [start, end], e.g. ["0 s", "1 s"]')
        a, b = (time_value(f"{section}.window", x) for x in w)
        if not a < b:
            raise HydroarmError(f"{section}.window", "start must be before end")
        keep = (t >= a) & (t <= b)
        t, v = t[keep], v[keep]
    if len(t) < MIN_SAMPLES:
        raise HydroarmError(
            field_csv, f"{path.name}: fewer than {MIN_SAMPLES} samples (in the window)"
        )
    if t[0] < 0:
        raise HydroarmError(field_csv, f"{path.name}: times before 0 s (the step is at 0 s)")
    if np.ptp(v) == 0:
        raise HydroarmError(field_csv, f"{path.name}: {column} does not change")
    name = text_value(f"{section}.name", table.get("name", f"{path.stem}"))
    group = text_value(f"{section}.group", table.get("group", name))
    return Trace(
        t=t,
        values=v,
        column=column,
        load=load,
        direction=direction,
        weight=weight,
        name=name,
        group=group,
    )


def fitted_toml(joint: ServoJoint, name: str = "fit") -> str:
    """A ``[joint]`` table with every field of ``joint`` (SI, with units)."""
    lines = [f"# fitted by hydroarm fit ({name}); load as a scenario's [joint]", "[joint]"]
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


def loo_markdown(rows) -> list[str]:
    """The leave-one-out table of a fit report (SI units; a trace: RMS error)."""
    out = [
        "Leave one out: each group refitted without, then predicted "
        "(error = model − measured; a trace: RMS error):",
        "",
        "| left out | item | measured | fit error | prediction error | prediction / σ | unit |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        z = "" if math.isnan(r["prediction_z"]) else f"{r['prediction_z']:+.2f}"
        meas = "" if math.isnan(r["measured"]) else f"{r['measured']:.6g}"
        out.append(
            f"| {r['group']} | {r['item']} | {meas} | {r['fit_error']:+.4g} | "
            f"{r['prediction_error']:+.4g} | {z} | {r['unit']} |"
        )
    return out
