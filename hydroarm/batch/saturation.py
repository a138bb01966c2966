"""Saturation tests of a joint on the batch engine, and the stall-mass search.

`batch_metrics` runs the paper's step-input saturation tests of many joints and loads
on the batch engine (`hydroarm.metrics.online`), grouped into as few batches as their
solver settings allow; `stall_mass` finds by bisection on full simulations the mass in
the hand that stalls the raising arm at the horizontal (the paper's stall test). Used by the
paper's validation (`hydroarm.paper.validation`, which re-exports them) and by the
requirements of `hydroarm.analysis.requirements`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from numba import njit

from ..core.equations import crank_reach, pressure_bound
from ..core.params import STANDARD_GRAVITY as G0
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import in_bounds, step_once
from ..io.catalog import paper_load
from ..metrics.online import scenarios_metrics
from ..model.joint import Load, ServoJoint
from ..model.scenario import Scenario, saturation_test
from .engine import run_scenarios


def hand_distance() -> float:
    """Distance of the hand from the shoulder axis [m] implied by loads 1 and 5."""
    a, b = paper_load(1), paper_load(5)
    return (b.weight * b.arm - a.weight * a.arm) / (b.weight - a.weight)


def hand_load(mass: float, *, distance: float | None = None) -> Load:
    """The straight arm (load 1) with ``mass`` [kg] in the hand [m from the shoulder]."""
    arm = paper_load(1)
    xh = hand_distance() if distance is None else distance
    w = arm.weight + mass * G0
    x = (arm.weight * arm.arm + mass * G0 * xh) / w
    return Load(
        weight=w, arm=x, inertia=arm.inertia + mass * xh**2, name=f"arm + {mass:.3g} kg in the hand"
    )


@njit(cache=True, nogil=True, error_model="numpy")
def _records_above(method, theta0, p0, h, nsteps, every, tab_t, tab_y, sine, J, L, angle):
    """Whether `hydroarm.integrators.fixed.integrate` (t0 = 0, ω0 = 0) keeps a state
    above ``angle`` among its recorded ones (every ``every``-th step): 1 yes, 0 no, −1 the run
    left the physical bounds. The same steps (``step_once``), stopped once decided: at the
    first recorded state above the angle, or at an exact fixed point of the step once the
    lever has settled (from there every state is the same)."""
    theta, omega, p = theta0, 0.0, p0
    if theta > angle:
        return 1
    p_max = pressure_bound(p0, J, L)
    th_max = crank_reach(J)
    settled = tab_t[tab_t.shape[0] - 1]
    last_record = (nsteps // every) * every
    for k in range(1, nsteps + 1):
        t = (k - 1) * h
        th1, om1, p1 = step_once(method, t, h, theta, omega, p, tab_t, tab_y, sine, J, L)
        if not in_bounds(th1, om1, p1, th_max, p_max):
            return -1
        above = th1 > angle
        if above and k % every == 0:
            return 1
        if th1 == theta and om1 == omega and p1 == p and t > settled and sine[0] == 0.0:
            return 1 if above and last_record >= k else 0
        theta, omega, p = th1, om1, p1
    return 0


def _horizontal_probe(joint: ServoJoint, load: Load, duration: float, step: float) -> Scenario:
    return saturation_test(joint, load, "raise", duration=duration, step=step, record_every=20)


def horizontal_probe(
    joint: ServoJoint, load: Load, duration: float = 2.5, step: float = 10e-6
) -> Scenario:
    """The raising saturation test of `reaches_horizontal` (every 20th state kept)."""
    return _horizontal_probe(joint, load, duration, step)


def passes_horizontal(sc: Scenario) -> bool:
    """Does a run of ``sc`` (without the step check) record an angle above the horizontal?"""
    lev = sc.lever
    J, L = sc.params
    r = _records_above(
        registry.method(sc.method).code,
        sc.initial_angle,
        sc.start_pressure(),
        sc.step,
        sc.nsteps,
        sc.record_every,
        lev.times,
        lev.positions,
        lev.sine,
        J,
        L,
        sc.joint.horizontal_angle,
    )
    if r < 0:
        sc.integrate()  # raises the run's error (it left the physical bounds)
    return r > 0


def reaches_horizontal(
    joint: ServoJoint, load: Load, *, duration: float = 2.5, step: float = 10e-6
) -> bool:
    """Does the raising saturation test lift ``load`` past the horizontal?

    The run of ``simulate`` (step checked, every 20th state kept, the largest angle kept
    compared with the horizontal), stopped as soon as the answer is known."""
    sc = _horizontal_probe(joint, load, duration, step)
    sc.check_step()
    return passes_horizontal(sc)


def _bisect(
    passes: Callable[[float], bool], lo: float, hi: float, tol: float
) -> tuple[float, float]:
    """The last bracket [lo, hi] (hi − lo ≤ tol) of a bisection of a decreasing predicate
    (``passes(lo)`` true, ``passes(hi)`` false)."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if passes(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi


