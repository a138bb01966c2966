"""``hydroarm arm`` on a mechanism file: any tree of links and joints, driven by circuits or
passive, on the system kernel (issue 30; docs/mechanism.md).

The file is a circuit file with a ``[mechanism]`` section (:mod:`hydroarm.io.circuit`):
its joints are mechanical nodes named after them, the components act on them directly or
through linkages, and a file without components runs the mechanism passive from its
``[initial]`` angles for ``[solver] duration``. Written to the output folder, all at once
(a staging folder moved into place): ``joints.csv`` (every output, each joint's
``<joint>_angle_deg``, ``<joint>_angular_velocity_rad_s``, ``<joint>_torque_n_m`` and the
driving actuator's ``<joint>_pressure_a_bar``, ``_b_bar`` among them), ``energy.csv``
(what each component and the mechanism absorbed), ``joints.png``, ``frames.png`` and
``mechanism.gif``.
"""

from __future__ import annotations

import numpy as np

from ..core.circuit import declare
from ..errors import HydroarmError
from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..io.circuit import load_circuit
from ..model.circuit import build, simulate
from ..plotting import mechanism as plots
from ..plotting.joint import save_figure

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


def run_mechanism(config, out_dir, *, progress=None, animation: bool = True) -> dict:
    """Run a mechanism file and write its outputs (module doc); returns the result, the
    energy account and each joint's final position (SI)."""
    tick = progress or (lambda label: None)
    out = check_output_folder("--out", out_dir)
    circuit = load_circuit(config)
    if circuit.mechanism is None:
        raise HydroarmError("mechanism", "the file has no [mechanism] section")
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
    energy = res.energy()
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
    }
