"""``hydroarm validate``: the physics model against the measured arm, side by side.

Writes ``validation.csv`` (columns ``quantity,measured,paper_model1,paper_model2,hydroarm,
rel_error``), ``validation_notes.csv`` (the same rows with a note), ``whatif.csv`` (design
what-ifs), ``leave_one_load_out.csv`` and ``.png`` (the measured arm fitted on one of Table
I's loads, predicting the other: `hydroarm.paper.calibration.leave_one_load_out`),
``validation.png`` and ``fig06_gearbox_efficiency.png``, and a report (``validation.md``,
``validation.html``). Files are staged and moved into place only when everything has been
computed.
"""

from __future__ import annotations

import inspect
from pathlib import Path

from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..io.report import to_html, to_markdown
from ..io.schema import parameter_set
from ..metrics.step import step_metrics
from ..plotting import paper as pl
from ..plotting.joint import save_figure
from .calibration import leave_one_load_out
from .data import measurement
from .labels import label
from .validation import joint_results, validation_rows, what_if_cases, what_if_rows

MEASURED_SET = "ucl-arm-measured"
PAPER_SET = "paper-calibrated"
VALIDATION_COLUMNS = [
    "quantity",
    "measured",
    "paper_model1",
    "paper_model2",
    "hydroarm",
    "rel_error",
]
WHATIF_COLUMNS = [
    "case",
    "supply_pressure_bar",
    "stall_mass_kg",
    "stall_torque_Nm",
    "load1_raise_mm_s",
    "load1_lower_mm_s",
    "load5_raise_mm_s",
    "load5_lower_mm_s",
]
LOO_COLUMNS = [
    "quantity",
    "fitted_on",
    "measured",
    "in_sample",
    "predicted",
    "in_sample_rel_error",
    "predicted_rel_error",
]
OUTPUT_FILES = (
    "validation.csv",
    "validation_notes.csv",
    "whatif.csv",
    "leave_one_load_out.csv",
    "leave_one_load_out.png",
    "validation.png",
    "fig06_gearbox_efficiency.png",
    "validation.md",
    "validation.html",
)


def compute(
    measured_set: str = MEASURED_SET,
    paper_set: str = PAPER_SET,
    progress=None,
    *,
    leave_one_out: bool = True,
):
    """(rows, what-if rows, measured joint, leave-one-load-out rows) of the validation.

    ``leave_one_out=False`` leaves out the two refits of the measured arm (about 7 s of CPU,
    most of it the stall searches of the solved gearbox loss): ``reproduce`` does, so that
    the paper's numbers stay a few seconds away; ``hydroarm validate`` runs them."""
    arm = parameter_set(measured_set)
    paper = parameter_set(paper_set)
    # every joint's velocities and stall mass at once (the batch engine, the stall searches
    # side by side); the "as built" what-if is the measured arm itself
    res = joint_results([arm, paper, *(j for _, j in what_if_cases(arm))], progress=progress)
    rows = validation_rows(arm, paper, progress=progress, results=res)
    whatif = what_if_rows(arm, progress=progress, results=res)
    loo = leave_one_load_out(arm, progress=progress) if leave_one_out else []
    return rows, whatif, arm, loo


def prose_values(rows) -> dict:
    """The numbers the validation report's prose quotes, from ``rows``, the paper's
    measurements (`hydroarm.paper.data`) and the metric's defaults."""
    by = {r["quantity"]: r for r in rows}
    eff = by["gearbox_efficiency_half_stall"]["measured"]
    stall_t = by["stall_torque_Nm"]["measured"]
    design_t = measurement("expected_output_torque_Nm")
    return {
        "efficiency_pct": 100 * eff,
        "efficiency_loss_pct": 100 * (1 - eff),
        "efficiency_stall_ratio_pct": measurement("gearbox_efficiency_stall_ratio_pct"),
        "model_efficiency_pct": 100 * by["gearbox_efficiency_half_stall"]["hydroarm"],
        "stall_torque_Nm": stall_t,
        "design_stall_torque_Nm": design_t,
        "stall_share_of_design_pct": 100 * stall_t / design_t,
        "stall_ratio_at_stall_pct": 100.0,  # γ real of the stall load, by definition
        "middle_pct": 100 * inspect.signature(step_metrics).parameters["middle"].default,
    }


