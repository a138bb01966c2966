"""Scalar targets and tied parameters of a fit file; leave-one-out prediction (issue 16).

A ``[[target]]`` entry states a measured scalar metric of a saturation test (the saturation
velocity of a load raised, a time constant, a peak pressure, the stall mass …) with its
uncertainty. Its residual is (model − value)/uncertainty: a number of standard deviations.
The model's values of all targets, for all the joints of a fit's trial (the optimiser's
point and its perturbed copies), are computed together: every saturation test in one run of
the batch engine (`hydroarm.batch.saturation.batch_metrics`), the stall searches side by
side (`hydroarm.batch.saturation.stall_masses`).

``[fit.tied]`` sets joint fields from the fitted parameters by a small grammar, constant ±
factor·parameter ± …, e.g. ``null_leakage_coefficient = "475 mm**5/s/N - leakage_coefficient"``
(the measured arm's valve keeps the paper's printed leakage at null, docs/physics.md).

`leave_one_out` refits a problem without each group of traces or targets in turn and
reports the prediction of the group left out. docs/fit.md states the statistics.
"""

from __future__ import annotations

import math
import re
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace

import numpy as np

from ..batch.saturation import (
    batch_metrics,
    hand_load,
    horizontal_probe,
    passes_horizontal,
    stall_mass,
    stall_masses,
)
from ..errors import HydroarmError
from ..io.catalog import paper_load
from ..io.schema import parse_load
from ..io.sections import (
    FIELD_DIMENSIONS,
    number_or_quantity,
    reject_unknown_keys,
    require_keys,
    text_value,
    unknown_name,
)
from ..io.units import SI_UNITS, check_number, velocity_or_angular_velocity
from ..model.joint import Load, ServoJoint
from ..model.rules import FIELD_RULES, NONNEGATIVE, POSITIVE
from ..model.scenario import Scenario, saturation_test