def stall_mass(
    joint: ServoJoint,
    *,
    hi: float = 20.0,
    tol: float = 1e-3,
    guess: float | None = None,
    width: float = 0.01,
    **kw,
) -> float:
    """Smallest hand mass [kg] that stalls the raising arm before the horizontal.

    Found by bisection on full simulations of the raising saturation test (the paper's
    stall assessment: "stalled at the horizontal when trying to raise 0.45 kg"); each probe
    stops once it has passed the horizontal or come to rest (`reaches_horizontal`).
    ``guess`` [kg]: search first in guess ± ``width`` (fewer probes, the same answer to
    ``tol``), the whole range 0 … ``hi`` if the stall is not in there.
    """
    duration, step = kw.get("duration", 2.5), kw.get("step", 10e-6)

    def passes(m: float) -> bool:
        return passes_horizontal(_horizontal_probe(joint, hand_load(m), duration, step))

    if guess is not None and math.isfinite(guess) and guess - width > 0:
        a, b = guess - width, guess + width
        if reaches_horizontal(joint, hand_load(a), **kw) and not passes(b):
            a, b = _bisect(passes, a, b, tol)
            return 0.5 * (a + b)
    lo = 0.0
    if not reaches_horizontal(joint, hand_load(lo), **kw):
        return 0.0
    if reaches_horizontal(joint, hand_load(hi), **kw):
        return math.inf
    lo, hi = _bisect(passes, lo, hi, tol)
    return 0.5 * (lo + hi)


def stall_masses(joints, **kw) -> list[float]:
    """`stall_mass` of several joints, each searched in its own thread (the probe
    kernel releases the GIL)."""
    joints = list(joints)
    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(lambda j: stall_mass(j, **kw), joints))


def batch_metrics(scenarios) -> list[dict]:
    """Batch-engine metrics of step-input scenarios (grouped by method, step, duration and
    metric options: one `run_scenarios` per group), in order.

    The step is checked as [`simulate`][hydroarm.simulate] checks it on the
    governing scenario of each joint and motion, the one with the lightest load (the fastest
    mode, `rate_estimate`; the sweep engine's screen),
    and a run that left the physical bounds is an error, as it is for ``simulate``."""
    scs = list(scenarios)
    out: list = [None] * len(scs)
    for idx in _groups(scs):
        for i, m in zip(idx, run_scenarios([scs[i] for i in idx]), strict=True):
            if m["failure"] is not None:
                raise HydroarmError("metrics", f"{scs[i].name}: the run failed ({m['failure']})")
            out[i] = m
    return out


def step_metrics_of(scenarios, *, keep_failures: bool = False) -> list[dict]:
    """`scenarios_metrics` of step-input scenarios, grouped
    and step-checked as `batch_metrics` does, in order: the metrics of
    ``simulate(sc).metric_values()`` (with ``travel`` and the averaging window ``t_middle``), one
    batch per group. ``keep_failures``: a run that left the physical bounds gives
    ``{"failure": reason}`` instead of an error."""
    scs = list(scenarios)
    out: list = [None] * len(scs)
    for idx in _groups(scs):
        ms = scenarios_metrics([scs[i] for i in idx], keep_failures=keep_failures)
        for i, m in zip(idx, ms, strict=True):
            out[i] = m
    return out


def _groups(scs: list) -> list[list[int]]:
    """Indices of the scenarios that can share one batch; the step of each joint and motion
    checked on its governing scenario (raises [`StabilityError`][hydroarm.StabilityError])."""
    groups: dict = {}
    governing: dict = {}
    for i, sc in enumerate(scs):
        motion = (sc.joint, sc.method, sc.step, sc.initial_angle, sc.target)
        g = governing.get(motion)
        if g is None or sc.load.inertia < g.load.inertia:
            governing[motion] = sc
        key = (sc.method, sc.step, sc.nsteps, float(sc.lever.times[0]), sc.metric_options)
        groups.setdefault(key, []).append(i)
    for sc in governing.values():
        sc.check_step()
    return list(groups.values())
