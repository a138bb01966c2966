"""Validation of the shoulder-elevation model against the measured arm.

Puts, quantity by quantity, the measurement, the paper's Model 1 (its physics on the real
loads 1–5), its Model 2 (re-rated loads 6–10, Table III) and hydroarm's physics model side
by side (``hydroarm validate``). Every hydroarm number here comes from a simulation.

The measured data (all from the paper's text and tables, read from
``hydroarm/data/paper/measurements.csv`` and ``table1.csv``, :mod:`hydroarm.paper.data`):

* Table I — saturation velocities of loads 1 and 5, raising and lowering [mm/s];
* stall — 0.45 kg in the hand stalls the arm at the horizontal (5.09 N m at the gearbox);
* no-load time constant — 25, 28, 24, 26 ms (the paper's mean: 25.8 ms);
* friction tests — spring balance at the elbow: 0.7 N m output torque loss; piston rod:
  30 N stiction falling to 18 N Coulomb; Fig. 6: gearbox efficiency 35 % at γ = 50 %.

The hand position: loads 2–5 of Appendix I add 0.113…0.45 kg "in the hand"; loads 1 and 5
put that hand at X_h = (W₅X₅ − W₁X₁)/(W₅ − W₁) = 0.511 m, which with Table II's 5.09 N m
is consistent, while the text's "460 mm (18 in)" is not (it would give 4.81 N m). The tables
are used; docs/physics.md discusses the discrepancy.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from numba import njit

from ..batch.engine import run_scenarios
from ..core.equations import crank_reach, dry_friction_torque, pressure_bound
from ..core.params import STANDARD_GRAVITY as G0
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import in_bounds, step_once
from ..io.catalog import no_load, paper_load
from ..model.joint import Load, ServoJoint
from ..model.scenario import Scenario, saturation_test
from .data import measurement, table1, table3

CELLS = ((1, "raise"), (1, "lower"), (5, "raise"), (5, "lower"))
MODEL2_OF = {1: 6, 5: 10}  # Model 2 re-rates load 1 as load 6 and load 5 as load 10


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
    """Whether :func:`hydroarm.integrators.fixed.integrate` (t0 = 0, ω0 = 0) keeps a state
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


def stall_mass(joint: ServoJoint, *, hi: float = 20.0, tol: float = 1e-3, **kw) -> float:
    """Smallest hand mass [kg] that stalls the raising arm before the horizontal.

    Found by bisection on full simulations of the raising saturation test (the paper's
    stall assessment: "stalled at the horizontal when trying to raise 0.45 kg"); each probe
    stops once it has passed the horizontal or come to rest (:func:`reaches_horizontal`).
    """
    lo = 0.0
    if not reaches_horizontal(joint, hand_load(lo), **kw):
        return 0.0
    if reaches_horizontal(joint, hand_load(hi), **kw):
        return math.inf
    duration, step = kw.get("duration", 2.5), kw.get("step", 10e-6)
    lo, hi = _bisect(
        lambda m: passes_horizontal(_horizontal_probe(joint, hand_load(m), duration, step)),
        lo,
        hi,
        tol,
    )
    return 0.5 * (lo + hi)


def stall_masses(joints, **kw) -> list[float]:
    """:func:`stall_mass` of several joints, each searched in its own thread (the probe
    kernel releases the GIL)."""
    joints = list(joints)
    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(lambda j: stall_mass(j, **kw), joints))


def stall_torque_of_mass(mass: float) -> float:
    ld = hand_load(mass)
    return ld.weight * ld.arm


def velocities(joint: ServoJoint, loads=None, **kw) -> dict:
    """Simulated saturation velocities {(load, direction): mm/s} of the real loads 1 and 5."""
    return velocities_of([joint], loads, **kw)[0]


def batch_metrics(scenarios) -> list[dict]:
    """Batch-engine metrics of step-input scenarios (grouped by method, step, duration and
    metric options: one :func:`~hydroarm.batch.engine.run_scenarios` per group), in order.

    The step is checked as :func:`~hydroarm.model.scenario.simulate` checks it on the
    governing scenario of each joint and motion, the one with the lightest load (the fastest
    mode, :func:`~hydroarm.integrators.stability.rate_estimate`; the sweep engine's screen),
    and a run that left the physical bounds is an error, as it is for ``simulate``."""
    scs = list(scenarios)
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
    out: list = [None] * len(scs)
    for idx in groups.values():
        for i, m in zip(idx, run_scenarios([scs[i] for i in idx]), strict=True):
            if m["failure"] is not None:
                raise HydroarmError("metrics", f"{scs[i].name}: the run failed ({m['failure']})")
            out[i] = m
    return out


