"""``hydroarm arm``: a mechanism file, or an arm file as its mechanism, on the system kernel
(issues 28 and 30; docs/mechanism.md, docs/arm.md).

A mechanism file is a circuit file with a ``[mechanism]`` section
(`hydroarm.io.circuit`): its joints are mechanical nodes named after them, the components
act on them directly or through linkages, and a file without components runs the
mechanism passive from its ``[initial]`` angles for ``[solver] duration``. Written to the
output folder, all at once (a staging folder moved into place): ``joints.csv`` (every
output, each joint's ``<joint>_angle_deg``, ``<joint>_angular_velocity_rad_s``,
``<joint>_torque_n_m`` and the driving actuator's ``<joint>_pressure_a_bar``, ``_b_bar``
among them), ``energy.csv`` (what each component and the mechanism absorbed),
``joints.png``, ``frames.png`` and ``mechanism.gif``.

An arm file (``[joints.<name>]``: the UCL arm, docs/arm.md) runs as its expansion
(`hydroarm.arm.expand.simulate_arm`: `hydroarm.arm.expand.arm_circuit`, what
``hydroarm expand`` writes, with its energy account) and writes what the arm command
always wrote: ``joints.csv`` (per joint its angle, rate, load pressure, lever, and the
supply pressure against time), ``hand_trajectory.csv`` (elbow, wrist, hand in 3-D),
``joints.png``, ``frames.png`` (stick-figure frames), ``arm.gif`` (animation),
``power.csv`` (``quantity,value,unit,description``: the power pack's energies from the
circuit's energy account, `hydroarm.arm.energy`, and with its efficiencies and battery
the electric energy, energy per task cycle — the run is one cycle — cycles and run time
per charge), ``energy.png`` (cumulative energies), and ``energy.csv`` as a mechanism's.
With a ``validation`` function (the CLI passes
`hydroarm.paper.arm_validation.validation_rows`) its ``arm_validation.csv``
(``quantity,measured,model,rel_error``) is the paper's reported arm quantities from the
validation's protocols run the same way, and with a ``card`` function as well (the CLI
passes `hydroarm.paper.arm_card.arm_card`) ``arm_card.csv`` (per joint: speeds and stall)
and ``arm_card.png`` (the block-transfer score against published Box and Block Test
scores, `hydroarm.arm.blocks`). The validation's simulations run on a second thread
while the arm runs and its files, figures and animation are written.

With a ``mechanism_card`` function (``hydroarm arm --card``; the CLI passes
`hydroarm.analysis.mechanism_card.mechanism_card`) any mechanism file's evaluation card
is written beside: ``card.csv``, ``card.md``, ``card.png`` (docs/evaluate.md "Any mechanism
file").
"""

from __future__ import annotations

import threading

import numpy as np

from ..core.circuit import declare
from ..errors import HydroarmError
from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..io.circuit import load_circuit
from ..io.sections import read_toml_file
from ..model.circuit import build, simulate
from ..plotting import arm as arm_plots
from ..plotting import mechanism as plots
from ..plotting.evaluate import fig_block_score
from ..plotting.joint import save_figure
from .blocks import BBT_REFERENCES, card_csv
from .config import load_arm
from .energy import energy_summary, power_traces, summary_rows, traces_with_units
from .expand import arm_circuit, is_arm_file, simulate_arm, simulate_motion

OUTPUT_FILES = ("joints.csv", "energy.csv", "joints.png", "frames.png", "mechanism.gif")
#: an arm file's (`run_mechanism`): the arm's time series, hand, power pack and animation
ARM_OUTPUT_FILES = (
    "joints.csv",
    "hand_trajectory.csv",
    "energy.csv",
    "power.csv",
    "joints.png",
    "frames.png",
    "energy.png",
    "arm.gif",
)


def joint_pressures(compiled, columns: dict) -> dict:
    """``<joint>_pressure_a_bar`` and ``_b_bar``: the chamber pressures of the cylinder (or
    hydraulic motor) that drives each joint, directly or through a linkage (copies of its
    nodes' pressure columns, named after the joint)."""
    names = list(compiled.mechanical)
    master = {int(sl): int(ma) for sl, ma, _ in compiled.slaves}
    out = {}
    for c, decl in zip(compiled.circuit.components, compiled.decls, strict=True):
        drive = [p for p in decl.ports if p.drives and p.domain in declare.MECHANICAL]
        chambers = [p for p in decl.ports if p.domain == declare.HYDRAULIC and p.compliant]
        if not drive or len(chambers) != 2:
            continue
        node = compiled.mechanical[c.ports[drive[0].name]]
        while node in master:
            node = master[node]
        mech = compiled.mechanism
        if node >= mech.n:
            continue
        for side, port in zip(("a", "b"), chambers, strict=True):
            key = f"{c.ports[port.name]}_pressure_bar"
            if key in columns:
                out[f"{names[node]}_pressure_{side}_bar"] = columns[key]
    return out


def _validate_beside(arm, validation, card, tick) -> tuple[dict, threading.Thread | None]:
    """The validation (and card) of ``arm`` started on a second thread (the system kernel
    releases the GIL): its box gets ``rows``, ``card`` or the ``error`` raised."""
    box: dict = {}
    if arm is None or validation is None:
        return box, None

    def validate() -> None:
        try:
            box["rows"] = validation(arm, progress=tick, simulate=simulate_motion)
            if card is not None:
                box["card"] = card(arm, box["rows"], progress=tick, simulate=simulate_motion)
        except BaseException as exc:  # handed to the caller's thread
            box["error"] = exc

    worker = threading.Thread(target=validate, name="hydroarm-arm-validation", daemon=True)
    worker.start()
    return box, worker


