"""``hydroarm reproduce``: the paper's evaluation end to end — tables, figures, report.

Every number is computed here from the paper's inputs (Appendix I, the loads, the stall
tests); the published values are read from ``hydroarm/data/paper`` only to be compared.
Output files are staged in a temporary folder and moved into place at the end, so a failure
leaves nothing half-written, and only hydroarm's own files in the folder are replaced.
"""

from __future__ import annotations

import json
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..batch.engine import run_scenarios
from ..errors import HydroarmError
from ..files import csv_text
from ..io.catalog import loads_table, paper_load
from ..io.progress import Progress
from ..io.schema import parameter_set
from ..io.units import quantity
from ..model.joint import Load
from ..model.scenario import saturation_test, simulate
from ..plotting import paper as pl
from ..plotting.joint import save_figure
from . import stall
from . import validate as val
from .data import published_table
from .report import to_html, to_markdown
from .stall import G0
from .validation import no_load_time_constant

HAND_DISTANCE = 0.460  # [m] "0.45 Kg mass positioned at 460 mm (18 in)"
ARM_MASS = 1.55  # [kg]
ARM_COM = 0.180  # [m]
STALL_HAND_MASS = 0.45  # [kg]
# Published measurements used as inputs or compared against (text of the paper).
MEASURED = {
    "mean_raise_mm_s": 22.6,
    "mean_lower_mm_s": 34.7,
    "lower_over_raise_pct": 53.5,
    "mean_raise_rad_s": 2.37,
    "mean_lower_rad_s": 3.64,
    "no_load_time_constants_ms": (25.0, 28.0, 24.0, 26.0),
    "no_load_time_constant_ms": 25.8,
    "theory_no_load_time_constant_ms": 23.0,
    "max_loaded_time_constant_ms": 40.0,
}
OUTPUT_FILES = (
    "table2.csv",
    "table3.csv",
    "experiment_comparison.csv",
    "stall_analysis.json",
    "fig07_model1.png",
    "fig08_model2.png",
    "fig09_rising_transients.png",
    "fig10_falling_transients.png",
    "fig11_time_constant_vs_stall_ratio.png",
    "report.md",
    "report.html",
    "validation.csv",
    "validation_notes.csv",
    "whatif.csv",
    "validation.png",
    "fig06_gearbox_efficiency.png",
)


# ------------------------------------------------------------------ computations ---
def _rel(model, ref):
    return (model - ref) / ref


def velocity(joint, load, direction) -> float:
    """Saturation velocity [mm/s] of the paper's test (middle 80 %)."""
    return simulate(saturation_test(joint, load, direction)).metrics()["saturation_velocity"] * 1e3


def table2_rows(joint) -> list[dict]:
    """Table II recomputed from loads 1–5 (W·X) and the theoretical stall torque A·p_s·r/n."""
    loads = [(r["load"], r["W_N"], r["X_mm"] * 1e-3) for r in loads_table() if r["load"] <= 5]
    rows = stall.table2(loads, joint.stall_torque)
    printed = {r["load"]: r for r in published_table("table2")}
    out = []
    for r in rows:
        p = printed[r["load"]]
        d = {"load": r["load"]}
        for c in ("output_torque_Nm", "gamma_theory_pct", "gamma_real_pct"):
            d[c] = r[c]
        for c in ("output_torque_Nm", "gamma_theory_pct", "gamma_real_pct"):
            d[f"paper_{c}"] = p[c]
            d[f"diff_{c}"] = r[c] - p[c]
        out.append(d)
    return out


def table3_rows(joint) -> list[dict]:
    printed = {r["load"]: r for r in published_table("table3")}
    rows = []
    for k in range(6, 11):
        for d in ("raise", "lower"):
            v = velocity(joint, paper_load(k), d)
            pv = printed[k][f"{d}_mm_s"] if k in printed else None
            rows.append(
                {
                    "load": k,
                    "direction": d,
                    "model_mm_s": v,
                    "paper_mm_s": pv,
                    "rel_error": _rel(v, pv) if pv else None,
                }
            )
    return rows