# metric -> dimension of its value (saturation_velocity: also an angular velocity)
TARGET_METRICS = {
    "saturation_velocity": "velocity",
    "time_constant_start": "time",
    "time_constant_start_velocity": "time",
    "time_constant_end": "time",
    "peak_pressure": "pressure",
    "reach": "length",
    "final_x": "length",
    "stall_mass": "mass",
}
TARGET_KEYS = {"metric", "value", "uncertainty", "load", "direction", "name", "group"}
# the stall search's tolerance [kg]: far below the change a Jacobian step makes (a relative
# step of 1e-4 in the gearbox loss at stall moves the ucl-arm-measured stall mass by 1.7 g)
STALL_TOL_KG = 1e-6
# solving a field for the stall: bisection to SOLVE_TOL of the bracket, first in the last
# value ± SOLVE_WIDTH of it; SOLVE_STEP: the step of its sensitivity (forward difference)
SOLVE_TOL = 1e-7
SOLVE_WIDTH = 0.005
SOLVE_STEP = 1e-4
SOLVE_NEAR = 5e-4  # the width for a Jacobian's perturbed points, near the first's value
_last_solved: dict = {}  # the last value solved per field: where the next search starts
_last_stall: list = [None]  # the last stall mass found [kg]: where the next search starts
PERCENT = re.compile(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*%\s*")


@dataclass(frozen=True)
class Target:
    """A measured scalar, fitted beside or instead of traces (docs/fit.md).

    ``metric`` of the saturation test of ``load`` in ``direction`` (the stall mass: of the
    paper's stall test) is ``value`` ± ``uncertainty``.

    Parameters
    ----------
    metric : str
        The metric (``saturation_velocity``, ``stall_mass``, ...).
    value : float
        Measured value (SI: an angular velocity in [rad/s], a mass in [kg]).
    uncertainty : float
        Its standard uncertainty [the value's unit].
    load : Load, optional
        The load of the test.
    direction : str, optional
        ``"raise"`` or ``"lower"``.
    dimension : str
        The value's dimension (``"velocity"``, ...), which gives its SI unit.
    name : str
        Label.
    group : str
        Leave-one-out group.
    """

    metric: str
    value: float
    uncertainty: float
    load: Load | None = None
    direction: str | None = None
    dimension: str = "velocity"
    name: str = "target"
    group: str = "target"

    @property
    def unit(self) -> str:
        return SI_UNITS[self.dimension]


@dataclass(frozen=True)
class Tie:
    """``field`` = ``constant`` + Σ factor·parameter (SI), clipped at the field's sign rule."""

    field: str
    constant: float
    terms: tuple[tuple[float, str], ...]
    text: str = ""

    def value(self, values: dict) -> float:
        v = self.constant + sum(f * values[p] for f, p in self.terms)
        rule = FIELD_RULES[self.field][1]
        if rule == POSITIVE:  # a joint rejects 0: the smallest positive float instead
            return max(v, 5e-324)
        return max(v, 0.0) if rule == NONNEGATIVE else v


def apply_ties(joint: ServoJoint, values: dict, ties) -> ServoJoint:
    """``joint`` with the fitted ``values`` and the tied fields that follow from them."""
    j = joint.replace(**values)
    if not ties:
        return j
    return j.replace(**{t.field: float(t.value(values)) for t in ties})


@dataclass(frozen=True)
class Solve:
    """``field`` solved, for every trial, so that the stall-mass target ``target`` is met
    exactly (bisection in ``bracket`` on the stall test at the target's mass)."""

    field: str
    target: str
    bracket: tuple[float, float]


def solve_field(
    joint: ServoJoint, sv: Solve, mass: float, guess=None, width: float | None = None
) -> ServoJoint:
    """``joint`` with ``sv.field`` set so that ``mass`` [kg] in the hand just stalls the
    raising arm at the horizontal, to `SOLVE_TOL` (relative to the bracket); searched
    first in ``guess`` ± ``width`` (default `SOLVE_WIDTH`, relative to the bracket)."""
    lo, hi = sv.bracket
    load = hand_load(mass)

    def passes(v: float) -> bool:
        return passes_horizontal(horizontal_probe(joint.replace(**{sv.field: v}), load))

    tol = SOLVE_TOL * (hi - lo)
    w = (SOLVE_WIDTH if width is None else width) * (hi - lo)
    if guess is not None and lo < guess - w < guess + w < hi:
        a, b = guess - w, guess + w
        pa, pb = passes(a), passes(b)
        if pa != pb:
            return joint.replace(**{sv.field: float(_solve_bisect(passes, a, b, pa, tol))})
    pa, pb = passes(lo), passes(hi)
    if pa == pb:
        raise HydroarmError(
            f"fit.solve.{sv.field}",
            f"no value in {lo:g} … {hi:g} makes {mass:g} kg just stall the arm (with "
            f"{sv.field} = {lo:g} the arm {'passes' if pa else 'stalls'}, with {hi:g} too)",
        )
    return joint.replace(**{sv.field: float(_solve_bisect(passes, lo, hi, pa, tol))})


def _solve_bisect(passes, a: float, b: float, pa: bool, tol: float) -> float:
    """The switch of a predicate between ``a`` (value ``pa``) and ``b`` (the other)."""
    while b - a > tol:
        mid = 0.5 * (a + b)
        if passes(mid) == pa:
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)


