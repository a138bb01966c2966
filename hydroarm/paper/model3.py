"""Model 3 of the paper (Figs. 9 and 10), reconstructed as parameters of the existing equations.

The captions of Figs. 9 and 10 say "Model 3"; the text never defines it. Appendix I lists four
values that the equations of Models 1 and 2 never use: a nominal piston mass m, a viscous
friction f_o, the oil-column stiffness λ_o and the load referred to the jack, M = I·(n/r)².
Eq. (3) is printed "assuming the inertial mass of the piston itself to be negligible"; Model 3
is read as the jack-form equation that drops that assumption::

    (m + M)·s̈ = A·p − f_o·ẋ − F_g,     F_g = W·X·cos(θ₂ − θ_h)·n/r,     s = r·θ₂/n

with eqs. (1), (2), (4) unchanged (λ_o = β·A²/V is already the compressibility of every
parameter set). With the paper's constant torque arm r/n this *is* eq. (3) at the joint with
I = (m + M)·(r/n)² and the existing viscous piston friction option b = f_o (b·ẋ·r/n at the
joint, `hydroarm.core.equations.angular_acceleration`): Model 3 is a joint and a load,
not new equations. Values and the column of the print adopted: ``hydroarm/data/model3.csv``
(`hydroarm.io.catalog.model3_values`); reasons: docs/model.md, "Model 3".
"""

from __future__ import annotations

import math

import numpy as np

from ..io.catalog import model3_values, paper_load
from ..io.report import Block
from ..metrics.step import DEFAULT_METRIC_OPTIONS
from ..model.joint import Load, ServoJoint
from ..model.scenario import saturation_test, simulate

LOADS = (6, 8, 10)  # the loads of Figs. 9 and 10
RISE_FRACTION = DEFAULT_METRIC_OPTIONS.threshold  # the 63 % of the time constants
PROBE_TIME = 0.05  # [s] time at which the two models' transient velocities are compared


def jack_mass(joint: ServoJoint, number: int) -> float:
    """M of load ``number`` referred to the jack [kg]: the printed value (loads 6 and 10), else
    I·(n/r)² with the r the printed values use (0.8 in), the rule that gives both printed ones."""
    v = model3_values()
    if number in v["M"]:
        return v["M"][number]
    return paper_load(number).inertia * (joint.gear_ratio / v["r"]) ** 2


def model3_joint(joint: ServoJoint) -> ServoJoint:
    """``joint`` with Model 3's viscous piston friction f_o [N s/m]."""
    return joint.replace(viscous_friction=model3_values()["f_o"], name=f"{joint.name} model 3")


def model3_load(joint: ServoJoint, number: int) -> Load:
    """Load ``number`` of Appendix I as Model 3 sees it: W and X as printed, inertia
    (m + M)·(r/n)² [kg m²] (the jack mass referred to the joint through the torque arm r/n)."""
    load = paper_load(number)
    mass = model3_values()["m"] + jack_mass(joint, number)
    return Load(
        weight=load.weight,
        arm=load.arm,
        inertia=mass * (joint.crank_radius / joint.gear_ratio) ** 2,
        name=load.name,
    )


def model3_runs(joint: ServoJoint, loads=LOADS, directions=("raise", "lower")) -> dict:
    """Model 3 saturation tests {(load, direction): result} on the Model 2 joint ``joint``."""
    j3 = model3_joint(joint)
    return {
        (k, d): simulate(saturation_test(j3, model3_load(joint, k), d))
        for k in loads
        for d in directions
    }


def transient_features(res) -> dict:
    """What Figs. 9 and 10 show of one run, measured on its trace.

    ``v_probe_mm_s``: |ẋ| at `PROBE_TIME` [mm/s]; ``rise_ms``: the start time constant T',
    the time from the lever step until the jack has moved 63 % of e_o [ms];
    ``v_sat_mm_s``: saturation velocity, middle 80 % [mm/s]; ``tc_end_ms``: end-of-travel
    63 % time constant [ms] (NaN if the run stalled).
    """
    m = res.metric_values()
    v = np.abs(res.xdot)
    t = res.t
    v_sat = m["saturation_velocity"]
    t0 = float(res.scenario.lever.times[0])
    return {
        "v_probe_mm_s": 1e3 * float(np.interp(t0 + PROBE_TIME, t, v)),
        "rise_ms": 1e3 * m["time_constant_start"],
        "v_sat_mm_s": 1e3 * v_sat,
        "tc_end_ms": 1e3 * m["time_constant_end"],
    }