def experiment_rows(joint, printed_joint, t3, sweep, model1=None) -> list[dict]:
    """The paper's own comparisons: Table I vs Model 2, means, ratio, time constants."""
    t1 = {r["load"]: r for r in published_table("table1")}
    m = {(r["load"], r["direction"]): r["model_mm_s"] for r in t3}
    rows = []

    def add(q, measured, model, note=""):
        rows.append(
            {
                "quantity": q,
                "measured": measured,
                "model": model,
                "rel_error": _rel(model, measured),
                "note": note,
            }
        )

    pair = {1: 6, 5: 10}
    for ld in (1, 5):
        for d in ("raise", "lower"):
            add(
                f"table1_load{ld}_{d}_mm_s",
                t1[ld][f"{d}_mm_s"],
                m[(pair[ld], d)],
                f"Table I load {ld} vs Model 2 load {pair[ld]}",
            )
    if model1:
        for ld in (1, 5):
            for d in ("raise", "lower"):
                v = model1[(ld, d)].metrics()["saturation_velocity"] * 1e3
                add(
                    f"model1_load{ld}_{d}_mm_s",
                    t1[ld][f"{d}_mm_s"],
                    v,
                    f"Table I load {ld} vs Model 1 (the real load {ld}, same model)",
                )
    mr = (m[(6, "raise")] + m[(10, "raise")]) / 2
    ml = (m[(6, "lower")] + m[(10, "lower")]) / 2
    add("mean_raise_mm_s", MEASURED["mean_raise_mm_s"], mr, "mean of loads 1 and 5 (6 and 10)")
    add("mean_lower_mm_s", MEASURED["mean_lower_mm_s"], ml, "")
    add(
        "lower_over_raise_pct",
        MEASURED["lower_over_raise_pct"],
        100 * (ml / mr - 1),
        "average lowering speed above raising",
    )
    rad_per_mm = math.radians(120.0) / 20.0  # the paper's conversion: 120° over 20 mm
    add("mean_raise_rad_s", MEASURED["mean_raise_rad_s"], mr * rad_per_mm, "120° per 20 mm")
    add("mean_lower_rad_s", MEASURED["mean_lower_rad_s"], ml * rad_per_mm, "")
    add(
        "no_load_time_constant_ms",
        MEASURED["no_load_time_constant_ms"],
        no_load_time_constant(joint),
        "simulated end-of-travel 63 % constant, no load",
    )
    add(
        "no_load_time_constant_formula_ms",
        MEASURED["theory_no_load_time_constant_ms"],
        printed_joint.no_load_time_constant * 1e3,
        "paper's theory (23 ms) vs A/K_q of the printed parameters",
    )
    worst = float(np.nanmax(np.r_[sweep["tc_raise_ms"], sweep["tc_lower_ms"]]))
    tested = sweep["gamma_pct"] <= 73.0 + 1e-9
    worst_tested = float(
        np.nanmax(np.r_[sweep["tc_raise_ms"][tested], sweep["tc_lower_ms"][tested]])
    )
    add(
        "max_loaded_time_constant_ms",
        MEASURED["max_loaded_time_constant_ms"],
        worst,
        "paper: never above 40 ms; model: largest T' of the sweep up to stall",
    )
    add(
        "max_loaded_time_constant_tested_ms",
        MEASURED["max_loaded_time_constant_ms"],
        worst_tested,
        "model: largest T' up to gamma = 73 %, the heaviest of Fig. 4",
    )
    return rows