def solve_fields(joints, solves, targets) -> list[ServoJoint]:
    """`solve_field` of every solve for every joint, the first joint (a fit's point)
    near the last value found, the others (its perturbed copies) near the first's, side by
    side in threads (the probe kernel releases the GIL)."""
    joints = list(joints)
    if not solves or not joints:
        return joints
    by_name = {tg.name: tg for tg in targets}

    def one(j: ServoJoint, guesses: dict, width=None) -> ServoJoint:
        for sv in solves:
            j = solve_field(j, sv, by_name[sv.target].value, guesses.get(sv.field), width)
        return j

    start = {sv.field: getattr(joints[0], sv.field) for sv in solves}
    first = one(joints[0], {**start, **_last_solved})
    _last_solved.update({sv.field: getattr(first, sv.field) for sv in solves})
    if len(joints) == 1:
        return [first]
    guesses = {sv.field: getattr(first, sv.field) for sv in solves}
    with ThreadPoolExecutor(max_workers=2) as pool:
        rest = list(pool.map(lambda j: one(j, guesses, SOLVE_NEAR), joints[1:]))
    return [first, *rest]


def solved_sensitivity(joint: ServoJoint, sv: Solve, mass: float) -> float:
    """∂(stall mass)/∂(solved field) [kg per unit] at ``joint``: how far the field moves
    for the stall target's uncertainty."""
    lo, hi = sv.bracket
    v = getattr(joint, sv.field)
    h = SOLVE_STEP * (hi - lo) * (1 if v + SOLVE_STEP * (hi - lo) < hi else -1)
    m1 = stall_mass(joint.replace(**{sv.field: v + h}), tol=STALL_TOL_KG, guess=mass)
    return (m1 - mass) / h


# ---------------------------------------------------------------- the model ---
def target_scenario(joint: ServoJoint, tg: Target) -> Scenario:
    assert tg.load is not None and tg.direction is not None
    return saturation_test(joint, tg.load, tg.direction)


def angular_factor(sc: Scenario, m: dict) -> float:
    """Arm angle per jack travel [rad/m] over the window of the saturation velocity (the
    middle of the motion, to the target or, stalled, to the furthest point reached):
    the jack's saturation velocity times this is the arm's mean angular velocity there."""
    j = sc.joint
    x0 = j.jack_position(sc.initial_angle)
    # a stalled motion ends where it got to: ``reach`` is a distance from the start, in the
    # direction of the command (metrics/online.py)
    sign = 1.0 if sc.target >= x0 else -1.0
    x_end = x0 + sign * m["reach"] if m["stalled"] else sc.target
    mid = sc.metric_options.middle
    a = x0 + 0.5 * (1 - mid) * (x_end - x0)
    b = x0 + 0.5 * (1 + mid) * (x_end - x0)
    return abs(j.joint_angle(b) - j.joint_angle(a)) / abs(b - a)


def target_values(joints, targets, met=()) -> np.ndarray:
    """The model's value of each target for each joint, shape (len(joints), len(targets)):
    every saturation test in one batch-engine run, the stall masses searched side by side;
    the targets named in ``met`` (met by a solved field) are their value."""
    joints, targets = list(joints), list(targets)
    out = np.full((len(joints), len(targets)), math.nan)
    for i, tg in enumerate(targets):
        if tg.name in met:
            out[:, i] = tg.value
    runs = [i for i, tg in enumerate(targets) if tg.metric != "stall_mass"]
    if runs:
        scs = [target_scenario(j, targets[i]) for j in joints for i in runs]
        ms = batch_metrics(scs)
        k = 0
        for a in range(len(joints)):
            for i in runs:
                tg, m = targets[i], ms[k]
                v = float(m[tg.metric])
                if tg.dimension == "angular_velocity":
                    v *= angular_factor(scs[k], m)
                out[a, i] = v
                k += 1
    stalls = [i for i, tg in enumerate(targets) if tg.metric == "stall_mass" and tg.name not in met]
    if stalls:
        # the first joint (a fit's point) searched near the last stall found, the others
        # (its perturbed copies) near it: a hint only, the answer is the same to the tolerance
        first = stall_mass(joints[0], tol=STALL_TOL_KG, guess=_last_stall[0])
        _last_stall[0] = first
        rest = stall_masses(joints[1:], tol=STALL_TOL_KG, guess=first) if joints[1:] else []
        for i in stalls:
            out[:, i] = [first, *rest]
    return out


