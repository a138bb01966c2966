"""Requirements on a servo joint as data, evaluated over load cases (issue 17; docs/design.md).

A requirement bounds one metric (`METRICS`: its SI unit and the sense a requirement
usually has) over a set of load cases and motion directions: ``time_constant <= 50 ms`` holds
when the 63 % time constant of every motion of every case it covers is at most 50 ms.
`read_requirements` and `read_load_cases` read them from a file's
``[requirements]`` table and ``[[load_case]]`` array (units through `hydroarm.io`);
`case_metrics` simulates the saturation tests of many joints, every joint, case and
direction in one run of the batch engine, and measures the metrics; `check` says,
requirement by requirement and case by case, whether each is met and with what margin.

The metrics of one motion (the paper's saturation test,
[`saturation_test`][hydroarm.saturation_test], lever stepped over the full range) come from the
batch engine's step metrics (`hydroarm.batch.saturation.step_metrics_of`, the numbers of
``simulate(sc).metric_values()``; simulated for the saturation test's default duration, or with
``grid_durations`` for `motion_duration`):

- ``time_constant`` [s]: ``time_constant_start``, from the lever step until the jack has
  moved 63 % of the full valve opening (infinite when it never does: a stalled start);
- ``effective_delay`` [s]: dead time + ``time_constant``, where the dead time is the same
  measure at 1 % of the full valve opening (``time_constant_start`` with the threshold 0.01:
  the time until the jack visibly starts to move);
- ``saturation_angular_velocity`` [rad/s]: the joint angle swept over the middle 80 % of the
  travel divided by the time it took (the paper's saturation velocity, in joint angle); a
  motion that stalls short of its target counts 0;
- ``peak_pressure`` [Pa]: the largest load pressure |p| of the motion;
- ``pump_flow`` [m³/s]: piston area × saturation velocity of the jack, the flow the servo
  draws through its open valve at saturation;

one metric of a load case (its *task*: the case's motions one after the other):

- ``energy_per_task`` [J]: the hydraulic energy the supply delivers, p_s·A·|Δx| summed over
  the case's motions (supply pressure times the oil displaced by the jack; leakage and oil
  compression not counted, docs/design.md);

and one of the joint:

- ``stall_mass`` [kg]: the mass in the hand that just stalls the raising arm at the
  horizontal (`hydroarm.batch.saturation.stall_mass`, bisection on simulations).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from ..batch.saturation import hand_load, stall_mass, step_metrics_of
from ..errors import HydroarmError, StabilityError
from ..io.catalog import paper_load
from ..io.schema import parse_load
from ..io.sections import reject_unknown_keys, text_value, unknown_name
from ..io.units import quantity
from ..metrics.step import MetricOptions
from ..model.joint import Load, ServoJoint
from ..model.scenario import DEFAULT_STEP, Scenario, default_duration, saturation_test

# name -> (SI unit, sense of a requirement: "max" = the value must be <= the limit, "min" >=)
METRICS: dict[str, tuple[str, str]] = {
    "time_constant": ("s", "max"),
    "effective_delay": ("s", "max"),
    "stall_mass": ("kg", "min"),
    "saturation_angular_velocity": ("rad/s", "min"),
    "peak_pressure": ("Pa", "max"),
    "pump_flow": ("m^3/s", "max"),
    "energy_per_task": ("J", "max"),
}
# the dimension (hydroarm.io.units.SI_UNITS) of each metric's limit
DIMENSIONS = {
    "time_constant": "time",
    "effective_delay": "time",
    "stall_mass": "mass",
    "saturation_angular_velocity": "angular_velocity",
    "peak_pressure": "pressure",
    "pump_flow": "flow",
    "energy_per_task": "energy",
}
JOINT_METRICS = ("stall_mass",)  # one value per joint, under the key (None, None)
TASK_METRICS = ("energy_per_task",)  # one value per load case, under (case, None)
MOTION_METRICS = tuple(m for m in METRICS if m not in JOINT_METRICS + TASK_METRICS)
DIRECTIONS = ("raise", "lower")
DEAD_TIME_THRESHOLD = 0.01  # dead time: time to move 1 % of the full valve opening
_COMPARISON = re.compile(r"^\s*(<=|>=|≤|≥|<|>)?\s*(.*)$", re.S)
_SENSE = {"<=": "max", "<": "max", "≤": "max", ">=": "min", ">": "min", "≥": "min"}


@dataclass(frozen=True)
class LoadCase:
    """A load the joint moves in its saturation tests, in the given directions."""

    name: str
    load: Load
    directions: tuple[str, ...] = DIRECTIONS


@dataclass(frozen=True)
class Requirement:
    """``metric`` must stay at most (``sense`` "max") or at least ("min") ``limit`` [SI
    unit of `METRICS`] in every load case of ``cases`` (None: all of them)."""

    metric: str
    limit: float
    sense: str
    cases: tuple[str, ...] | None = None
    label: str = ""

    def __post_init__(self):
        if self.metric not in METRICS:
            raise unknown_name("requirements", "metric", self.metric, METRICS)
        if self.sense not in ("max", "min"):
            raise HydroarmError(f"requirements.{self.metric}", "sense must be 'max' or 'min'")
        if not self.label:
            cmp = "<=" if self.sense == "max" else ">="
            object.__setattr__(self, "label", f"{self.metric} {cmp} {self.limit:g} {self.unit}")

    @property
    def unit(self) -> str:
        return METRICS[self.metric][0]

    def met_by(self, value: float) -> bool:
        """Whether ``value`` [SI] meets the requirement (NaN: a failed run, never)."""
        if math.isnan(value):
            return False
        return value <= self.limit if self.sense == "max" else value >= self.limit

    def margin(self, value: float) -> float:
        """Signed fraction of the limit by which ``value`` meets it (> 0 met, < 0 not):
        (limit − value)/limit for "max", (value − limit)/limit for "min"; −inf for NaN."""
        if math.isnan(value):
            return -math.inf
        d = self.limit - value if self.sense == "max" else value - self.limit
        if self.limit == 0:
            return math.copysign(math.inf, d) if d else 0.0
        return d / abs(self.limit)


# ------------------------------------------------------------------------ reading ---
def _requirement(field: str, metric: str, value, cases=None) -> Requirement:
    if not isinstance(value, str):
        raise HydroarmError(
            field, f'must be a comparison and a limit, e.g. "<= 50 ms", got {value!r}'
        )
    cmp, rest = comparison(field, value)
    sense = _SENSE[cmp] if cmp else METRICS[metric][1]
    limit = quantity(field, rest, DIMENSIONS[metric])
    label = f"{metric} {cmp or ('<=' if sense == 'max' else '>=')} {rest}"
    if cases is not None:
        label += f" ({', '.join(cases)})"
    return Requirement(metric=metric, limit=limit, sense=sense, cases=cases, label=label)


def comparison(field: str, value: str) -> tuple[str | None, str]:
    """(comparison, the rest) of a limit ``"<= 50 ms"``: the comparison ``<=``, ``<``,
    ``>=``, ``>`` (``≤``, ``≥``) or None when the text starts with the quantity."""
    m = _COMPARISON.match(value)
    assert m is not None  # the pattern matches every string
    cmp, rest = m.group(1), m.group(2).strip()
    if rest[:1] in "<>=!≤≥" and rest:
        raise HydroarmError(field, f"{value!r}: the comparison must be <=, <, >= or >")
    return cmp, rest


def sense_of(cmp: str) -> str:
    """ "max" (the value must stay below) for ``<=``, ``<``, ``≤``; "min" for the others."""
    return _SENSE[cmp]


def _case_names(field: str, value) -> tuple[str, ...]:
    if not isinstance(value, list) or not value:
        raise HydroarmError(field, "must be a non-empty list of load case names")
    return tuple(text_value(f"{field}[{i}]", v) for i, v in enumerate(value))


def read_requirements(table: dict, field: str = "requirements") -> tuple[Requirement, ...]:
    """The requirements of a ``[requirements]`` table: ``metric = "<= 50 ms"`` (any unit of
    the metric's dimension: psi, gal/min, lb, ...; without a comparison the metric's usual
    sense), or ``metric = {limit = "<= 50 ms", cases = ["light"]}``, or a list of these."""
    if not isinstance(table, dict):
        raise HydroarmError(field, "must be a table")
    if not table:
        raise HydroarmError(field, "is empty: give at least one requirement")
    out = []
    for metric, value in table.items():
        f = f"{field}.{metric}"
        if metric not in METRICS:
            raise unknown_name(f, "metric", metric, METRICS)
        items = value if isinstance(value, list) else [value]
        if not items:
            raise HydroarmError(f, "is an empty list")
        for i, item in enumerate(items):
            fi = f if not isinstance(value, list) else f"{f}[{i}]"
            if isinstance(item, dict):
                reject_unknown_keys(fi, item, {"limit", "cases"})
                if "limit" not in item:
                    raise HydroarmError(f"{fi}.limit", "is missing")
                cases = _case_names(f"{fi}.cases", item["cases"]) if "cases" in item else None
                if cases is not None and metric in JOINT_METRICS:
                    raise HydroarmError(
                        f"{fi}.cases", f"{metric} is a property of the joint, not of a load case"
                    )
                out.append(_requirement(f"{fi}.limit", metric, item["limit"], cases))
            else:
                out.append(_requirement(fi, metric, item))
    return tuple(out)


def _case_load(field: str, value) -> Load:
    if isinstance(value, bool):
        raise HydroarmError(field, "must be a built-in load number or a table")
    if isinstance(value, int):
        return paper_load(value, field=field)
    if not isinstance(value, dict):
        raise HydroarmError(
            field, 'must be a built-in load number (1..10) or a table ({mass = "1 kg"})'
        )
    if "mass" in value and not ({"arm", "inertia"} & set(value)):
        reject_unknown_keys(field, value, {"mass", "name"})
        m = quantity(f"{field}.mass", value["mass"], "mass", nonnegative=True)
        ld = hand_load(m)
        if "name" in value:
            ld = Load(
                weight=ld.weight,
                arm=ld.arm,
                inertia=ld.inertia,
                name=text_value(f"{field}.name", value["name"]),
            )
        return ld
    return parse_load(field, value)


def read_load_cases(entries: list, field: str = "load_case") -> tuple[LoadCase, ...]:
    """The load cases of a ``[[load_case]]`` array: ``name``; ``load``: a built-in paper
    load number (1–10), ``{mass = "1 kg"}`` (that mass in the hand of the straight arm,
    `hand_load`) or a load table as in scenario files
    (``builtin``, or ``weight``/``mass``, ``arm``, ``inertia``); ``directions`` from
    ``["raise", "lower"]`` (default both)."""
    if not isinstance(entries, list) or not entries:
        raise HydroarmError(field, "give at least one [[load_case]]")
    out: list[LoadCase] = []
    for i, e in enumerate(entries):
        f = f"{field}[{i}]"
        if not isinstance(e, dict):
            raise HydroarmError(f, "must be a table")
        reject_unknown_keys(f, e, {"name", "load", "directions"})
        for k in ("name", "load"):
            if k not in e:
                raise HydroarmError(f"{f}.{k}", "is missing")
        name = text_value(f"{f}.name", e["name"])
        if not name.strip():
            raise HydroarmError(f"{f}.name", "is empty")
        if any(c.name == name for c in out):
            raise HydroarmError(f"{f}.name", f"{name!r} is used by another load case")
        dirs = e.get("directions", list(DIRECTIONS))
        if not isinstance(dirs, list) or not dirs:
            raise HydroarmError(f"{f}.directions", 'must be a non-empty list, e.g. ["raise"]')
        directions = tuple(
            text_value(f"{f}.directions[{k}]", d, DIRECTIONS) for k, d in enumerate(dirs)
        )
        if len(set(directions)) != len(directions):
            raise HydroarmError(f"{f}.directions", "names a direction twice")
        out.append(
            LoadCase(name=name, load=_case_load(f"{f}.load", e["load"]), directions=directions)
        )
    return tuple(out)


def check_cases(
    requirements: Sequence[Requirement], cases: Sequence[LoadCase], field: str = "requirements"
) -> None:
    """Every load case a requirement names exists."""
    names = [c.name for c in cases]
    for r in requirements:
        for c in r.cases or ():
            if c not in names:
                raise unknown_name(f"{field}.{r.metric}.cases", "load case", c, names)


# ----------------------------------------------------------------------- metrics ---
def needed_metrics(requirements: Sequence[Requirement], extra=()) -> tuple[str, ...]:
    """The metrics the requirements (and ``extra`` ones) need, in `METRICS` order."""
    want = {r.metric for r in requirements} | set(extra)
    return tuple(m for m in METRICS if m in want)


def motion_values(joint: ServoJoint, sc: Scenario, m: dict, dead: dict | None) -> dict:
    """The motion metrics [SI] of one saturation test from its step metrics ``m`` (and the
    step metrics at the dead-time threshold, ``dead``); a failed run: all NaN."""
    if m.get("failure") is not None or (dead is not None and dead.get("failure") is not None):
        return dict.fromkeys(MOTION_METRICS, math.nan) | {"travel": math.nan}
    tc = m["time_constant_start"]
    tc = math.inf if math.isnan(tc) else tc
    out = {"time_constant": tc, "peak_pressure": m["peak_pressure"], "travel": m["travel"]}
    out["pump_flow"] = joint.piston_area * abs(m["saturation_velocity"])
    if m["stalled"]:
        out["saturation_angular_velocity"] = 0.0
    else:
        x0 = joint.jack_position(sc.initial_angle)
        lo = 0.5 * (1.0 - sc.metric_options.middle)
        xa = x0 + lo * m["travel"]
        xb = x0 + (1.0 - lo) * m["travel"]
        ta, tb = m["t_middle"]
        swept = abs(joint.joint_angle(xb) - joint.joint_angle(xa))
        out["saturation_angular_velocity"] = swept / (tb - ta) if tb > ta else math.nan
    if dead is not None:
        td = dead["time_constant_start"]
        out["dead_time"] = math.inf if math.isnan(td) else td
        # dead time L plus the 63 % time constant of the motion after it, τ = T' − L: the
        # paper's T' is measured from the lever step, so it holds the dead time already
        # (a first-order-plus-dead-time response reaches 63 % at L + τ)
        out["effective_delay"] = out["dead_time"] + (tc - out["dead_time"])
    return out


STALL_PROBE_DURATION = 2.5  # [s] the stall search's probe (batch.saturation.stall_mass)


def _stall_mass_or_nan(joint: ServoJoint, step: float, keep_failures: bool) -> float:
    # a slow design gets at least the time its own saturation test runs to reach the
    # horizontal, not the 2.5 s that suit the UCL arm (for which both give 2.5 s)
    duration = max(STALL_PROBE_DURATION, motion_duration(joint))
    try:
        return stall_mass(joint, step=step, duration=duration)
    except HydroarmError:
        if keep_failures:
            return math.nan
        raise


def motion_duration(joint: ServoJoint) -> float:
    """Simulated time [s] of the joint's saturation tests here: the default duration of
    [`saturation_test`][hydroarm.saturation_test] (a full-speed motion at half the no-load
    velocity and its settling) rounded up to the grid 2^(k/4) s, so that joints of similar
    speed share one batch (a batch needs one duration) at most 19 % longer; a test depends
    on its joint alone."""
    angle = math.radians(60.0)  # the saturation test's range, θ₂ = −60° … +60°
    d = default_duration(joint, abs(joint.jack_position(angle) - joint.jack_position(-angle)))
    k = math.ceil(4.0 * math.log2(d) - 1e-9)
    return math.ceil(2.0 ** (k / 4.0) * 100.0) / 100.0


def stable_step(
    joint: ServoJoint, cases: Sequence[LoadCase], step: float = DEFAULT_STEP, method: str = "euler"
) -> float:
    """``step`` [s], halved until every saturation test of ``joint`` in ``cases`` is stable
    with it (at most 10 halvings; then the error)."""
    for _ in range(11):
        try:
            for c in cases:
                for d in c.directions:
                    saturation_test(joint, c.load, d, step=step, method=method).check_step()
            return step
        except StabilityError as e:
            step = step / 2.0 ** max(1, math.ceil(math.log2(step / e.largest_stable_step)))
    raise HydroarmError("solver.step", f"no stable step for the joint {joint.name!r}")


def case_metrics(
    joints: Sequence[ServoJoint],
    cases: Sequence[LoadCase],
    *,
    metrics: Sequence[str] | None = None,
    method: str = "euler",
    step: float | Sequence[float] = DEFAULT_STEP,
    keep_failures: bool = False,
    jack_velocity: bool = False,
    grid_durations: bool = False,
) -> list[dict]:
    """The metrics of each joint over the load cases, one dictionary per joint:
    ``{(case, direction): {metric: value}}`` for the motion metrics, ``{(case, None):
    {"energy_per_task": value}}`` for the task metrics and ``{(None, None): {"stall_mass":
    value}}`` for the joint metrics [SI].

    Every joint × case × direction runs in one batch of the batch engine (one per solver
    step when ``step`` differs by joint, one more at the dead-time threshold when
    ``effective_delay`` is wanted); the stall masses are searched two joints at a time.
    ``metrics``: the metrics to compute (default all; the stall mass is the costly one).
    ``keep_failures``: a run that left the physical bounds gives NaN metrics instead of an
    error (a design study's unstable designs). ``jack_velocity``: each motion's dictionary
    also has the jack's ``saturation_velocity`` [m/s] (the batch engine's, the number
    ``hydroarm validate`` reports; the evaluation card shows it beside Table I).
    ``grid_durations``: simulate each joint for `motion_duration` (the default duration
    rounded up to a grid, so that joints of similar speed share a batch: a design study)
    instead of the saturation test's default duration."""
    joints = list(joints)
    want = tuple(METRICS) if metrics is None else tuple(metrics)
    for name in want:
        if name not in METRICS:
            raise unknown_name("metrics", "metric", name, METRICS)
    steps = (
        [float(step)] * len(joints) if isinstance(step, (int, float)) else [float(s) for s in step]
    )
    if len(steps) != len(joints):
        raise HydroarmError("step", "give one step per joint")
    out: list[dict] = [{} for _ in joints]
    motion = [name for name in want if name not in JOINT_METRICS]
    if motion:
        keys = [(j, c, d) for j in range(len(joints)) for c in cases for d in c.directions]
        # the saturation test's default duration, or on the grid (keyword only when given)
        durations = [{"duration": motion_duration(jt)} if grid_durations else {} for jt in joints]
        scs = [
            saturation_test(joints[j], c.load, d, method=method, step=steps[j], **durations[j])
            for j, c, d in keys
        ]
        ms = step_metrics_of(scs, keep_failures=keep_failures)
        dead: list = [None] * len(scs)
        if "effective_delay" in want:
            opts = MetricOptions(threshold=DEAD_TIME_THRESHOLD)
            dead = step_metrics_of(
                [sc.replace(metric_options=opts) for sc in scs], keep_failures=keep_failures
            )
        for (j, c, d), sc, m, dm in zip(keys, scs, ms, dead, strict=True):
            v = motion_values(joints[j], sc, m, dm)
            out[j][(c.name, d)] = {k: v[k] for k in want if k in v} | (
                {"dead_time": v["dead_time"]} if "dead_time" in v else {}
            )
            if jack_velocity and "saturation_velocity" in m:
                out[j][(c.name, d)]["saturation_velocity"] = m["saturation_velocity"]
            if "energy_per_task" in want:
                task = out[j].setdefault((c.name, None), {"energy_per_task": 0.0})
                task["energy_per_task"] += (
                    joints[j].supply_pressure * joints[j].piston_area * abs(v["travel"])
                )
    if "stall_mass" in want:
        with ThreadPoolExecutor(max_workers=2) as pool:
            sms = list(
                pool.map(lambda j, h: _stall_mass_or_nan(j, h, keep_failures), joints, steps)
            )
        for j, sm in enumerate(sms):
            out[j][(None, None)] = {"stall_mass": sm}
    return out