def stall_analysis(joint) -> dict:
    """The paper's stall and efficiency arithmetic from its inputs."""
    f_stall = stall.stall_force(joint.piston_area, joint.supply_pressure)
    t_crank = stall.crank_torque(f_stall, joint.crank_radius)
    t_out = stall.output_torque(t_crank, joint.gear_ratio)
    measured_stall = quantity("stall torque", "45.0 lbf*in", "torque")  # "5.09 Nm (45.0 lb in)"
    lost, frac = stall.torque_loss(t_out, measured_stall)
    arm_alone = paper_load(1)
    masses_torque = stall.gravity_torque(ARM_MASS, ARM_COM) + stall.gravity_torque(
        STALL_HAND_MASS, HAND_DISTANCE
    )
    load5 = paper_load(5)
    elbow_needed, elbow_available = 320.0, 440.0
    rerating = []
    printed = {r["load"]: r for r in loads_table()}
    t2 = {r["load"]: r for r in table2_rows(joint)}
    for k in range(1, 6):
        gamma_real = t2[k]["gamma_real_pct"] / 100
        torque = gamma_real * t_out
        m_hand = stall.hand_mass_for_torque(torque, arm_alone.gravity_torque, HAND_DISTANCE)
        w = arm_alone.weight + m_hand * G0
        x = torque / w
        pr = printed[k + 5]
        pwx = pr["W_N"] * pr["X_mm"] * 1e-3
        rerating.append(
            {
                "from_load": k,
                "to_load": k + 5,
                "gamma_real_pct": 100 * gamma_real,
                "equivalent_torque_Nm": torque,
                "added_hand_mass_kg": m_hand,
                "weight_N": w,
                "arm_mm": 1e3 * x,
                "printed_weight_N": pr["W_N"],
                "printed_arm_mm": pr["X_mm"],
                "printed_torque_Nm": pwx,
                "torque_rel_diff": (torque - pwx) / pwx,
                "printed_added_mass_distance_mm": 1e3
                * (pwx - arm_alone.gravity_torque)
                / (pr["W_N"] - arm_alone.weight),
            }
        )

    def cmp(value, paper, unit, digits):
        return {
            "value": value,
            "paper": paper,
            "unit": unit,
            "matches_print": round(value, digits) == round(paper, digits),
        }

    return {
        "source": "UCL hydraulic arm paper, 'Stall Load Tests' and 'Gearbox Efficiency Test'",
        "inputs": {
            "piston_area_mm2": joint.piston_area * 1e6,
            "supply_pressure_bar": joint.supply_pressure * 1e-5,
            "crank_radius_mm": joint.crank_radius * 1e3,
            "gear_ratio": joint.gear_ratio,
            "measured_stall_torque": "45.0 lbf*in (printed 5.09 N m)",
            "arm_mass_kg": ARM_MASS,
            "arm_centre_of_mass_mm": ARM_COM * 1e3,
            "stall_hand_mass_kg": STALL_HAND_MASS,
            "hand_distance_mm": HAND_DISTANCE * 1e3,
        },
        "theoretical_stall_force_kN": cmp(f_stall / 1e3, 0.94, "kN", 2),
        "crank_torque_Nm": cmp(t_crank, 18.8, "N m", 1),
        "expected_output_torque_Nm": cmp(t_out, 9.4, "N m", 1),
        "measured_stall_torque_Nm": {
            **cmp(measured_stall, 5.09, "N m", 2),
            "note": "an input: 45.0 lbf in is 5.084 N m; the paper prints 5.09 (its own "
            "rounding). The loss below uses 45.0 lbf in and matches the printed 4.31",
        },
        "torque_loss_Nm": cmp(lost, 4.31, "N m", 2),
        "torque_loss_pct": cmp(100 * frac, 46.0, "%", 0),
        "stall_torque_checks": {
            "load5_W_times_X_Nm": load5.gravity_torque,
            "arm_plus_hand_mass_Nm": masses_torque,
            "note": "the paper's 5.09 N m is 45.0 lbf in; W·X of load 5 gives 5.04 N m and "
            "1.55 kg at 180 mm plus 0.45 kg at 460 mm gives 4.77 N m",
        },
        "elbow": {
            "force_needed_kN": elbow_needed / 1e3,
            "force_available_kN": elbow_available / 1e3,
            "loss_pct": cmp(100 * (1 - elbow_needed / elbow_available), 30.0, "%", -1),
            "implied_piston_area_mm2": elbow_available / joint.supply_pressure * 1e6,
            "note": "paper: 'a loss of nearly 30 %'",
        },
        "friction": {
            "spring_balance_loss_Nm": 0.7,
            "spring_balance_loss_pct": cmp(100 * 0.7 / t_out, 7.0, "%", 0),
            "piston_stiction_N": 30.0,
            "piston_coulomb_N": 18.0,
            "stiction_pct_of_stall": cmp(100 * 30.0 / f_stall, 3.2, "%", 1),
            "coulomb_pct_of_stall": 100 * 18.0 / f_stall,
        },
        "gearbox_efficiency": {
            "formulas": {
                "input_torque": "T_in = W_in * r * cos(phi)  "
                "(hydroarm.analysis.stall.gearbox_input_torque)",
                "output_torque": "T_out = W * x * sin(theta)  "
                "(hydroarm.analysis.stall.gearbox_output_torque)",
                "efficiency": "eta = n * T_out / T_in, n = 2  "
                "(hydroarm.analysis.stall.gearbox_efficiency)",
                "stall_ratio": "gamma = W_in / 940 N  (hydroarm.analysis.stall.input_stall_ratio)",
            },
            "overall_efficiency_at_stall": measured_stall / t_out,
            "paper_efficiency_at_half_stall": 0.35,
            "note": "Fig. 6 (efficiency against gamma) is lost from the text; only its "
            "35 % at gamma = 50 % survives",
        },
        "rerating_loads_1_5_to_6_10": rerating,
        "rerating_note": "W·X of the re-rated loads matches printed loads 6–10 within "
        f"{100 * max(abs(r['torque_rel_diff']) for r in rerating):.1f} %; "
        "the printed W and X place the added mass at different distances "
        "(printed_added_mass_distance_mm), so only W·X and I are comparable",
    }