def target_residuals(joints, targets, met=()) -> np.ndarray:
    """(model − value)/uncertainty of each target for each joint, shape
    (len(joints), len(targets)); a target the model gives no finite value of is an error.
    ``met``: names of targets met by a solved field (residual 0)."""
    vals = target_values(joints, targets, met)
    for i, tg in enumerate(targets):
        if not np.all(np.isfinite(vals[:, i])):
            raise HydroarmError(
                f"target {tg.name}",
                f"the model gives no finite {tg.metric} (e.g. a motion that never gets "
                "under way, or a stall mass beyond the search range 0–20 kg)",
            )
    value = np.array([tg.value for tg in targets])
    sigma = np.array([tg.uncertainty for tg in targets])
    return (vals - value) / sigma


# ----------------------------------------------------------------- the file ---
def read_target(section: str, table: dict, index: int) -> Target:
    """A ``[[target]]`` entry; every problem a one-line error naming ``section``."""
    reject_unknown_keys(section, table, TARGET_KEYS)
    require_keys(section, table, ("metric", "value", "uncertainty"))
    metric = table["metric"]
    if not isinstance(metric, str) or metric not in TARGET_METRICS:
        raise unknown_name(f"{section}.metric", "metric", metric, TARGET_METRICS)
    dimension = TARGET_METRICS[metric]
    fv = f"{section}.value"
    if metric == "saturation_velocity":
        dimension, value = velocity_or_angular_velocity(fv, table["value"])
        if value == 0:
            raise HydroarmError(fv, "must not be zero")
    else:
        value = number_or_quantity(fv, table["value"], dimension)
    uncertainty = uncertainty_value(
        f"{section}.uncertainty", table["uncertainty"], value, dimension
    )
    load = direction = None
    if metric == "stall_mass":
        for k in ("load", "direction"):
            if k in table:
                raise HydroarmError(
                    f"{section}.{k}",
                    "has no meaning for stall_mass (the paper's stall test: the arm of "
                    "load 1 raised with a mass in the hand)",
                )
        default = "stall"
    else:
        require_keys(section, table, ("load", "direction"))
        direction = text_value(f"{section}.direction", table["direction"], ("raise", "lower"))
        raw = table["load"]
        load = (
            parse_load(f"{section}.load", raw)
            if isinstance(raw, dict)
            else paper_load(raw, field=f"{section}.load")
        )
        default = f"{metric} {load.name} {direction}"
    name = text_value(f"{section}.name", table.get("name", default))
    group = text_value(f"{section}.group", table.get("group", name))
    return Target(
        metric=metric,
        value=value,
        uncertainty=uncertainty,
        load=load,
        direction=direction,
        dimension=dimension,
        name=name,
        group=group,
    )


def uncertainty_value(field: str, raw, value: float, dimension: str) -> float:
    """A standard uncertainty [SI]: a quantity of the value's dimension, or ``"2 %"`` of it."""
    if isinstance(raw, str) and raw.strip().endswith("%"):
        m = PERCENT.fullmatch(raw)
        if m is None:
            raise HydroarmError(field, f'cannot read {raw!r} as a percentage (e.g. "2 %")')
        u = abs(value) * float(m.group(1)) / 100
    elif dimension == "angular_velocity":
        kind, u = velocity_or_angular_velocity(field, raw)
        if kind != dimension:
            raise HydroarmError(field, f"{raw!r} is not an angular velocity, as the value is")
    elif dimension == "velocity":
        kind, u = velocity_or_angular_velocity(field, raw)
        if kind != dimension:
            raise HydroarmError(field, f"{raw!r} is not a velocity, as the value is")
    else:
        u = number_or_quantity(field, raw, dimension)
    check_number(field, u, positive=True, shown=raw)
    return u


TERM = re.compile(
    r"(?:(?P<factor>[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*\*\s*)?(?P<name>[a-z_][a-z0-9_]*)"
)
MAX_TIE_TERMS = 8


