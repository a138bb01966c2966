"""Honest fit intervals (issue 29; docs/fit.md "Profile-likelihood intervals" and "When
not to trust the Jacobian's intervals").

Two things beside the fit's linearised (Jacobian) intervals:

- `profile_intervals`: profile-likelihood intervals. Each parameter in turn is held at
  a sequence of values on each side of its estimate, the others re-optimised by the fit's
  own optimiser on the fit's own residuals (`hydroarm.analysis.fit.least_squares` on
  the fit's model, passed in), until the cost Σr² has risen by the threshold Δ above its
  minimum (Venzon & Moolgavkar 1988, *Appl. Statist.* 37, 87–94; Raue et al. 2009,
  *Bioinformatics* 25, 1923–1929). The likelihood assumed is the fit's: independent
  Gaussian residuals of one variance s² estimated from the fit, s² = Σr²/(m − p); the
  threshold is Δ = t²₀.₉₇₅(m − p)·s² (= F₀.₉₅(1, m − p)·s², the exact likelihood-ratio
  threshold of a linear model with estimated variance, Bates & Watts 1988, *Nonlinear
  regression analysis*, §6.1.2; χ²₁(0.95)·s² = 3.84·s² as m grows), so that for a model
  linear in its parameters the profile interval is the Jacobian's exactly.
- `interval_checks`: per parameter, why the Jacobian's interval is not to be trusted
  (an estimate at a bound, an ill-conditioned JᵀJ, a profile or bootstrap interval of
  another width, minima that disagree), as flags for fit.csv and warning lines.

This module takes the fit's model, optimiser and arrays as arguments; it imports nothing of
`hydroarm.analysis.fit` (which imports it).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import HydroarmError

#: the interval kinds of ``[fit] intervals`` (the Jacobian's is always computed)
INTERVAL_KINDS = ("jacobian", "bootstrap", "profile")
#: refits per side and parameter of a profile, by default (``[fit] profile_refits``
#: defaults to 2·p times this): enough for 2 to 4 steps outwards and 2 refinements
PROFILE_STEPS = 8
#: fewest refits per side: one step out, one further, one refinement
MIN_PROFILE_STEPS = 3
#: most profile refits in all (each a whole fit of p − 1 parameters from a near start)
MAX_PROFILE_REFITS = 5000
#: refinements of a bracketed end (each one refit): the ends interpolated in √q between
#: the bracket, exact for a model linear in its parameters
PROFILE_REFINE = 2
#: a bracketed end is accepted when its refit's statistic q is within this of 1 (the
#: threshold): the end then lies within ≈ 1 % of the interval's half-width (√q linear)
PROFILE_Q_TOL = 0.02
#: a profile point whose cost is below the fit's minimum by more than this fraction of the
#: threshold Δ is a lower minimum the fit did not find
LOWER_MINIMUM = 0.05
#: growth of the step outwards between refits, at least and at most (the next step aims
#: 10 % beyond where √q, linear in the step, predicts the threshold)
GROW_MIN, GROW_MAX, OVERSHOOT = 1.25, 4.0, 1.1
#: an interval (or one side of it, for a profile) this many times wider or narrower than
#: the Jacobian's: the model is not linear in the parameter over the interval
DISAGREE = 1.5
#: an ill-conditioned JᵀJ: a condition index of the column-equilibrated Jacobian above
#: this (κ(JᵀJ) > 10⁶). Why: the Jacobian is a forward difference with relative step 10⁻⁴,
#: so each column carries an error of about 10⁻⁴ of its size; by Weyl's inequality a
#: singular value below 10⁻³ of the largest then moves by more than 10 %, and the variance
#: along it (1/σ²) by more than 20 %. The parameters whose variance comes more than half
#: from such directions are flagged (variance-decomposition proportions, Belsley, Kuh &
#: Welsch 1980, *Regression diagnostics*, §3.2)
CONDITION_LIMIT = 1e3
VARIANCE_SHARE = 0.5


@dataclass
class Profile:
    """One parameter's profile: the values held [SI], the statistic q = (C − C_min)/Δ of
    each (the others re-optimised; 1 is the 95 % threshold), the interval's ends [SI] and
    why an end is open (``""``: closed, ``"bound"``: the parameter's bound reached below
    the threshold, ``"budget"``: the side's refits spent below it, the end reported being
    the furthest value profiled)."""

    parameter: str
    estimate: float
    values: np.ndarray
    q: np.ndarray
    low: float
    high: float
    low_open: str = ""
    high_open: str = ""
    refits: int = 0
    failed: int = 0
    lower: tuple | None = None  # (value held [SI], cost) of a lower minimum found

    @property
    def ends(self) -> str:
        """``closed``, ``open_low``, ``open_high`` or ``open_both`` (fit.csv)."""
        lo, hi = bool(self.low_open), bool(self.high_open)
        return "open_both" if lo and hi else "open_low" if lo else "open_high" if hi else "closed"

    def describe(self) -> str:
        """The interval in words, an open side said (the bound: the cost stays below the
        threshold down to it; the refits or the model ran out: the end lies beyond)."""
        return f"{_end(self.low, self.low_open, '≤')} … {_end(self.high, self.high_open, '≥')}"


def _end(value: float, why: str, beyond: str) -> str:
    if not why:
        return f"{value:.6g}"
    if why == "bound":
        return f"{value:.6g} (the bound)"
    reason = "refits spent" if why == "budget" else "the model fails beyond"
    return f"{beyond} {value:.6g} (open: {reason})"


@dataclass
class ProfileRun:
    """What `profile_intervals` needs of the fit: the residuals ``model`` (called on
    scaled parameters z; ``model.jacobian(z, lo, hi, central, free)``, ``model.engine``),
    the optimiser ``least_squares(fun, z0, jac, lo, hi, tol)``, the solution ``z_hat``
    (scaled) with its cost ``cost_min`` = Σr², the scaled covariance ``cov_z``, the
    threshold ``delta`` (Δ, in cost), the bounds, the scale (SI = z·scale), the Jacobian
    scheme, the tolerance and the failed-run residual ``penalty``."""

    model: Any
    least_squares: Callable[..., Any]
    z_hat: np.ndarray
    cost_min: float
    cov_z: np.ndarray
    delta: float
    quantile: float
    lo_z: np.ndarray
    hi_z: np.ndarray
    scale: np.ndarray
    central: bool
    tol: float
    penalty: float
    names: tuple = ()
    refits: int = 0
    notes: list = field(default_factory=list)


def profile_refits_default(n_parameters: int) -> int:
    """``[fit] profile_refits`` when not given: `PROFILE_STEPS` per side."""
    return 2 * PROFILE_STEPS * n_parameters


def check_profile_budget(field_name: str, budget: int, n_parameters: int) -> None:
    """Refuse, before any run, a budget that cannot profile every parameter on both sides
    (`MIN_PROFILE_STEPS` each) or is above `MAX_PROFILE_REFITS`."""
    need = 2 * MIN_PROFILE_STEPS * n_parameters
    if budget < need:
        raise HydroarmError(
            field_name,
            f"{budget} refits cannot profile {n_parameters} parameters: at least {need} "
            f"({MIN_PROFILE_STEPS} per side and parameter; default "
            f"{profile_refits_default(n_parameters)})",
        )
    if budget > MAX_PROFILE_REFITS:
        raise HydroarmError(field_name, f"{budget} refits: at most {MAX_PROFILE_REFITS}")


def profile_intervals(run: ProfileRun, budget: int, tick=None) -> list[Profile]:
    """The profile-likelihood interval of every parameter (module doc), ``budget`` refits
    in all, shared equally by the 2·p sides (a side that closes early leaves its rest
    unused). ``tick(label)`` is called once at the end and its ``note`` (throttled) after
    each refit, as the bootstrap's progress."""
    n = len(run.z_hat)
    per_side = budget // (2 * n)
    note = getattr(tick, "note", None)
    out = []
    for i in range(n):
        sides = []
        for sign in (-1.0, 1.0):
            sides.append(_side(run, i, sign, per_side, note, budget))
        (dl, ql, zl, why_l, nl, fl), (dh, qh, zh, why_h, nh, fh) = sides
        s = run.scale[i]
        values = np.concatenate([(run.z_hat[i] - dl[::-1]) * s, [run.z_hat[i] * s],
                                 (run.z_hat[i] + dh) * s])  # fmt: skip
        q = np.concatenate([ql[::-1], [0.0], qh])
        lower = _lowest(run, i, [(dl, ql, -1.0), (dh, qh, 1.0)])
        out.append(
            Profile(
                parameter=run.names[i] if run.names else str(i),
                estimate=float(run.z_hat[i] * s),
                values=values,
                q=q,
                low=float((run.z_hat[i] - zl) * s),
                high=float((run.z_hat[i] + zh) * s),
                low_open=why_l,
                high_open=why_h,
                refits=nl + nh,
                failed=fl + fh,
                lower=lower,
            )
        )
    if tick is not None:
        failed = sum(p.failed for p in out)
        tick(f"profile: {run.refits} refits, {failed} failed")
    return out