def fig11_sweep(joint, n: int = 25) -> dict:
    """Loaded time constant T' against stall ratio γ, from the arm alone (load 1) to stall.

    Run by the batch engine (:mod:`hydroarm.batch`), one batch per direction.

    Mass added in the hand at 460 mm: W = W₁ + m·g, W·X = W₁X₁ + m·g·d, I = I₁ + m·d².
    γ = W·X / (A·p_s·r/n).
    """
    base = paper_load(1)
    m_stall = stall.hand_mass_for_torque(joint.stall_torque, base.gravity_torque, HAND_DISTANCE)
    masses = np.linspace(0.0, m_stall, n)
    out = {
        k: np.empty(n)
        for k in (
            "gamma_pct",
            "tc_raise_ms",
            "tc_lower_ms",
            "v_raise_mm_s",
            "v_lower_mm_s",
            "hand_mass_kg",
        )
    }
    scs = {"raise": [], "lower": []}
    for i, m in enumerate(masses):
        w = base.weight + m * G0
        load = Load(
            weight=w,
            arm=(base.gravity_torque + m * G0 * HAND_DISTANCE) / w,
            inertia=base.inertia + m * HAND_DISTANCE**2,
            name=f"hand {m:.3f} kg",
        )
        out["hand_mass_kg"][i] = m
        out["gamma_pct"][i] = 100 * load.gravity_torque / joint.stall_torque
        for d in ("raise", "lower"):
            scs[d].append(saturation_test(joint, load, d))
    for d in ("raise", "lower"):  # one batch per direction (the batch engine)
        for i, mt in enumerate(run_scenarios(scs[d])):
            out[f"tc_{d}_ms"][i] = 1e3 * mt["time_constant_start"]
            out[f"v_{d}_mm_s"][i] = 1e3 * mt["saturation_velocity"]
    out["no_load_formula_ms"] = joint.no_load_time_constant * 1e3
    out["paper_theory_ms"] = MEASURED["theory_no_load_time_constant_ms"]
    return out


def fig11_statements(sweep) -> list[dict]:
    """The paper's statements about Fig. 11, checked on the sweep."""
    r, lo = sweep["tc_raise_ms"], sweep["tc_lower_ms"]
    grow_r = bool(np.all(np.diff(r) > 0))
    grow_l = bool(np.all(np.diff(lo) > 0))
    rise_r, rise_l = float(r[-1] - r[0]), float(lo[-1] - lo[0])
    g = sweep["gamma_pct"]
    over = g[(r > 40) | (lo > 40)]
    first_over = float(over[0]) if over.size else None
    return [
        {
            "statement": "T' grows with the stall ratio when raising",
            "holds": grow_r,
            "detail": f"{r[0]:.1f} ms at γ = {g[0]:.0f} % to {r[-1]:.1f} ms at {g[-1]:.0f} %",
        },
        {
            "statement": "T' grows with the stall ratio when lowering",
            "holds": grow_l,
            "detail": f"{lo[0]:.1f} ms to {lo[-1]:.1f} ms",
        },
        {
            "statement": "the growth is more marked when raising",
            "holds": rise_r > rise_l,
            "detail": f"raising +{rise_r:.1f} ms, lowering +{rise_l:.1f} ms over the sweep",
        },
        {
            "statement": "no-load time constant ≈ 23 ms (standard formula)",
            "holds": abs(sweep["no_load_formula_ms"] / 23.0 - 1) < 0.03,
            "detail": f"A/K_q = {sweep['no_load_formula_ms']:.1f} ms for this parameter set",
        },
        {
            "statement": "T' below 40 ms even at the heaviest load",
            "holds": first_over is None,
            "detail": "never above 40 ms"
            if first_over is None
            else f"above 40 ms from γ = {first_over:.0f} % (raising); the heaviest load the paper "
            "measured transients at (Fig. 4) was γ = 73 %",
        },
    ]


