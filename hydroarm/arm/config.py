"""Whole-arm config files (TOML, a unit on every quantity); see examples/ucl-arm.toml.

Sections: ``[arm]`` (segment geometry and hand payload), ``[power_pack]`` (supply pressure,
pump flow or ``"unlimited"``; the electric side: ``motor_efficiency``, ``pump_efficiency``,
``battery_capacity`` as an energy or a charge, ``battery_voltage`` with a charge,
``usable_fraction``), ``[joints.<name>]`` (a ``parameter_set`` plus any joint or
physics override, ``angle_offset``, ``own_inertia``; a ``[joints.<name>.load]`` table, the
joint file's ``[load]``, for a joint on a test bench driving that fixed load instead of the
arm's pose), ``[initial]`` (articulation angles),
``[inputs.<name>]`` (``step``/``ramp``/``hold`` in articulation angles) or ``[inputs] csv =``
(lever positions as articulation angles against time for any joints), ``[solver]``, and
optionally ``[block_task]`` (the pick and place poses and hand times of the arm card's
block-transfer score, `hydroarm.arm.blocks`).
The section and value readers are those of `hydroarm.io.sections`, shared with scenario
and sweep files.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HydroarmError
from ..files import checked_path
from ..integrators import registry
from ..io.components import actuator_values, valve_values
from ..io.schema import parse_load
from ..io.sections import (
    angle_value,
    as_table,
    check_run_size,
    check_times,
    field_value,
    finite_or_unlimited,
    joint_from_table,
    number_or_quantity,
    optional_table,
    parse_toml,
    ramp_times,
    read_csv_columns,
    read_text_file,
    reject_unknown_keys,
    require_keys,
    solver_values,
    text_value,
    time_value,
    unknown_name,
)
from ..io.units import energy_or_charge, quantity
from ..model import lever as inp
from .blocks import DEFAULT_TASK, BlockTask
from .model import JOINT_NAMES, ArmGeometry, ArmJoint, ArmScenario, PowerPack

GEOMETRY_KEYS = {
    "upper_arm_length": "length",
    "forearm_length": "length",
    "hand_length": "length",
    "upper_arm_mass": "mass",
    "upper_arm_com": "length",
    "forearm_mass": "mass",
    "forearm_com": "length",
    "hand_mass": "mass",
    "reach_shoulder_ratio": "dimensionless",
}
ARM_SECTIONS = {
    "name",
    "description",
    "arm",
    "power_pack",
    "joints",
    "initial",
    "inputs",
    "solver",
    "block_task",
}
BLOCK_TASK_KEYS = {"pick", "place", "grasp_time", "release_time"}
ARM_METHODS = registry.fixed_step_methods()  # the arm kernel steps euler or rk4


def _geometry(t: dict) -> ArmGeometry:
    reject_unknown_keys("arm", t, set(GEOMETRY_KEYS))
    kw = {
        k: number_or_quantity(f"arm.{k}", v, GEOMETRY_KEYS[k], nonnegative=True)
        for k, v in t.items()
    }
    return ArmGeometry(**kw)


PACK_KEYS = {
    "supply_pressure",
    "pump_flow",
    "motor_efficiency",
    "pump_efficiency",
    "battery_capacity",
    "battery_voltage",
    "usable_fraction",
}


def _pack(t: dict) -> PowerPack:
    reject_unknown_keys("power_pack", t, PACK_KEYS)
    kw: dict[str, Any] = {}
    for k in ("motor_efficiency", "pump_efficiency", "usable_fraction"):
        if k in t:
            kw[k] = number_or_quantity(f"power_pack.{k}", t[k], "dimensionless", positive=True)
    if "battery_capacity" in t:
        kind, v = energy_or_charge("power_pack.battery_capacity", t["battery_capacity"])
        kw[f"battery_{kind}"] = v
    if "battery_voltage" in t:
        kw["battery_voltage"] = quantity(
            "power_pack.battery_voltage", t["battery_voltage"], "voltage", positive=True
        )
    if "supply_pressure" in t:
        kw["supply_pressure"] = field_value(
            "power_pack.supply_pressure", "supply_pressure", t["supply_pressure"]
        )
    if "pump_flow" in t:
        kw["pump_flow"] = finite_or_unlimited("power_pack.pump_flow", t["pump_flow"], "flow")
    return PowerPack(**kw)


def _joint(name: str, t: dict, base_dir: Path = Path(".")) -> ArmJoint:
    sec = f"joints.{name}"
    if name not in JOINT_NAMES:
        raise unknown_name(sec, "joint", name, JOINT_NAMES)
    t = dict(t)
    extra: dict[str, Any] = {}
    if "angle_offset" in t:
        extra["angle_offset"] = angle_value(f"{sec}.angle_offset", t.pop("angle_offset"))
    if "own_inertia" in t:
        extra["own_inertia"] = quantity(
            f"{sec}.own_inertia", t.pop("own_inertia"), "inertia", nonnegative=True
        )
    if "load" in t:
        # a fixed load (a joint on a test bench: its own W, X, I instead of the pose's), the
        # joint file's [load] (`hydroarm.io.schema.parse_load`)
        extra["fixed_load"] = parse_load(f"{sec}.load", as_table(f"{sec}.load", t.pop("load")))
    tables = {k: as_table(f"{sec}.{k}", t.pop(k)) for k in COMPONENT_TABLES if k in t}
    servo = joint_from_table(sec, t, default_set="ucl-arm-measured", name=name, base_dir=base_dir)
    if "valve" in tables and "actuator" not in tables:
        raise HydroarmError(
            f"{sec}.valve", "needs an actuator table (a joint built from components)"
        )
    if "actuator" in tables:
        if "piston_area" in t:
            raise HydroarmError(f"{sec}.piston_area", "is the actuator table's (its areas)")
        component = component_values(sec, servo, tables["actuator"], tables.get("valve"))
        servo = servo.replace(piston_area=component["area_a"])
        extra["component"] = component
    return ArmJoint(name=name, servo=servo, **extra)


COMPONENT_TABLES = ("actuator", "valve")


def component_values(sec: str, servo, actuator: dict, valve: dict | None) -> dict:
    """The servo parameters (SI) of a joint's ``[<sec>.actuator]`` and ``[<sec>.valve]``
    tables, read by the component file's readers (`hydroarm.io.components`), its
    errors named ``<sec>.actuator.<key>``. The crank sets the stroke (±r); what the actuator
    table leaves out is the joint's: its bulk modulus, piston friction, internal leakage 2·L
    and each chamber 2·V at mid-stroke (the lumped joint's equivalent, docs/components.md).
    Without a valve table the valve is the joint's own (a zero-lap spool valve with the
    joint's K on each edge and stroke e_o); a valve table's stroke defaults to e_o."""
    r = servo.crank_radius
    a = dict(actuator)
    for k in ("stroke", "stroke_min", "stroke_max"):
        if k in a:
            raise HydroarmError(
                f"{sec}.actuator.{k}", "is set by the joint's crank (±crank_radius)"
            )
    if a.get("type") == "rotary":
        raise HydroarmError(f"{sec}.actuator.type", "a crank joint takes a linear actuator")
    a["stroke_min"], a["stroke_max"] = f"{-r!r} m", f"{r!r} m"
    defaults = {
        "bulk_modulus": f"{servo.bulk_modulus!r} Pa",
        "internal_leakage": f"{2.0 * servo.leakage_coefficient!r} m**3/s/Pa",
        "coulomb_friction": f"{servo.coulomb_friction!r} N",
        "breakaway_friction": f"{servo.breakaway_friction!r} N",
        "viscous_friction": f"{servo.viscous_friction!r} N*s/m",
    }
    for k, v in defaults.items():
        a.setdefault(k, v)
    try:
        if not any(k.startswith(("dead_volume", "line_volume")) for k in actuator):
            # each chamber 2V at mid-stroke: its areas first (a placeholder volume)
            first, _ = actuator_values({**a, "dead_volume": "1 m**3"})
            for side in ("a", "b"):
                v = 2.0 * servo.trapped_volume - first[f"area_{side}"] * r
                if not v > 0.0:
                    raise HydroarmError(
                        "actuator.dead_volume", "is needed (2V is less than the swept volume)"
                    )
                a[f"dead_volume_{side}"] = f"{v!r} m**3"
        values, _ = actuator_values(a)
        if valve is not None:
            vt = dict(valve)
            vt.setdefault("max_stroke", f"{servo.valve_saturation!r} m")
            values.update(valve_values(vt))
    except HydroarmError as exc:
        raise HydroarmError(f"{sec}.{exc.field}", exc.problem) from None
    return values


def _inputs(doc_inputs: dict, joints, init: dict, base_dir: Path) -> dict:
    out = {}
    csv_levers = {}
    names = [j.name for j in joints]
    for k in doc_inputs:
        if k == "time_column" and "csv" not in doc_inputs:
            raise HydroarmError("inputs.time_column", "is only for inputs.csv")
        if k not in names and k not in ("csv", "time_column"):
            raise unknown_name(f"inputs.{k}", "joint", k, names)
    if "csv" in doc_inputs:
        csv_levers = _read_csv(doc_inputs, joints, base_dir)
    for j in joints:
        n = j.name
        if n in csv_levers:
            if n in doc_inputs:
                raise HydroarmError(f"inputs.{n}", "is also a column of inputs.csv")
            out[n] = csv_levers[n]
            continue
        sec = f"inputs.{n}"
        t = as_table(sec, doc_inputs.get(n, {"type": "hold"}))
        kind = t.get("type", "step")
        if kind == "hold":
            reject_unknown_keys(sec, t, {"type"})
            y = j.lever_for_angle(init[n])
            out[n] = inp.step(y, y, 0.0)
        elif kind == "step":
            reject_unknown_keys(sec, t, {"type", "to", "at"})
            require_keys(sec, t, ("to",))
            at = time_value(f"{sec}.at", t.get("at", "0 s"))
            out[n] = inp.step(
                j.lever_for_angle(init[n]), j.lever_for_angle(angle_value(f"{sec}.to", t["to"])), at
            )
        elif kind == "ramp":
            reject_unknown_keys(sec, t, {"type", "to", "start", "end"})
            require_keys(sec, t, ("to", "end"))
            t0, t1 = ramp_times(sec, t)
            y1 = j.lever_for_angle(angle_value(f"{sec}.to", t["to"]))
            out[n] = inp.ramp(j.lever_for_angle(init[n]), y1, t0, t1)
        else:
            raise HydroarmError(f"{sec}.type", f"must be hold, step or ramp, got {kind!r}")
    return out


def _read_csv(t: dict, joints, base_dir: Path) -> dict:
    """Lever positions (articulation angles in degrees) against time, one column per joint."""
    path = checked_path("inputs.csv", text_value("inputs.csv", t["csv"]), base_dir)
    tcol = text_value("inputs.time_column", t.get("time_column", "t_s"))
    data = read_csv_columns("inputs.csv", path)
    if tcol not in data:
        raise HydroarmError(
            "inputs.csv", f"{path.name} has no column {tcol!r} (columns: {', '.join(data)})"
        )
    times = check_times("inputs.csv", path.name, data[tcol])
    names = {j.name for j in joints}
    unknown = [h for h in data if h != tcol and h[:-4] not in names]
    if unknown:
        raise HydroarmError(
            "inputs.csv",
            f"{path.name}: column {unknown[0]!r} is not <joint>_deg of a joint of this arm",
        )
    out = {}
    for j in joints:
        col = f"{j.name}_deg"
        if col in data:
            if not np.all(np.isfinite(data[col])):
                raise HydroarmError("inputs.csv", f"{path.name}: {col} values must be finite")
            ys = [j.lever_for_angle(math.radians(a)) for a in data[col]]
            out[j.name] = inp.LeverInput(times, np.array(ys), description=f"csv:{path.name}")
    return out


def _block_task(t: dict, joints) -> BlockTask | None:
    """The ``[block_task]`` of the arm's card: ``pick`` and ``place`` poses (articulation
    angles of the arm's joints; a joint left out keeps the default task's angle) and the
    stated ``grasp_time`` and ``release_time``; absent: None (the default task)."""
    if not t:
        return None
    reject_unknown_keys("block_task", t, BLOCK_TASK_KEYS)
    names = {j.name for j in joints}
    poses = {}
    for which in ("pick", "place"):
        pose = dict(getattr(DEFAULT_TASK, which))
        given = as_table(f"block_task.{which}", t.get(which, {}))
        reject_unknown_keys(f"block_task.{which}", given, names)
        for k, v in given.items():
            pose[k] = angle_value(f"block_task.{which}.{k}", v)
        poses[which] = pose
    grasp, release = (
        time_value(f"block_task.{k}", t[k]) if k in t else getattr(DEFAULT_TASK, k)
        for k in ("grasp_time", "release_time")
    )
    return BlockTask(
        pick=poses["pick"],
        place=poses["place"],
        grasp_time=grasp,
        release_time=release,
        name="the arm file's [block_task]",
    )


def load_arm_text(text: str, base_dir: Path = Path("."), source: str = "arm") -> ArmScenario:
    doc = parse_toml(text, source)
    reject_unknown_keys("", doc, ARM_SECTIONS)
    geometry = _geometry(optional_table(doc, "arm"))
    pack = _pack(optional_table(doc, "power_pack"))
    jt = optional_table(doc, "joints")
    if not jt:
        raise HydroarmError("joints", "section is missing (give at least one joint)")
    joints = tuple(_joint(n, as_table(f"joints.{n}", t), base_dir) for n, t in jt.items())
    it = optional_table(doc, "initial")
    reject_unknown_keys("initial", it, {j.name for j in joints})
    init = {j.name: angle_value(f"initial.{j.name}", it.get(j.name, "0 deg")) for j in joints}
    for j in joints:
        j.servo_angle(init[j.name])  # within reach
    inputs = _inputs(optional_table(doc, "inputs"), joints, init, base_dir)
    kw = solver_values("solver", optional_table(doc, "solver"), ARM_METHODS)
    task = _block_task(optional_table(doc, "block_task"), joints)
    defaults = {f.name: f.default for f in dataclasses.fields(ArmScenario)}
    check_run_size(*(kw.get(k, defaults[k]) for k in ("duration", "step", "record_every")))
    return ArmScenario(
        joints=joints,
        inputs=inputs,
        initial_angles=init,
        geometry=geometry,
        power_pack=pack,
        name=text_value("name", doc.get("name", source)),
        block_task=task,
        **kw,
    )


def load_arm(path) -> ArmScenario:
    """Read a whole-arm TOML config into an `ArmScenario`."""
    text, path = read_text_file(path)
    return load_arm_text(text, path.parent, source=path.name)