def _lowest(run: ProfileRun, i: int, sides) -> tuple | None:
    """The lowest profile point whose cost is below the fit's minimum by more than
    `LOWER_MINIMUM`·Δ: (value held [SI], cost), else None."""
    best = None
    for d, q, sign in sides:
        for dd, qq in zip(d, q, strict=True):
            if qq < -LOWER_MINIMUM and (best is None or qq < best[1]):
                best = (dd * sign, qq)
    if best is None:
        return None
    return (float((run.z_hat[i] + best[0]) * run.scale[i]), run.cost_min + best[1] * run.delta)


def _side(run: ProfileRun, i: int, sign: float, steps: int, note, budget: int):
    """One side of parameter i's profile: (distances δ ≥ 0 profiled [scaled], their q, the
    end's distance, why open ("" closed), refits, failed)."""
    z_hat = run.z_hat
    room = (run.hi_z[i] - z_hat[i]) if sign > 0 else (z_hat[i] - run.lo_z[i])
    ds: list[float] = []
    qs: list[float] = []
    if not room > 0:  # the estimate on the bound: the interval ends there
        return np.zeros(0), np.zeros(0), 0.0, "bound", 0, 0
    var = run.cov_z[i, i]
    sigma = math.sqrt(var) if math.isfinite(var) and var > 0 else 0.1 * max(abs(z_hat[i]), 1.0)
    free = np.arange(len(z_hat)) != i
    slope = (
        run.cov_z[free, i] / var
        if math.isfinite(var) and var > 0 and np.all(np.isfinite(run.cov_z[free, i]))
        else np.zeros(int(free.sum()))
    )  # the linear profile trace: the others' conditional optimum per unit of parameter i
    inner = (0.0, 0.0, z_hat[free])  # (δ, q, the others' optimum)
    outer: tuple | None = None
    failed = used = 0
    step = min(run.quantile * sigma, room)  # where the Jacobian's interval ends
    while used < steps:
        q, zf, ok = _refit(run, i, sign, step, inner, slope, free)
        used += 1
        failed += not ok
        ds.append(step)
        qs.append(q)
        if note is not None:
            note(f"profile: {run.refits}/{budget} refits")
        if q >= 1.0 or not ok:
            outer = (step, q, zf, ok)
            break
        inner = (step, q, zf)
        if step >= room * (1 - 1e-12):  # the bound reached below the threshold
            return np.array(ds), np.array(qs), room, "bound", used, failed
        grow = GROW_MAX if q <= 0 else OVERSHOOT / math.sqrt(q)
        step = min(step * min(max(grow, GROW_MIN), GROW_MAX), room)
    if outer is None:  # the side's refits spent below the threshold
        return np.array(ds), np.array(qs), inner[0], "budget", used, failed
    refine = 0
    while refine < PROFILE_REFINE and used < steps and abs(outer[1] - 1.0) > PROFILE_Q_TOL:
        mid = _crossing(inner, outer)
        q, zf, ok = _refit(run, i, sign, mid, inner, slope, free)
        used += 1
        refine += 1
        failed += not ok
        ds.append(mid)
        qs.append(q)
        if note is not None:
            note(f"profile: {run.refits}/{budget} refits")
        if abs(q - 1.0) <= PROFILE_Q_TOL and ok:
            order = np.argsort(ds)
            return np.array(ds)[order], np.array(qs)[order], mid, "", used, failed
        if q >= 1.0 or not ok:
            outer = (mid, q, zf, ok)
        else:
            inner = (mid, q, zf)
    order = np.argsort(ds)
    if not outer[3]:  # the model fails beyond the furthest point that ran
        return np.array(ds)[order], np.array(qs)[order], inner[0], "failed", used, failed
    return np.array(ds)[order], np.array(qs)[order], _crossing(inner, outer), "", used, failed


