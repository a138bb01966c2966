"""``hydroarm arm --config FILE --out DIR``: run a whole-arm config and write its outputs.

DIR gets ``joints.csv`` (per-joint angle, rate, pressure, lever, and the supply pressure
against time), ``hand_trajectory.csv`` (elbow, wrist, hand in 3-D), ``joints.png``,
``frames.png`` (stick-figure frames), ``arm.gif`` (animation), ``power.csv``
(``quantity,value,unit,description``: the power pack's energies, and with its efficiencies
and battery the electric energy, energy per task cycle — the run is one cycle — cycles and
run time per charge), ``energy.png`` (cumulative energies) and, when a ``validation``
function is given (the CLI passes `hydroarm.paper.arm_validation.validation_rows`),
``arm_validation.csv`` (``quantity,measured,model,rel_error``) and, when a ``card`` function
is given as well (the CLI passes `hydroarm.paper.arm_card.arm_card`), ``arm_card.csv``
(per joint: speeds and stall) and ``arm_card.png`` (the block-transfer score against
published Box and Block Test scores, `hydroarm.arm.blocks`). Files are staged and moved
into place at the end. The validation's simulations run on a second thread while the
arm runs and its files, figures and animation are written.
"""

from __future__ import annotations

import math
import threading

from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..plotting import arm as plots
from ..plotting.evaluate import fig_block_score
from ..plotting.joint import save_figure
from .blocks import BBT_REFERENCES, card_csv
from .config import load_arm
from .energy import energy_summary, power_traces, summary_rows, traces_with_units
from .model import simulate_arm

OUTPUT_FILES = (
    "joints.csv",
    "hand_trajectory.csv",
    "joints.png",
    "frames.png",
    "arm.gif",
    "power.csv",
    "energy.png",
    "arm_validation.csv",
    "arm_card.csv",
    "arm_card.png",
)


def run_arm(
    config, out_dir, *, progress=None, animation: bool = True, validation=None, card=None
) -> dict:
    tick = progress or (lambda label: None)
    out = check_output_folder("--out", out_dir)
    sc = load_arm(config)
    # the validation's simulations (compiled, releasing the GIL) run on a second thread while
    # this one runs the arm, writes the files and draws the figures and the animation
    box: dict = {}
    worker = None
    if validation is not None:

        def validate() -> None:
            try:
                box["rows"] = validation(sc, progress=tick)
                if card is not None:
                    box["card"] = card(sc, box["rows"], progress=tick)
            except BaseException as exc:  # handed to the caller's thread below
                box["error"] = exc

        worker = threading.Thread(target=validate, name="hydroarm-arm-validation", daemon=True)
        worker.start()
    tick(f"simulating {len(sc.joints)} joints for {sc.duration:g} s")
    try:
        res = simulate_arm(sc)
    except BaseException:
        if worker is not None:
            worker.join()
        raise
    rows: list = []
    traces = power_traces(res)
    energy = energy_summary(res, traces)
    with staging_folder(out) as stage:
        res.to_csv(stage / "joints.csv", stage / "hand_trajectory.csv")
        (stage / "power.csv").write_text(
            csv_text(
                ["quantity", "value", "unit", "description"],
                [
                    {"quantity": k, "value": v, "unit": u, "description": d}
                    for k, v, u, d in summary_rows(energy)
                ],
            )
        )
        names = list(OUTPUT_FILES)
        tick("plots")
        save_figure(plots.fig_joints(res), stage / "joints.png")
        save_figure(plots.fig_frames(res), stage / "frames.png")
        save_figure(plots.fig_energy(res, traces_with_units(traces)), stage / "energy.png")
        if animation:
            tick("animation")
            plots.save_animation(res, stage / "arm.gif")
        else:
            names.remove("arm.gif")
        if worker is not None:
            worker.join()
            if "error" in box:
                raise box["error"]
            rows = box["rows"]
            (stage / "arm_validation.csv").write_text(
                csv_text(["quantity", "measured", "model", "rel_error"], rows)
            )
        else:
            names.remove("arm_validation.csv")
        card_result = box.get("card")
        if card_result is not None:
            (stage / "arm_card.csv").write_text(card_csv(card_result))
            save_figure(
                fig_block_score(card_result["score"], BBT_REFERENCES), stage / "arm_card.png"
            )
        else:
            names.remove("arm_card.csv")
            names.remove("arm_card.png")
        move_into(stage, out, names)
    return {
        "result": res,
        "validation": rows,
        "card": box.get("card"),
        "energy": energy,
        "hand_final_m": res.points()[-1, 2].tolist(),
        "peak_supply_drop_bar": float(
            (sc.power_pack.supply_pressure - res.supply_pressure.min()) * 1e-5
        )
        if math.isfinite(sc.power_pack.pump_flow)
        else 0.0,
    }