# ------------------------------------------------------------------------ checking ---
def check(requirements: Sequence[Requirement], metrics_of_one_joint: dict) -> list[dict]:
    """One row per requirement and load case (and direction, for a motion metric) it
    covers: ``requirement`` (its label), ``metric``, ``case``, ``direction`` (None for a
    joint or task metric), ``value``, ``limit``, ``unit`` (SI), ``met``, ``margin``
    (`Requirement.margin`: a signed fraction of the limit, > 0 met)."""
    rows = []
    for r in requirements:
        for (case, direction), values in metrics_of_one_joint.items():
            if r.metric not in values:
                continue
            if r.cases is not None and case not in r.cases:
                continue
            v = float(values[r.metric])
            rows.append(
                {
                    "requirement": r.label,
                    "metric": r.metric,
                    "case": case,
                    "direction": direction,
                    "value": v,
                    "limit": r.limit,
                    "unit": r.unit,
                    "met": r.met_by(v),
                    "margin": r.margin(v),
                }
            )
    return rows


def worst(requirement: Requirement, metrics_of_one_joint: dict) -> float:
    """The worst value of the requirement's metric over the cases and directions it covers
    (the largest for a "max" requirement, the smallest for a "min" one; NaN when one run
    failed or none is covered)."""
    vals = [
        float(v[requirement.metric])
        for (case, _), v in metrics_of_one_joint.items()
        if requirement.metric in v and (requirement.cases is None or case in requirement.cases)
    ]
    if not vals or any(math.isnan(v) for v in vals):
        return math.nan
    return max(vals) if requirement.sense == "max" else min(vals)


def margins(requirements: Sequence[Requirement], metrics_of_one_joint: dict) -> list[float]:
    """The smallest margin of each requirement (`Requirement.margin` of `worst`)."""
    return [r.margin(worst(r, metrics_of_one_joint)) for r in requirements]