def _crossing(inner, outer) -> float:
    """Where q = 1 between a point below (inner) and one above (outer): linear in √q (exact
    for a linear model, whose q is (δ/(t·σ))²); the midpoint when the outer run failed."""
    d0, q0 = inner[0], max(inner[1], 0.0)
    d1, q1 = outer[0], outer[1]
    if not outer[3] or not math.isfinite(q1):
        return 0.5 * (d0 + d1)
    r0, r1 = math.sqrt(q0), math.sqrt(q1)
    if r1 <= r0:
        return 0.5 * (d0 + d1)
    return d0 + (1.0 - r0) / (r1 - r0) * (d1 - d0)


def _refit(run: ProfileRun, i: int, sign: float, step: float, inner, slope, free):
    """Parameter i held at ẑᵢ + sign·step, the others re-optimised from the inner point
    moved along the linear profile trace: (q, the others' optimum, whether the model ran)."""
    run.refits += 1
    z_hat = run.z_hat
    zi = float(np.clip(z_hat[i] + sign * step, run.lo_z[i], run.hi_z[i]))
    y0 = np.clip(inner[2] + slope * sign * (step - inner[0]), run.lo_z[free], run.hi_z[free])

    def full(y):
        z = z_hat.copy()
        z[free] = y
        z[i] = zi
        return z

    model = run.model
    if not free.any():  # one parameter: nothing to re-optimise
        r = np.asarray(model(full(y0)))
        y = y0
    else:
        jac: Any = "3-point" if run.central else "2-point"
        if getattr(model, "engine", "serial") == "batch":
            jac = lambda y: model.jacobian(full(y), run.lo_z, run.hi_z, run.central, free)  # noqa: E731
        try:
            sol = run.least_squares(
                lambda y: model(full(y)),
                y0,
                jac,
                run.lo_z[free],
                run.hi_z[free],
                run.tol,
            )
        except HydroarmError:
            return math.inf, y0, False
        r, y = np.asarray(sol.fun), sol.x
    if not np.all(np.isfinite(r)) or np.all(r == run.penalty):
        return math.inf, y0, False
    return (float(r @ r) - run.cost_min) / run.delta, y, True