def read_ties(table: dict, parameters, joint: ServoJoint) -> tuple[Tie, ...]:
    """``[fit.tied]``: ``field = "constant ± factor*parameter ± …"``, terms split at a ``+``
    or ``-`` with spaces on both sides; a constant carries the field's unit, a parameter
    (one of fit.parameters, of the field's dimension) an optional plain factor."""
    ties = []
    for key, raw in table.items():
        f = f"fit.tied.{key}"
        if key not in FIELD_DIMENSIONS or key not in FIELD_RULES:
            raise unknown_name(f, "joint parameter", key, sorted(FIELD_RULES))
        if key in parameters:
            raise HydroarmError(f, "is one of fit.parameters (a field is fitted or tied)")
        if not isinstance(raw, str) or not raw.strip():
            raise HydroarmError(f, 'must be a text, e.g. "475 mm**5/s/N - leakage_coefficient"')
        parts = re.split(r"\s+([+-])\s+", " " + raw.strip())
        head = parts[0].strip()
        items = ([("+", head)] if head else []) + list(zip(parts[1::2], parts[2::2], strict=True))
        if len(items) > MAX_TIE_TERMS:
            raise HydroarmError(f, f"has more than {MAX_TIE_TERMS} terms")
        constant, terms = 0.0, []
        for sign, text in items:
            text = text.strip()
            s = -1.0 if sign == "-" else 1.0
            m = TERM.fullmatch(text.removeprefix("-").strip())
            if m is not None:
                if text.startswith("-"):
                    s = -s
                name = m.group("name")
                if name not in parameters:
                    raise HydroarmError(f, f"{name!r} is not one of fit.parameters")
                if FIELD_DIMENSIONS[name] != FIELD_DIMENSIONS[key]:
                    raise HydroarmError(
                        f,
                        f"{name} is a {FIELD_DIMENSIONS[name]}, {key} a "
                        f"{FIELD_DIMENSIONS[key]}: only a plain factor may multiply it",
                    )
                terms.append((s * float(m.group("factor") or 1.0), name))
            else:
                constant += s * number_or_quantity(f, text, FIELD_DIMENSIONS[key])
        if not terms:
            raise HydroarmError(f, "names no fitted parameter (set the value in [joint])")
        tie = Tie(field=key, constant=constant, terms=tuple(terms), text=raw.strip())
        start = tie.value({p: getattr(joint, p) for _, p in terms})
        check_number(f, start, positive=FIELD_RULES[key][1] == POSITIVE, shown=raw)
        ties.append(tie)
    return tuple(ties)


def read_solves(table: dict, parameters, ties, targets) -> tuple[Solve, ...]:
    """``[fit.solve.<field>]``: ``target`` (the name of a stall_mass target) and
    ``bracket = [low, high]`` (with the field's units)."""
    out = []
    tied = {t.field for t in ties}
    stall_targets = [tg.name for tg in targets if tg.metric == "stall_mass"]
    used = set()
    for key, raw in table.items():
        f = f"fit.solve.{key}"
        if key not in FIELD_DIMENSIONS or key not in FIELD_RULES:
            raise unknown_name(f, "joint parameter", key, sorted(FIELD_RULES))
        if key in parameters or key in tied:
            raise HydroarmError(f, "is fitted or tied already (a field is fitted, tied or solved)")
        if not isinstance(raw, dict):
            raise HydroarmError(f, 'must be a table: target = "<stall_mass target name>", bracket')
        reject_unknown_keys(f, raw, {"target", "bracket"})
        require_keys(f, raw, ("target", "bracket"))
        name = raw["target"]
        if not isinstance(name, str) or name not in stall_targets:
            raise unknown_name(f"{f}.target", "stall_mass target", name, stall_targets)
        if name in used:
            raise HydroarmError(f"{f}.target", f"{name!r} is met by another solved field")
        used.add(name)
        b = raw["bracket"]
        if not isinstance(b, list) or len(b) != 2:
            raise HydroarmError(f"{f}.bracket", "must be [low, high] with units")
        lo, hi = (
            number_or_quantity(f"{f}.bracket", x, FIELD_DIMENSIONS[key], nonnegative=True)
            for x in b
        )
        if not lo < hi:
            raise HydroarmError(f"{f}.bracket", "low must be below high")
        out.append(Solve(field=key, target=name, bracket=(lo, hi)))
    return tuple(out)


