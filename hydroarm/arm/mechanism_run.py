"""``hydroarm arm`` on a mechanism file: any tree of links and joints, driven by circuits or
passive, on the system kernel (issue 30; docs/mechanism.md).

The file is a circuit file with a ``[mechanism]`` section (`hydroarm.io.circuit`):
its joints are mechanical nodes named after them, the components act on them directly or
through linkages, and a file without components runs the mechanism passive from its
``[initial]`` angles for ``[solver] duration``. Written to the output folder, all at once
(a staging folder moved into place): ``joints.csv`` (every output, each joint's
``<joint>_angle_deg``, ``<joint>_angular_velocity_rad_s``, ``<joint>_torque_n_m`` and the
driving actuator's ``<joint>_pressure_a_bar``, ``_b_bar`` among them), ``energy.csv``
(what each component and the mechanism absorbed), ``joints.png``, ``frames.png`` and
``mechanism.gif``.

An arm file (``[joints.<name>]``: the UCL arm, docs/arm.md) runs as its expansion
(`hydroarm.arm.expand.arm_circuit`, what ``hydroarm expand`` writes), and with a
``validation`` function (the CLI passes
`hydroarm.paper.arm_validation.validation_rows`) its ``arm_validation.csv`` is the
paper's reported arm quantities from the validation's protocols run on the mechanism
(`hydroarm.arm.expand.simulate_expanded`).

With a ``mechanism_card`` function (``hydroarm arm --card``; the CLI passes
`hydroarm.analysis.mechanism_card.mechanism_card`) any mechanism file's evaluation card
is written beside: ``card.csv``, ``card.md``, ``card.png`` (docs/evaluate.md "Any mechanism
file").
"""

from __future__ import annotations

import numpy as np

from ..core.circuit import declare
from ..errors import HydroarmError
from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..io.circuit import load_circuit
from ..io.sections import read_toml_file
from ..model.circuit import build, simulate
from ..plotting import mechanism as plots
from ..plotting.evaluate import fig_block_score
from ..plotting.joint import save_figure
from .blocks import BBT_REFERENCES, card_csv
from .config import load_arm
from .expand import arm_circuit, is_arm_file, simulate_expanded

OUTPUT_FILES = ("joints.csv", "energy.csv", "joints.png", "frames.png", "mechanism.gif")


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
    doc); returns the result, the energy account, each joint's final position (SI), the
    validation's rows (None unless an arm file with a ``validation``) and the arm's card
    (None unless an arm file with a ``validation`` and a ``card``: the CLI passes
    `hydroarm.paper.arm_card.arm_card`; ``arm_card.csv``, ``arm_card.png``), both
    from runs of the arm as its mechanism."""
    tick = progress or (lambda label: None)
    out = check_output_folder("--out", out_dir)
    doc, _ = read_toml_file(config)
    arm = load_arm(config) if is_arm_file(doc) else None
    circuit = load_circuit(config) if arm is None else arm_circuit(arm)
    if circuit.mechanism is None:
        raise HydroarmError("mechanism", "the file has no [mechanism] section")
    if mechanism_card is not None:
        runs = mechanism_card(circuit, check_only=True)
        if hasattr(progress, "total"):  # the card's runs, at most, in the progress count
            progress.total += runs
    compiled = build(circuit)
    mech = compiled.mechanism
    assert mech is not None
    tick(
        f"simulating {mech.n} joints and {len(circuit.components)} components for "
        f"{circuit.duration:g} s"
    )
    res = simulate(compiled)
    if res.bad_step >= 0:
        raise HydroarmError(
            "solver.step",
            f"the run left finite numbers at step {res.bad_step} (t = "
            f"{res.bad_step * circuit.step:.4g} s): take a smaller step",
        )
    columns = res.columns()
    columns.update(joint_pressures(compiled, columns))
    q = res.states[:, len(compiled.hydraulic) : len(compiled.hydraulic) + mech.n]
    energy = res.component_energies()
    rows = card_result = None
    if arm is not None and validation is not None:
        rows = validation(arm, progress=tick, simulate=simulate_expanded)
        if card is not None:
            card_result = card(arm, rows, progress=tick, simulate=simulate_expanded)
    generic = None
    if mechanism_card is not None:
        generic = mechanism_card(circuit, res, progress=tick)
    tick("plots")
    points = plots.stick_points(mech, q)
    parents = plots.stick_parents(mech)
    names = list(OUTPUT_FILES)
    with staging_folder(out) as stage:
        import pandas as pd

        (stage / "joints.csv").write_text(
            pd.DataFrame(columns).to_csv(index=False, float_format="%.10g")
        )
        (stage / "energy.csv").write_text(
            csv_text(
                ["component", "energy_j"],
                [{"component": k, "energy_j": v} for k, v in energy.items()],
            )
        )
        save_figure(plots.fig_joints(res.t, columns, mech.joint_names), stage / "joints.png")
        save_figure(plots.fig_frames(res.t, points, parents), stage / "frames.png")
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
        if generic is not None:
            names += generic.write(stage)
        if animation:
            tick("animation")
            plots.save_animation(res.t, points, parents, stage / "mechanism.gif")
        else:
            names.remove("mechanism.gif")
        move_into(stage, out, names)
    return {
        "result": res,
        "energy": energy,
        "joints": mech.joint_names,
        "final": {name: float(q[-1, j]) for j, name in enumerate(mech.joint_names)},
        "end_point_m": np.asarray(points[-1, -1]).tolist(),
        "validation": rows,
        "card": card_result,
        "mechanism_card": generic,
    }