def linear_ends(z_hat, cov_z, quantile: float, lo_z, hi_z) -> tuple[np.ndarray, list]:
    """The 2p points where the linear theory puts each Jacobian interval's ends: the
    estimate moved along the linear profile trace Cov_{·i}/Cov_{ii} by ∓t·SEᵢ (scaled
    parameters, rows), those inside the bounds, and their (parameter, side) (side 0: low,
    1: high). At each, a model linear in its parameters has the cost C_min + Δ exactly
    (`interval_checks`' ``end_q``); one engine run evaluates them all."""
    rows, where = [], []
    for i in range(len(z_hat)):
        var = cov_z[i, i]
        if not (math.isfinite(var) and var > 0 and np.all(np.isfinite(cov_z[:, i]))):
            continue
        move = quantile * cov_z[:, i] / math.sqrt(var)
        for side, z in enumerate((z_hat - move, z_hat + move)):
            if np.all(z >= lo_z) and np.all(z <= hi_z):
                rows.append(z)
                where.append((i, side))
    return np.array(rows).reshape(len(rows), len(z_hat)), where


# ------------------------------------------------------------------ the checks ---
@dataclass
class IntervalChecks:
    """Per parameter the reasons its Jacobian interval is not to be trusted (codes:
    ``at_bound``, ``ill_conditioned``, ``nonlinear``, ``multimodal``) and the warning
    lines saying why."""

    flags: list[list[str]]
    warnings: list[str]

    def flag(self, i: int) -> str:
        """fit.csv's ``jacobian_warning`` cell: the codes joined by ``;``, or ``none``."""
        return ";".join(self.flags[i]) or "none"