# ------------------------------------------------------------ leave one out ---
def groups_of(problem) -> list[str]:
    """The groups of a problem's traces and targets, in file order."""
    names = [tr.group for tr in problem.traces]
    names += [tg.group for tg in problem.targets]
    return list(dict.fromkeys(names))


def loo_groups(problem) -> list[str]:
    """The groups that can be left out: those without a target met by a solved field."""
    met = {tg.group for tg in problem.targets if tg.name in problem.met}
    return [g for g in groups_of(problem) if g not in met]


def without_group(problem, group: str):
    """``problem`` without the traces and targets of ``group``."""
    return replace(
        problem,
        traces=tuple(tr for tr in problem.traces if tr.group != group),
        targets=tuple(tg for tg in problem.targets if tg.group != group),
    )


def leave_one_out(
    problem, joint: ServoJoint, groups=None, *, run, simulate, progress=None
) -> list[dict]:
    """Refit ``problem`` without each group in turn (started from ``joint``'s values of the
    parameters: the full fit's) and compare, for each trace and target of the group left
    out, ``joint`` (the in-sample model) with the prediction. Rows: ``group, item, kind,
    measured, fitted, predicted, fit_error, prediction_error, prediction_z, unit`` (a trace:
    RMS errors in its column's unit; a target: model − value, SI, and the prediction error
    over the uncertainty). ``run``: the fit (`hydroarm.analysis.fit.run_fit`);
    ``simulate``: a trace's model values (`hydroarm.analysis.fit.simulate_trace`)."""
    start = {k: float(getattr(joint, k)) for k in problem.parameters}
    rows = []
    for g in groups or loo_groups(problem):
        if progress is not None:
            progress(f"leave one out: refit without {g}")
        rest = replace(without_group(problem, g), initial=start)
        n_res = sum(len(t.t) for t in rest.traces) + len(rest.targets) - len(rest.solves)
        if n_res < len(problem.parameters):
            raise HydroarmError(
                "fit.leave_one_out",
                f"without {g!r} fewer data ({n_res}) than parameters ({len(problem.parameters)})",
            )
        loo = run(rest)
        for tr in problem.traces:
            if tr.group != g:
                continue
            rows.append(
                {
                    "group": g,
                    "item": tr.name,
                    "kind": "trace",
                    "measured": math.nan,
                    "fitted": math.nan,
                    "predicted": math.nan,
                    "fit_error": _rms(simulate(joint, tr) - tr.values),
                    "prediction_error": _rms(simulate(loo.joint, tr) - tr.values),
                    "prediction_z": math.nan,
                    "unit": tr.column.split("_")[-1],
                }
            )
        mine = [tg for tg in problem.targets if tg.group == g]
        if mine:
            full, pred = target_values([joint, loo.joint], mine)
            for tg, f_, p_ in zip(mine, full, pred, strict=True):
                rows.append(
                    {
                        "group": g,
                        "item": tg.name,
                        "kind": "target",
                        "measured": tg.value,
                        "fitted": float(f_),
                        "predicted": float(p_),
                        "fit_error": float(f_ - tg.value),
                        "prediction_error": float(p_ - tg.value),
                        "prediction_z": float((p_ - tg.value) / tg.uncertainty),
                        "unit": tg.unit,
                    }
                )
    return rows


def _rms(e) -> float:
    return float(np.sqrt(np.mean(np.square(e))))