def run_mechanism(
    config,
    out_dir,
    *,
    progress=None,
    animation: bool = True,
    validation=None,
    card=None,
    mechanism_card=None,
) -> dict:
    """Run a mechanism file (or an arm file as its mechanism) and write its outputs (module
    doc); returns the result (the circuit's), the energy account, each joint's final
    position (SI), the validation's rows (None unless an arm file with a ``validation``)
    and the arm's card (None unless an arm file with a ``validation`` and a ``card``), both
    from runs of the arm as its mechanism; for an arm file also ``arm`` (its
    `ArmResult`), ``power`` (the power pack's `energy_summary`) and ``hand_final_m``."""
    tick = progress or (lambda label: None)
    out = check_output_folder("--out", out_dir)
    doc, _ = read_toml_file(config)
    arm = load_arm(config) if is_arm_file(doc) else None
    circuit = load_circuit(config) if arm is None else arm_circuit(arm)
    if circuit.mechanism is None:
        raise HydroarmError("mechanism", "the file has no [mechanism] section")
    if arm is not None:
        arm.check_step()  # before any work, as the run would
    if mechanism_card is not None:
        runs = mechanism_card(circuit, check_only=True)
        if hasattr(progress, "total"):  # the card's runs, at most, in the progress count
            progress.total += runs
    box, worker = _validate_beside(arm, validation, card, tick)
    try:
        moving = sum(j.type != "fixed" for j in circuit.mechanism.joints)
        tick(
            f"simulating {moving} joints and {len(circuit.components)} components for "
            f"{circuit.duration:g} s"
        )
        arm_res = None
        if arm is not None:
            arm_res = simulate_arm(arm, check_stability=False)
            res = arm_res.circuit
            assert res is not None
        else:
            res = simulate(build(circuit))
            if res.bad_step >= 0:
                raise HydroarmError(
                    "solver.step",
                    f"the run left finite numbers at step {res.bad_step} (t = "
                    f"{res.bad_step * circuit.step:.4g} s): take a smaller step",
                )
    except BaseException:
        if worker is not None:
            worker.join()
        raise
    compiled = res.compiled
    mech = compiled.mechanism
    assert mech is not None
    columns = res.columns()
    columns.update(joint_pressures(compiled, columns))
    q = res.states[:, len(compiled.hydraulic) : len(compiled.hydraulic) + mech.n]
    energy = res.component_energies()
    generic = None
    if mechanism_card is not None:
        generic = mechanism_card(circuit, res, progress=tick)
    tick("plots")
    points = plots.stick_points(mech, q)
    parents = plots.stick_parents(mech)
    names = list(OUTPUT_FILES if arm_res is None else ARM_OUTPUT_FILES)
    power = traces = None
    if arm_res is not None:
        traces = power_traces(arm_res)
        power = energy_summary(arm_res)
    with staging_folder(out) as stage:
        (stage / "energy.csv").write_text(
            csv_text(
                ["component", "energy_j"],
                [{"component": k, "energy_j": v} for k, v in energy.items()],
            )
        )
        if arm_res is None:
            import pandas as pd

            (stage / "joints.csv").write_text(
                pd.DataFrame(columns).to_csv(index=False, float_format="%.10g")
            )
            save_figure(plots.fig_joints(res.t, columns, mech.joint_names), stage / "joints.png")
            save_figure(plots.fig_frames(res.t, points, parents), stage / "frames.png")
        else:
            assert power is not None and traces is not None
            arm_res.to_csv(stage / "joints.csv", stage / "hand_trajectory.csv")
            (stage / "power.csv").write_text(
                csv_text(
                    ["quantity", "value", "unit", "description"],
                    [
                        {"quantity": k, "value": v, "unit": u, "description": d}
                        for k, v, u, d in summary_rows(power)
                    ],
                )
            )
            save_figure(arm_plots.fig_joints(arm_res), stage / "joints.png")
            save_figure(arm_plots.fig_frames(arm_res), stage / "frames.png")
            save_figure(
                arm_plots.fig_energy(arm_res, traces_with_units(traces)), stage / "energy.png"
            )
        if generic is not None:
            names += generic.write(stage)
        gif = "mechanism.gif" if arm_res is None else "arm.gif"
        if animation:
            tick("animation")
            if arm_res is None:
                plots.save_animation(res.t, points, parents, stage / gif)
            else:
                arm_plots.save_animation(arm_res, stage / gif)
        else:
            names.remove(gif)
        if worker is not None:
            worker.join()
            if "error" in box:
                raise box["error"]
        rows, card_result = box.get("rows"), box.get("card")
        if rows is not None:
            (stage / "arm_validation.csv").write_text(
                csv_text(["quantity", "measured", "model", "rel_error"], rows)
            )
            names.append("arm_validation.csv")
        if card_result is not None:
            (stage / "arm_card.csv").write_text(card_csv(card_result))
            save_figure(
                fig_block_score(card_result["score"], BBT_REFERENCES), stage / "arm_card.png"
            )
            names += ["arm_card.csv", "arm_card.png"]
        move_into(stage, out, names)
    out_dict = {
        "result": res,
        "energy": energy,
        "joints": mech.joint_names,
        "final": {name: float(q[-1, j]) for j, name in enumerate(mech.joint_names)},
        "end_point_m": np.asarray(points[-1, -1]).tolist(),
        "validation": rows,
        "card": card_result,
        "mechanism_card": generic,
        "files": names,
        "arm": arm_res,
        "power": power,
        "hand_final_m": None,
    }
    if arm_res is not None:
        out_dict["hand_final_m"] = arm_res.points()[-1, 2].tolist()
    return out_dict