def _beyond_bounds(i, estimate, low, high, bounds, cov) -> tuple | None:
    """Parameter i's Jacobian interval against the bounds (`interval_checks`,
    ``at_bound``): (j, value, bound) of the first parameter j out of bounds at one of the
    interval's ends (value None: the estimate itself on its bound), else None."""
    lo_b, hi_b = bounds
    e = estimate[i]
    if e <= lo_b[i] or e >= hi_b[i]:
        return (i, None, lo_b[i] if e <= lo_b[i] else hi_b[i])
    var = cov[i, i] if cov is not None else math.nan
    if cov is not None and math.isfinite(var) and var > 0 and np.all(np.isfinite(cov[:, i])):
        trace = cov[:, i] / var  # the others' linear optimum per unit of parameter i
        ends = [estimate + trace * (low[i] - e), estimate + trace * (high[i] - e)]
    else:
        ends = [np.where(np.arange(len(estimate)) == i, x, estimate) for x in (low[i], high[i])]
    for end in ends:
        for j in [i, *(j for j in range(len(estimate)) if j != i)]:
            if end[j] < lo_b[j]:
                return (j, float(end[j]), float(lo_b[j]))
            if end[j] > hi_b[j]:
                return (j, float(end[j]), float(hi_b[j]))
    return None