def comparison_rows(model2: dict, model3: dict) -> list[dict]:
    """Model 3 against Model 2 per (load, direction) present in both."""
    rows = []
    for key in sorted(set(model2) & set(model3), key=lambda k: (k[0], k[1] != "raise")):
        a, b = transient_features(model2[key]), transient_features(model3[key])
        row: dict = {"load": key[0], "direction": key[1]}
        for q in a:
            row[f"model2_{q}"] = a[q]
            row[f"model3_{q}"] = b[q]
        row["v_sat_ratio"] = b["v_sat_mm_s"] / a["v_sat_mm_s"]
        row["rise_diff_ms"] = b["rise_ms"] - a["rise_ms"]
        row["v_probe_diff_mm_s"] = b["v_probe_mm_s"] - a["v_probe_mm_s"]
        rows.append(row)
    return rows


def notes(joint: ServoJoint, rows: list[dict]) -> dict:
    """The numbers the Model 3 paragraph of the report quotes."""
    v = model3_values()
    r, n = joint.crank_radius, joint.gear_ratio
    inertia_ratio = [
        model3_load(joint, k).inertia / paper_load(k).inertia
        for k in sorted({x["load"] for x in rows})
    ]
    ratios = [x["v_sat_ratio"] for x in rows]
    rise = [x["rise_diff_ms"] for x in rows]
    return {
        "f_o_N_s_m": v["f_o"],
        "piston_mass_kg": v["m"],
        "jack_mass_kg": {k: jack_mass(joint, k) for k in sorted({x["load"] for x in rows})},
        "model_r_mm": 1e3 * r,
        "jack_mass_r_mm": 1e3 * v["r"],
        "gear_ratio": n,
        "inertia_ratio_min_pct": 100 * (min(inertia_ratio) - 1),
        "inertia_ratio_max_pct": 100 * (max(inertia_ratio) - 1),
        "v_sat_change_min_pct": 100 * (min(ratios) - 1),
        "v_sat_change_max_pct": 100 * (max(ratios) - 1),
        "rise_diff_min_ms": min(rise),
        "rise_diff_max_ms": max(rise),
        "probe_ms": 1e3 * PROBE_TIME,
        "rise_pct": 100 * RISE_FRACTION,
    }


def _fmt(x: float, digits: int = 1) -> str:
    return "–" if not math.isfinite(x) else f"{x:.{digits}f}"


def report_blocks(rows: list[dict], n: dict) -> list[Block]:
    """The Model 3 section of the reproduction report (numbers from ``rows`` and ``n``)."""
    b: list[Block] = [("h", 2, "Figs. 9 and 10 — Model 3 beside Model 2")]
    masses = ", ".join(f"{m:.0f} kg (load {k})" for k, m in n["jack_mass_kg"].items())
    b.append(
        (
            "p",
            "Model 3 is read as Model 2 with the Appendix I values it never uses: viscous "
            f"piston friction f_o = {n['f_o_N_s_m']:.0f} N s/m (the imperial 20.4 lbf s/in; the "
            f"SI print 2.31 is that times the lbf·in→N·m factor), the piston mass m = "
            f"{n['piston_mass_kg']:g} kg, and the loads as the printed jack masses M = {masses}, "
            f"referred to the joint as (m + M)·(r/n)². The printed M use r = "
            f"{n['jack_mass_r_mm']:.2f} mm, the model {n['model_r_mm']:g} mm, so Model 3's "
            f"inertia is {_fmt(-n['inertia_ratio_max_pct'])}–{_fmt(-n['inertia_ratio_min_pct'])} "
            "% below Model 2's. The friction lowers every saturation velocity by "
            f"{_fmt(-n['v_sat_change_max_pct'], 2)}–{_fmt(-n['v_sat_change_min_pct'], 2)} %; the "
            f"start time constant T' (the jack has moved {n['rise_pct']:g} % of e_o) changes by "
            f"{n['rise_diff_min_ms']:+.1f} to {n['rise_diff_max_ms']:+.1f} ms. Dashed lines in "
            "Figs. 9 and 10: Model 2.",
        )
    )
    b.append(
        (
            "table",
            [
                "load",
                "direction",
                f"velocity at {n['probe_ms']:g} ms, mm/s M2",
                "M3",
                "T' ms M2",
                "M3",
                "sat. velocity M2",
                "M3",
                "end T' ms M2",
                "M3",
            ],
            [
                [
                    r["load"],
                    r["direction"],
                    _fmt(r["model2_v_probe_mm_s"], 2),
                    _fmt(r["model3_v_probe_mm_s"], 2),
                    _fmt(r["model2_rise_ms"]),
                    _fmt(r["model3_rise_ms"]),
                    _fmt(r["model2_v_sat_mm_s"], 2),
                    _fmt(r["model3_v_sat_mm_s"], 2),
                    _fmt(r["model2_tc_end_ms"]),
                    _fmt(r["model3_tc_end_ms"]),
                ]
                for r in rows
            ],
        )
    )
    return b