def velocities_of(joints, loads=None, **kw) -> list[dict]:
    """:func:`velocities` of several joints, every cell in one run of the batch engine."""
    joints = list(joints)
    keys = [(j, c) for j in range(len(joints)) for c in CELLS]
    scs = [
        saturation_test(joints[j], paper_load(ld) if loads is None else loads[ld], d, **kw)
        for j, (ld, d) in keys
    ]
    out: list[dict] = [{} for _ in joints]
    for (j, c), m in zip(keys, batch_metrics(scs), strict=True):
        out[j][c] = m["saturation_velocity"] * 1e3
    return out


def no_load_time_constant(joint: ServoJoint) -> float:
    """Simulated no-load end-of-travel 63 % time constant [ms], mean of both directions."""
    ms = batch_metrics(saturation_test(joint, no_load(joint), d) for d in ("raise", "lower"))
    return 1e3 * float(np.mean([m["time_constant_end"] for m in ms]))


def friction_torque_unpressurised(joint: ServoJoint) -> float:
    """Friction torque [N m] felt when lifting the unpressurised arm at the horizontal."""
    return float(dry_friction_torque(joint.horizontal_angle, 0.0, False, joint.params()))


def gearbox_loss_for_stall(
    joint: ServoJoint, mass: float | None = None, tol: float = 1e-4
) -> float:
    """Gearbox loss at stall c_stall [-] at which ``mass`` [kg] in the hand just stalls the
    raising arm at the horizontal, found by bisection on simulations (the measured stall:
    ``mass`` defaults to the paper's 0.45 kg)."""
    load = hand_load(measurement("stall_hand_mass_kg") if mass is None else mass)
    lo, hi = 0.0, 0.99
    if not reaches_horizontal(joint.replace(gearbox_loss_at_stall=lo), load):
        return 0.0
    lo, hi = _bisect(
        lambda c: passes_horizontal(
            _horizontal_probe(joint.replace(gearbox_loss_at_stall=c), load, 2.5, 10e-6)
        ),
        lo,
        hi,
        tol,
    )
    return hi


def _rel(model, measured):
    if model is None or measured is None or not np.isfinite(model):
        return float("nan")
    return model / measured - 1.0


def joint_results(joints, progress=None) -> dict:
    """{joint: {"velocities": :func:`velocities`, "stall_mass": :func:`stall_mass`}} of each
    distinct joint: the velocities of all of them in one batch-engine run, the stall masses
    searched side by side (:func:`stall_masses`)."""
    tick = progress or (lambda label: None)
    distinct = list(dict.fromkeys(joints))
    tick("validate: saturation velocities (batch engine)")
    vs = velocities_of(distinct)
    tick("validate: stall masses (bisection on simulations)")
    sms = stall_masses(distinct)
    return {
        j: {"velocities": v, "stall_mass": sm} for j, v, sm in zip(distinct, vs, sms, strict=True)
    }