def interval_checks(
    names,
    jac: np.ndarray,
    estimate: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    *,
    starts=(),
    delta: float = math.nan,
    profiles=None,
    boot_interval=None,
    cov: np.ndarray | None = None,
    end_q: np.ndarray | None = None,
) -> IntervalChecks:
    """Why each parameter's Jacobian interval [low, high] (SI) is not to be trusted
    (docs/fit.md "When not to trust the Jacobian's intervals"):

    - ``at_bound``: the estimate sits on a bound, or at an end of the interval the linear
      theory's parameter vector (the estimate moved along the linear profile trace,
      ``cov[:, i]/cov[i, i]``, by the interval's half-width; ``cov`` [SI], without it the
      parameter alone) lies beyond a bound of this parameter or of another: the constraint
      cuts the likelihood and that end cannot be reached, so a symmetric interval from the
      local curvature is wrong;
    - ``ill_conditioned``: more than `VARIANCE_SHARE` of the parameter's variance
      comes from directions of the column-equilibrated Jacobian ``jac`` whose condition
      index exceeds `CONDITION_LIMIT` (why that threshold: its comment);
    - ``nonlinear``: a profile side, or the bootstrap interval, `DISAGREE` times wider
      or narrower than the Jacobian's, or a profile end open where the Jacobian's is closed;
      without a profile, ``end_q`` (parameter × low/high: the cost's rise over Δ at the
      points of `linear_ends`, NaN where not run) outside [1/DISAGREE², DISAGREE²]:
      a linear model gives 1 there, and a quadratic profile of another curvature gives
      1/(width ratio)²;
    - ``multimodal``: another start ended within the threshold ``delta`` of the best cost
      with this parameter outside the interval, or the profile found a lower cost.
    """
    n = len(names)
    flags: list[list[str]] = [[] for _ in range(n)]
    warnings: list[str] = []
    use = (
        "use the profile's, which stops at the bound"
        if profiles is not None
        else 'ask for the profile\'s (intervals = "profile"), which stops at the bound'
    )
    for i, k in enumerate(names):
        beyond = _beyond_bounds(i, estimate, low, high, bounds, cov)
        if beyond:
            flags[i].append("at_bound")
            j, v, b = beyond
            span = f"its Jacobian interval ({low[i]:.6g} … {high[i]:.6g})"
            if v is None:
                where = f"its estimate {estimate[i]:.6g} sits on its bound {b:.6g}"
            elif j == i:
                where = f"{span} reaches {v:.6g}, beyond its bound {b:.6g}"
            else:
                where = (
                    f"at an end of {span} the others' linear optimum puts {names[j]} at "
                    f"{v:.6g}, beyond that parameter's bound {b:.6g}"
                )
            warnings.append(
                f"{k}: {where}: that interval assumes an unconstrained optimum and is not "
                f"to be trusted; {use}"
            )
    jac = np.asarray(jac, float)
    norms = np.linalg.norm(jac, axis=0) if jac.size else np.zeros(n)
    seen = norms > 0
    if jac.size and np.all(np.isfinite(jac)):
        for i in map(
            int, np.flatnonzero(~seen)
        ):  # a column of zeros: the data do not see it at all
            flags[i].append("ill_conditioned")
            warnings.append(
                f"{names[i]}: the residuals do not change with it (a zero column of the "
                "Jacobian): no interval from these data"
            )
    if jac.size and np.all(np.isfinite(jac)) and seen.any():
        _, sv, vt = np.linalg.svd(jac[:, seen] / norms[seen], full_matrices=False)
        index = sv[0] / np.maximum(sv, 1e-300)
        phi = vt.T**2 / np.maximum(sv, 1e-150) ** 2  # (parameter, direction)
        share = phi / phi.sum(axis=1, keepdims=True)
        weak = index > CONDITION_LIMIT
        for row, i in enumerate(map(int, np.flatnonzero(seen))):
            part = float(share[row, weak].sum())
            if part > VARIANCE_SHARE:
                flags[i].append("ill_conditioned")
                warnings.append(
                    f"{names[i]}: {part:.0%} of its variance lies along directions of JᵀJ with "
                    f"a condition index up to {index.max():.3g} (limit {CONDITION_LIMIT:.0e}: "
                    "the forward-difference Jacobian is not accurate enough there): its "
                    "Jacobian interval is not to be trusted"
                )
    for i, k in enumerate(names):
        lin = high[i] - low[i]
        if not (math.isfinite(lin) and lin > 0):
            continue
        p = profiles[i] if profiles is not None else None
        if p is not None:
            half = 0.5 * lin
            ratios = [(estimate[i] - p.low) / half, (p.high - estimate[i]) / half]
            bad = [
                r > DISAGREE or r < 1 / DISAGREE or bool(why)
                for r, why in zip(ratios, (p.low_open, p.high_open), strict=True)
            ]
            if any(bad):
                flags[i].append("nonlinear")
                warnings.append(
                    f"{k}: the profile-likelihood interval ({p.describe()}) spans "
                    f"{ratios[0]:.2g} and {ratios[1]:.2g} times the Jacobian's half-widths "
                    f"below and above the estimate (limits 1/{DISAGREE} … {DISAGREE}): the "
                    "model is not linear in it over the interval; use the profile's"
                )
        if boot_interval is not None:
            ratio = (boot_interval[1][i] - boot_interval[0][i]) / lin
            if ratio > DISAGREE or ratio < 1 / DISAGREE:
                if "nonlinear" not in flags[i]:
                    flags[i].append("nonlinear")
                warnings.append(
                    f"{k}: the bootstrap's 95 % interval is {ratio:.2g} times as wide as the "
                    "linearised one: the Jacobian's interval is unreliable here (the model is "
                    "not linear in it over the interval); use the bootstrap's"
                )
    if end_q is not None and profiles is None:
        for i, k in enumerate(names):
            for side, q in enumerate(end_q[i]):
                if not math.isfinite(q) or 1 / DISAGREE**2 <= q <= DISAGREE**2:
                    continue
                if "nonlinear" not in flags[i]:
                    flags[i].append("nonlinear")
                end = (low, high)[side][i]
                warnings.append(
                    f"{k}: at the {('lower', 'upper')[side]} end of its Jacobian interval "
                    f"({end:.6g}, the others at their linearised optimum) the cost rises by "
                    f"{q:.3g} times the 95 % threshold, where a model linear in its parameters "
                    f"rises by exactly 1 (limits 1/{DISAGREE}² … {DISAGREE}²): the model is not "
                    'linear over the interval; ask for the profile\'s (intervals = "profile")'
                )
    if len(starts) > 1 and math.isfinite(delta):
        best = min(r["cost"] for r in starts)
        for j, r in enumerate(starts):
            if not math.isfinite(r["cost"]) or r["cost"] - best > delta:
                continue
            away = [
                i
                for i in range(n)
                if not (low[i] <= r["estimate"][i] <= high[i]) and math.isfinite(high[i] - low[i])
            ]
            for i in away:
                if "multimodal" not in flags[i]:
                    flags[i].append("multimodal")
            if away:
                warnings.append(
                    f"start {j + 1} ended at another minimum of about the same cost "
                    f"({r['cost']:.6g}, within the 95 % threshold {delta:.3g} of the best) "
                    "with "
                    + ", ".join(f"{names[i]} = {r['estimate'][i]:.6g}" for i in away)
                    + " outside the kept estimate's interval: the cost has several minima "
                    "and the intervals describe one of them"
                )
    if profiles is not None:
        for i, p in enumerate(profiles):
            if p is not None and p.lower is not None:
                if "multimodal" not in flags[i]:
                    flags[i].append("multimodal")
                warnings.append(
                    f"{names[i]}: its profile found a lower cost ({p.lower[1]:.6g}) at "
                    f"{names[i]} = {p.lower[0]:.6g} (the others re-optimised): the fit stopped "
                    "at a local minimum; refit from there or with starts = N"
                )
    return IntervalChecks(flags, warnings)