def report_blocks(rows, whatif, arm, fig_prefix: str = "", loo=()) -> list:
    """The validation report; every number of its prose is one of `prose_values`."""
    v = prose_values(rows)
    b = [
        ("h", 2, "Validation: physics model against the measured arm"),
        (
            "p",
            f"hydroarm's physics model (parameter set `{arm.name}`: orifice valve, piston "
            "stiction and Coulomb friction, load-dependent gearbox loss, crank torque arm "
            "r·cos φ/n) with the **real** loads 1 and 5, beside the paper's Model 1 (its "
            "linearised model on the same loads, run by hydroarm), its Model 2 (re-rated loads "
            "6–10, Table III as printed) and the measurement. K and L are fitted to Table I, "
            "the gearbox loss at stall to the stall mass, the gearbox friction to the "
            "spring-balance test; the no-load time constant, the means and their ratio follow. "
            "Equations and sources: docs/physics.md.",
        ),
        (
            "table",
            [
                "quantity",
                "measured",
                "paper Model 1",
                "paper Model 2",
                "hydroarm",
                "hydroarm error",
                "note",
            ],
            [
                [
                    label(r["quantity"]),
                    r["measured"],
                    r["paper_model1"],
                    r["paper_model2"],
                    r["hydroarm"],
                    f"{100 * r['rel_error']:+.1f} %",
                    r["note"],
                ]
                for r in rows
            ],
        ),
        (
            "fig",
            f"{fig_prefix}validation.png",
            "Relative error against the measurement, quantity by quantity",
        ),
        (
            "p",
            f"The Fig. 6 efficiency ({v['efficiency_pct']:.0f} % at γ = "
            f"{v['efficiency_stall_ratio_pct']:g} %) cannot hold together with the measured "
            f"stall: at γ = {v['stall_ratio_at_stall_pct']:g} % the arm still delivers "
            f"{v['stall_torque_Nm']:g} of {v['design_stall_torque_Nm']:g} N m "
            f"(≥ {v['stall_share_of_design_pct']:.0f} %), and Table I's light-load velocities "
            f"leave no room for a {v['efficiency_loss_pct']:.0f} % loss at γ = "
            f"{v['efficiency_stall_ratio_pct']:g} %. hydroarm keeps the stall and the velocities "
            f"and reports the miss (its efficiency there: {v['model_efficiency_pct']:.0f} %).",
        ),
        (
            "fig",
            f"{fig_prefix}fig06_gearbox_efficiency.png",
            "Fig. 6 — gearbox torque efficiency against stall ratio γ, the model's law",
        ),
        ("h", 3, "Design what-if"),
        (
            "table",
            [
                "case",
                "p_s bar",
                "stall mass kg",
                "stall torque N m",
                "load 1 raise",
                "load 1 lower",
                "load 5 raise",
                "load 5 lower",
            ],
            [[w[c] for c in WHATIF_COLUMNS] for w in whatif],
        ),
        (
            "p",
            f"Velocities in mm/s (saturation velocity over the middle {v['middle_pct']:g} % of the "
            "motion, or up to the stall). 'Design gearbox' removes the gearbox friction and load "
            "loss, keeping the piston friction.",
        ),
    ]
    if loo:
        b += loo_blocks(loo, fig_prefix)
    return b


def loo_blocks(loo, fig_prefix: str = "") -> list:
    """Prediction, not only fit: the measured arm fitted on one load, predicting the other."""
    return [
        ("h", 3, "Prediction: fitted on one load, predicting the other"),
        (
            "p",
            "The measured-arm calibration (examples/fit_table1.toml: K and L fitted, the "
            "gearbox loss at stall solved for the stall) refitted on one of Table I's loads "
            "alone, with the stall, then run on the other load: the prediction error beside "
            "the in-sample error of `ucl-arm-measured`, fitted on both loads (docs/fit.md).",
        ),
        (
            "table",
            [
                "quantity",
                "fitted on",
                "measured",
                "in-sample",
                "predicted",
                "in-sample error",
                "prediction error",
            ],
            [
                [
                    label(r["quantity"]),
                    r["fitted_on"],
                    r["measured"],
                    r["in_sample"],
                    r["predicted"],
                    f"{100 * r['in_sample_rel_error']:+.1f} %",
                    f"{100 * r['predicted_rel_error']:+.1f} %",
                ]
                for r in loo
            ],
        ),
        (
            "fig",
            f"{fig_prefix}leave_one_load_out.png",
            "Table I velocities: error in-sample and predicted from the other load",
        ),
    ]


def write(out_dir, rows, whatif, arm, stage_dir=None, loo=()) -> None:
    """Write the validation files into ``stage_dir`` (default: ``out_dir`` directly)."""
    d = Path(stage_dir or out_dir)
    (d / "validation.csv").write_text(csv_text(VALIDATION_COLUMNS, rows))
    (d / "validation_notes.csv").write_text(csv_text(VALIDATION_COLUMNS + ["note"], rows))
    (d / "whatif.csv").write_text(csv_text(WHATIF_COLUMNS, whatif))
    if loo:
        (d / "leave_one_load_out.csv").write_text(csv_text(LOO_COLUMNS, loo))
        save_figure(pl.fig_leave_one_out(loo), d / "leave_one_load_out.png")
    save_figure(pl.fig_validation(rows, name_of=label), d / "validation.png")
    paper_point = (
        measurement("gearbox_efficiency_stall_ratio_pct"),
        100 * measurement("gearbox_efficiency_half_stall"),
    )
    fig6 = pl.fig_gearbox_efficiency(
        arm, paper_point=paper_point, stall_force=1e3 * measurement("theoretical_stall_force_kN")
    )
    save_figure(fig6, d / "fig06_gearbox_efficiency.png")
    blocks = [
        ("h", 1, "hydroarm validation against the UCL arm measurements"),
        *report_blocks(rows, whatif, arm, loo=loo)[1:],
    ]
    (d / "validation.md").write_text(to_markdown(blocks))
    (d / "validation.html").write_text(to_html(blocks, d, "hydroarm validation"))


def validate(out_dir="validation", *, progress=None) -> dict:
    out = check_output_folder("--out", out_dir)
    rows, whatif, arm, loo = compute(progress=progress)
    with staging_folder(out) as stage:
        write(out, rows, whatif, arm, stage, loo)
        move_into(stage, out, OUTPUT_FILES)
    return {"rows": rows, "whatif": whatif, "prose": prose_values(rows), "leave_one_out": loo}
