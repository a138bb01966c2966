"""Validation of the shoulder-elevation model against the measured arm.

Puts, quantity by quantity, the measurement, the paper's Model 1 (its physics on the real
loads 1–5), its Model 2 (re-rated loads 6–10, Table III) and hydroarm's physics model side
by side (``hydroarm validate``). Every hydroarm number here comes from a simulation.

The measured data (all from the paper's text and tables, read from
``hydroarm/data/paper/measurements.csv`` and ``table1.csv``, `hydroarm.paper.data`):

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

import numpy as np

from ..batch.saturation import (  # noqa: F401 (re-exported: the paper's API)
    _bisect,
    _horizontal_probe,
    _records_above,
    batch_metrics,
    hand_distance,
    hand_load,
    passes_horizontal,
    reaches_horizontal,
    stall_mass,
    stall_masses,
)
from ..core.equations import dry_friction_torque
from ..io.catalog import no_load, paper_load
from ..model.joint import ServoJoint
from ..model.scenario import saturation_test
from .data import measurement, table1, table3

CELLS = ((1, "raise"), (1, "lower"), (5, "raise"), (5, "lower"))
MODEL2_OF = {1: 6, 5: 10}  # Model 2 re-rates load 1 as load 6 and load 5 as load 10


def stall_torque_of_mass(mass: float) -> float:
    ld = hand_load(mass)
    return ld.weight * ld.arm


def velocities(joint: ServoJoint, loads=None, **kw) -> dict:
    """Simulated saturation velocities {(load, direction): mm/s} of the real loads 1 and 5."""
    return velocities_of([joint], loads, **kw)[0]


def velocities_of(joints, loads=None, **kw) -> list[dict]:
    """`velocities` of several joints, every cell in one run of the batch engine."""
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
    """{joint: {"velocities": `velocities`, "stall_mass": `stall_mass`}} of each
    distinct joint: the velocities of all of them in one batch-engine run, the stall masses
    searched side by side (`stall_masses`)."""
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

    ``results``: `joint_results` of (at least) the two joints, when already computed."""
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

    ``results``: `joint_results` of (at least) the joints of `what_if_cases`."""
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