def validation_rows(
    measured_arm: ServoJoint, paper_joint: ServoJoint, progress=None, results=None
) -> list:
    """Rows ``quantity, measured, paper_model1, paper_model2, hydroarm, rel_error, note``.

    ``results``: :func:`joint_results` of (at least) the two joints, when already computed."""
    tick = progress or (lambda label: None)
    M = measurement
    t1, t3 = table1(), table3()
    res = results or joint_results([measured_arm, paper_joint], progress=progress)
    m1 = res[paper_joint]["velocities"]
    hy = res[measured_arm]["velocities"]
    rows = []

    def add(q, meas, p1, p2, h, note=""):
        rows.append(
            {
                "quantity": q,
                "measured": meas,
                "paper_model1": p1,
                "paper_model2": p2,
                "hydroarm": h,
                "rel_error": _rel(h, meas),
                "note": note,
            }
        )

    for ld, d in CELLS:
        add(
            f"table1_load{ld}_{d}_mm_s",
            t1[(ld, d)],
            m1[(ld, d)],
            t3[(MODEL2_OF[ld], d)],
            hy[(ld, d)],
            f"Table I; Model 2 = Table III load {MODEL2_OF[ld]}",
        )

    def means(v):
        r = 0.5 * (v[(1, "raise")] + v[(5, "raise")])
        lw = 0.5 * (v[(1, "lower")] + v[(5, "lower")])
        return r, lw, lw / r

    m2 = {(ld, d): t3[(MODEL2_OF[ld], d)] for ld, d in CELLS}
    names = ("mean_raise_mm_s", "mean_lower_mm_s", "lower_to_raise_ratio")
    for i, q in enumerate(names):
        add(
            q,
            means(t1)[i],
            means(m1)[i],
            means(m2)[i],
            means(hy)[i],
            f"mean of loads 1 and 5 (the paper: {M('mean_raise_mm_s'):g}, "
            f"{M('mean_lower_mm_s'):g}, +{M('lower_over_raise_pct'):g} %)",
        )
    sm_h = res[measured_arm]["stall_mass"]
    sm_1 = res[paper_joint]["stall_mass"]
    add(
        "stall_mass_kg",
        M("stall_hand_mass_kg"),
        sm_1,
        M("stall_hand_mass_kg"),
        sm_h,
        "hand mass that stalls the raising arm at the horizontal; Model 2: by construction",
    )
    add(
        "stall_torque_Nm",
        M("stall_torque_Nm"),
        stall_torque_of_mass(sm_1),
        M("stall_torque_Nm"),
        stall_torque_of_mass(sm_h),
        f"W·X at the stall mass; the design value is {M('expected_output_torque_Nm'):g} N m",
    )
    tick("validate: no-load time constant")
    add(
        "no_load_time_constant_ms",
        M("no_load_time_constant_ms"),
        M("theory_no_load_time_constant_ms"),
        M("theory_no_load_time_constant_ms"),
        no_load_time_constant(measured_arm),
        "63 % time constant of a no-load step; the paper's models: 'standard formula' "
        f"{M('theory_no_load_time_constant_ms'):g} ms",
    )
    add(
        "spring_balance_friction_Nm",
        M("spring_balance_friction_Nm"),
        0.0,
        0.0,
        friction_torque_unpressurised(measured_arm),
        "unpressurised arm lifted at the horizontal (calibration input)",
    )
    add(
        "piston_coulomb_friction_N",
        M("piston_coulomb_N"),
        0.0,
        0.0,
        measured_arm.coulomb_friction,
        "piston rod test (model input)",
    )
    add(
        "piston_stiction_N",
        M("piston_stiction_N"),
        0.0,
        0.0,
        measured_arm.breakaway_friction,
        "piston rod test (model input)",
    )
    add(
        "gearbox_efficiency_half_stall",
        M("gearbox_efficiency_half_stall"),
        1.0,
        1.0,
        float(
            measured_arm.gearbox_efficiency(
                M("gearbox_efficiency_stall_ratio_pct") / 100, measured_arm.horizontal_angle
            )
        ),
        f"Fig. 6 at γ = {M('gearbox_efficiency_stall_ratio_pct'):g} %; not reconcilable with "
        "the measured stall (docs/physics.md)",
    )
    return rows


def what_if_cases(measured_arm: ServoJoint, supply_pressure: float = 45e5) -> list:
    """(label, joint) of the design what-ifs."""
    return [
        ("as built (ucl-arm-measured)", measured_arm),
        (
            "design gearbox efficiency (no gearbox loss)",
            measured_arm.replace(gearbox_loss_at_stall=0.0, gearbox_friction_torque=0.0),
        ),
        (
            f"supply pressure {supply_pressure / 1e5:g} bar",
            measured_arm.replace(supply_pressure=supply_pressure),
        ),
        (
            f"design gearbox and {supply_pressure / 1e5:g} bar",
            measured_arm.replace(
                gearbox_loss_at_stall=0.0,
                gearbox_friction_torque=0.0,
                supply_pressure=supply_pressure,
            ),
        ),
    ]


def what_if_rows(
    measured_arm: ServoJoint, *, supply_pressure: float = 45e5, progress=None, results=None
) -> list:
    """Design what-ifs: stall mass and Table I velocities with the design gearbox
    (no gearbox losses) and at another supply pressure.

    ``results``: :func:`joint_results` of (at least) the joints of :func:`what_if_cases`."""
    cases = what_if_cases(measured_arm, supply_pressure)
    res = results or joint_results([j for _, j in cases], progress=progress)
    rows = []
    for label, j in cases:
        v = res[j]["velocities"]
        sm = res[j]["stall_mass"]
        rows.append(
            {
                "case": label,
                "supply_pressure_bar": j.supply_pressure / 1e5,
                "stall_mass_kg": sm,
                "stall_torque_Nm": stall_torque_of_mass(sm),
                **{f"load{ld}_{d}_mm_s": v[(ld, d)] for ld, d in CELLS},
            }
        )
    return rows