def runs(joint, loads, directions=("raise", "lower")):
    return {
        (k, d): simulate(saturation_test(joint, paper_load(k), d))
        for k in loads
        for d in directions
    }


# ---------------------------------------------------------------------- writing ---
def _jsonable(o):
    if isinstance(o, dict):
        return {k: _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, (np.floating, float)):
        return None if not math.isfinite(o) else float(o)
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.bool_):
        return bool(o)
    return o


def reproduce(
    out_dir="reproduction",
    *,
    parameter_set_name: str = "paper-calibrated",
    progress: Progress | None = None,
    sweep_points: int = 25,
) -> dict:
    """Run the paper's evaluation and write tables, figures and the report into ``out_dir``.

    Returns a dict of the computed data (tables, sweep, statements).
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise HydroarmError("--out", f"{out} exists and is not a folder")
    prog = progress or Progress(9)
    joint = parameter_set(parameter_set_name)
    printed = parameter_set("paper-printed")

    t2 = table2_rows(printed)
    prog("Table II: stall ratios from loads 1-5")
    t3 = table3_rows(joint)
    prog("Table III: Model 2 saturation velocities (loads 6-10)")
    sweep = fig11_sweep(joint, sweep_points)
    statements = fig11_statements(sweep)
    prog(f"Fig. 11: time constant sweep ({sweep_points} loads x 2 directions)")
    model1 = runs(joint, (1, 5))
    exp = experiment_rows(joint, printed, t3, sweep, model1)
    st = stall_analysis(printed)
    prog("experiment comparison and stall analysis")
    model2 = runs(joint, (6, 10))
    transients = runs(joint, (6, 8, 10))
    prog("Figs. 7-10: Model 1, Model 2 and initial transients")
    vrows, whatif, arm = val.compute()
    prog("validation: physics model against the measured arm, design what-ifs")

    out.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=".hydroarm-reproduce-", dir=out.parent))
    try:
        (stage / "table2.csv").write_text(csv_text(list(t2[0]), t2))
        (stage / "table3.csv").write_text(
            csv_text(["load", "direction", "model_mm_s", "paper_mm_s", "rel_error"], t3)
        )
        (stage / "experiment_comparison.csv").write_text(
            csv_text(["quantity", "measured", "model", "rel_error", "note"], exp)
        )
        (stage / "stall_analysis.json").write_text(json.dumps(_jsonable(st), indent=2) + "\n")
        figs = {
            "fig07_model1.png": pl.fig_model_runs(
                model1, "Fig. 7 — computer simulation, Model 1 (loads 1 and 5)"
            ),
            "fig08_model2.png": pl.fig_model_runs(
                model2, "Fig. 8 — computer simulation, Model 2 (loads 6 and 10)"
            ),
            "fig09_rising_transients.png": pl.fig_transients(
                transients, "raise", joint, "Fig. 9 — initial arm rising transients"
            ),
            "fig10_falling_transients.png": pl.fig_transients(
                transients, "lower", joint, "Fig. 10 — initial arm falling transients"
            ),
            "fig11_time_constant_vs_stall_ratio.png": pl.fig_time_constant_sweep(sweep),
        }
        for name, fig in figs.items():
            save_figure(fig, stage / name)
        val.write(out, vrows, whatif, arm, stage)
        for extra in ("validation.md", "validation.html"):
            (stage / extra).unlink()
        prog("figures")
        blocks = report_blocks(joint, printed, t2, t3, exp, st, sweep, statements)
        blocks += val.report_blocks(vrows, whatif, arm)
        (stage / "report.md").write_text(to_markdown(blocks))
        (stage / "report.html").write_text(to_html(blocks, stage, "hydroarm reproduction"))
        out.mkdir(parents=True, exist_ok=True)
        for name in OUTPUT_FILES:
            shutil.move(str(stage / name), str(out / name))
        prog(f"report written to {out}")
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return {
        "table2": t2,
        "table3": t3,
        "experiment": exp,
        "stall": st,
        "sweep": sweep,
        "statements": statements,
        "model1": model1,
        "model2": model2,
        "transients": transients,
        "validation": vrows,
        "whatif": whatif,
    }


def report_blocks(joint, printed, t2, t3, exp, st, sweep, statements):
    b = []
    b.append(("h", 1, "hydroarm reproduction of the UCL hydraulic arm paper"))
    b.append(
        (
            "p",
            f"Parameter set: `{joint.name}` (Appendix I with K and L fitted to Table "
            "III; see 'Reading of the appendix' below). Method: the paper's rectangular "
            "scheme (semi-implicit Euler, eqs. 5–7), step 10 µs, converged. Every number "
            "below is computed by this run; the paper's values are printed beside it.",
        )
    )
    b.append(("h", 2, "Table III — Model 2 saturation velocity (mm/s)"))
    b.append(
        (
            "table",
            ["load", "direction", "hydroarm", "paper", "difference"],
            [
                [
                    r["load"],
                    r["direction"],
                    r["model_mm_s"],
                    r["paper_mm_s"],
                    "" if r["rel_error"] is None else f"{100 * r['rel_error']:+.1f} %",
                ]
                for r in t3
            ],
        )
    )
    b.append(
        (
            "p",
            "Loads 7–9 have no published value. The agreement is about 1 %, limited "
            "by the model's shape (two fitted parameters, four cells), not by the step.",
        )
    )
    b.append(("h", 2, "Comparison with the experiment (the paper's own comparisons)"))
    b.append(
        (
            "table",
            ["quantity", "measured", "hydroarm", "difference", "note"],
            [
                [
                    r["quantity"],
                    r["measured"],
                    r["model"],
                    f"{100 * r['rel_error']:+.1f} %",
                    r["note"],
                ]
                for r in exp
            ],
        )
    )
    b.append(
        (
            "p",
            "Model 1 rows run the same model with the real loads 1 and 5: its raise/lower "
            "split is far smaller than the arm's, which is why the paper re-rated the loads "
            "(Model 2) to make up for the measured gearbox losses.",
        )
    )
    b.append(("h", 2, "Table II — equivalent arm loadings"))
    b.append(
        (
            "table",
            ["load", "torque N m", "paper", "γ theory %", "paper", "γ real %", "paper"],
            [
                [
                    r["load"],
                    r["output_torque_Nm"],
                    r["paper_output_torque_Nm"],
                    r["gamma_theory_pct"],
                    r["paper_gamma_theory_pct"],
                    r["gamma_real_pct"],
                    r["paper_gamma_real_pct"],
                ]
                for r in t2
            ],
        )
    )
    b.append(
        (
            "p",
            "Torque = W·X of each load; γ theory = torque / (A·p_s·r/n = "
            f"{printed.stall_torque:.3f} N m); γ real = torque / W·X of load 5. The paper's "
            "torque column mixes rounded imperial products and, for load 5, the measured "
            "stall torque 5.09 N m (45.0 lbf in) where W·X gives 5.04 N m; every cell agrees "
            "within 1 %.",
        )
    )
    b.append(("h", 2, "Stall and efficiency arithmetic"))
    rows = []
    for k in (
        "theoretical_stall_force_kN",
        "crank_torque_Nm",
        "expected_output_torque_Nm",
        "measured_stall_torque_Nm",
        "torque_loss_Nm",
        "torque_loss_pct",
    ):
        v = st[k]
        rows.append([k, v["value"], v["paper"], v["unit"], v["matches_print"]])
    for sec, k in (
        ("elbow", "loss_pct"),
        ("friction", "spring_balance_loss_pct"),
        ("friction", "stiction_pct_of_stall"),
    ):
        v = st[sec][k]
        rows.append([f"{sec}.{k}", v["value"], v["paper"], v["unit"], v["matches_print"]])
    b.append(("table", ["quantity", "hydroarm", "paper", "unit", "matches print"], rows))
    b.append(
        (
            "p",
            "The elbow loss computes to 27 % (0.32 kN needed of 0.44 kN), which the "
            "paper calls 'nearly 30 %'. " + st["rerating_note"] + ".",
        )
    )
    b.append(
        (
            "table",
            [
                "load",
                "γ real %",
                "torque N m",
                "printed W·X",
                "hand mass kg",
                "W N",
                "printed W",
                "X mm",
                "printed X",
            ],
            [
                [
                    r["to_load"],
                    r["gamma_real_pct"],
                    r["equivalent_torque_Nm"],
                    r["printed_torque_Nm"],
                    r["added_hand_mass_kg"],
                    r["weight_N"],
                    r["printed_weight_N"],
                    r["arm_mm"],
                    r["printed_arm_mm"],
                ]
                for r in st["rerating_loads_1_5_to_6_10"]
            ],
        )
    )
    b.append(("h", 2, "Figures"))
    b.append(("fig", "fig07_model1.png", "Fig. 7 — Model 1, loads 1 and 5, rising and falling"))
    b.append(("fig", "fig08_model2.png", "Fig. 8 — Model 2, loads 6 and 10"))
    b.append(
        ("fig", "fig09_rising_transients.png", "Fig. 9 — initial rising transients, loads 6, 8, 10")
    )
    b.append(
        (
            "fig",
            "fig10_falling_transients.png",
            "Fig. 10 — initial falling transients, loads 6, 8, 10",
        )
    )
    b.append(
        (
            "fig",
            "fig11_time_constant_vs_stall_ratio.png",
            "Fig. 11 — loaded time constant T' against stall ratio γ",
        )
    )
    b.append(("h", 2, "Fig. 11 — the paper's statements, checked"))
    b.append(
        (
            "table",
            ["statement", "holds in hydroarm", "detail"],
            [[s["statement"], s["holds"], s["detail"]] for s in statements],
        )
    )
    b.append(
        (
            "p",
            "T' is the time from the lever step until the jack velocity reaches 63 % "
            "of its full-valve-opening velocity K_q·e_o/A. With an instantaneous lever step "
            "the unloaded model reaches it almost at once, so the sweep starts near 10 ms "
            "at the arm alone; the no-load 23 ms of the paper is the standard formula A/K_q "
            "(printed parameters), which the model's end-of-travel constant reproduces. "
            "Above γ ≈ 85 % the raising constant exceeds 40 ms because the raising velocity "
            "approaches 63 % of the no-load velocity; the paper's 40 ms is a measurement up "
            "to γ = 73 %, where the model agrees.",
        )
    )
    b.append(("h", 2, "Reading of the appendix, and where hydroarm differs"))
    b.append(
        (
            "p",
            "- The entry printed 'V = 2.9 ltr/min/mm (kN/m²)^-½ (1.34 in³/s lbf^-½)' "
            "is the valve flow coefficient K (its units), imperial value used.\n"
            "- Eq. (1) read as K·√(p_s/2)·e = A·ẋ + 2·L·p + (V/β)·ṗ: gives A/K_q = "
            f"{printed.no_load_time_constant * 1e3:.1f} ms, the paper's 23 ms.\n"
            "- The trapped volume V is not legible: V = β·A²/λ_o with λ_o = 6.4×10⁴ lb/in "
            f"read as the hydraulic stiffness ({printed.trapped_volume * 1e6:.2f} cm³).\n"
            "- Eqs. (5)–(7) as printed are a semi-implicit Euler scheme (pressure, then "
            "velocity, then angle); `euler` implements exactly that.\n"
            "- As printed, the parameters give velocities about 10 % above Table III "
            "(mean 32.1 against 29.2 mm/s) while reproducing the raise/lower split. The "
            "default set fits K (×0.907) and L (487.8 against 475 mm⁵ s⁻¹ N⁻¹) to Table "
            f"III; the fitted K gives A/K_q = {joint.no_load_time_constant * 1e3:.1f} ms, "
            "the measured no-load 25.8 ms, without using it.\n"
            "- The paper's eq. (3) lacks the crank's cos φ torque arm; kept as printed "
            '(option `torque_arm = "kinematic"`).\n'
            "- The linearised valve does not bound the load pressure by the supply: "
            "transient pressures exceed 31 bar, and no load stalls the model before the "
            "theoretical stall torque. Details: docs/model.md.",
        )
    )
    return b
