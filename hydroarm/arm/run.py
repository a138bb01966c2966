"""``hydroarm arm --config FILE --out DIR``: run a whole-arm config and write its outputs.

DIR gets ``joints.csv`` (per-joint angle, rate, pressure, lever, and the supply pressure
against time), ``hand_trajectory.csv`` (elbow, wrist, hand in 3-D), ``joints.png``,
``frames.png`` (stick-figure frames), ``arm.gif`` (animation) and, when a ``validation``
function is given (the CLI passes :func:`hydroarm.paper.arm_validation.validation_rows`),
``arm_validation.csv`` (``quantity,measured,model,rel_error``). Files are staged and moved
into place at the end.
"""

from __future__ import annotations

import math
import shutil
import tempfile
from pathlib import Path

from ..errors import HydroarmError
from ..files import csv_text
from ..plotting import arm as plots
from ..plotting.joint import save_figure
from .config import load_arm
from .model import simulate_arm

OUTPUT_FILES = (
    "joints.csv",
    "hand_trajectory.csv",
    "joints.png",
    "frames.png",
    "arm.gif",
    "arm_validation.csv",
)


def run_arm(config, out_dir, *, progress=None, animation: bool = True, validation=None) -> dict:
    tick = progress or (lambda label: None)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise HydroarmError("--out", f"{out} exists and is not a folder")
    sc = load_arm(config)
    tick(f"simulating {len(sc.joints)} joints for {sc.duration:g} s")
    res = simulate_arm(sc)
    rows = validation(sc, progress=tick) if validation is not None else []
    out.parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=".hydroarm-arm-", dir=out.parent))
    try:
        res.to_csv(stage / "joints.csv", stage / "hand_trajectory.csv")
        names = list(OUTPUT_FILES)
        if validation is not None:
            (stage / "arm_validation.csv").write_text(
                csv_text(["quantity", "measured", "model", "rel_error"], rows)
            )
        else:
            names.remove("arm_validation.csv")
        tick("plots")
        save_figure(plots.fig_joints(res), stage / "joints.png")
        save_figure(plots.fig_frames(res), stage / "frames.png")
        if animation:
            tick("animation")
            plots.save_animation(res, stage / "arm.gif")
        else:
            names.remove("arm.gif")
        out.mkdir(parents=True, exist_ok=True)
        for n in names:
            shutil.move(str(stage / n), str(out / n))
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return {
        "result": res,
        "validation": rows,
        "hand_final_m": res.points()[-1, 2].tolist(),
        "peak_supply_drop_bar": float(
            (sc.power_pack.supply_pressure - res.supply_pressure.min()) * 1e-5
        )
        if math.isfinite(sc.power_pack.pump_flow)
        else 0.0,
    }
