"""Whole-arm config files (TOML, a unit on every quantity); see examples/ucl-arm.toml.

Sections: ``[arm]`` (segment geometry and hand payload), ``[power_pack]`` (supply pressure,
pump flow or ``"unlimited"``), ``[joints.<name>]`` (a ``parameter_set`` plus any joint or
physics override, ``angle_offset``, ``own_inertia``), ``[initial]`` (articulation angles),
``[inputs.<name>]`` (``step``/``ramp``/``hold`` in articulation angles) or ``[inputs] csv =``
(lever positions as articulation angles against time for any joints), ``[solver]``.
"""

from __future__ import annotations

import csv
import math
import tomllib
from pathlib import Path

import numpy as np

from ..errors import HydroarmError, check_number
from ..io.schema import (
    _table,
    _unknown,
    build_joint,
    joint_values,
    parameter_set_values,
    read_text_file,
    record_every_value,
)
from ..io.units import quantity
from ..model import lever as inp
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


def _geometry(t: dict) -> ArmGeometry:
    _unknown("arm", t, set(GEOMETRY_KEYS))
    kw = {}
    for k, v in t.items():
        if (
            GEOMETRY_KEYS[k] == "dimensionless"
            and isinstance(v, (int, float))
            and not isinstance(v, bool)
        ):
            kw[k] = check_number(f"arm.{k}", float(v), nonnegative=True)
        else:
            kw[k] = quantity(f"arm.{k}", v, GEOMETRY_KEYS[k], nonnegative=True)
    return ArmGeometry(**kw)


def _pack(t: dict) -> PowerPack:
    _unknown("power_pack", t, {"supply_pressure", "pump_flow"})
    kw = {}
    if "supply_pressure" in t:
        kw["supply_pressure"] = quantity(
            "power_pack.supply_pressure", t["supply_pressure"], "pressure", positive=True
        )
    if "pump_flow" in t:
        v = t["pump_flow"]
        kw["pump_flow"] = (
            math.inf
            if v == "unlimited"
            else quantity("power_pack.pump_flow", v, "flow", positive=True)
        )
    return PowerPack(**kw)


def _joint(name: str, t: dict) -> ArmJoint:
    if name not in JOINT_NAMES:
        raise HydroarmError(f"joints.{name}", f"unknown joint (known: {', '.join(JOINT_NAMES)})")
    t = dict(t)
    extra = {}
    if "angle_offset" in t:
        extra["angle_offset"] = quantity(
            f"joints.{name}.angle_offset", t.pop("angle_offset"), "angle"
        )
    if "own_inertia" in t:
        extra["own_inertia"] = quantity(
            f"joints.{name}.own_inertia", t.pop("own_inertia"), "inertia", nonnegative=True
        )
    vals = joint_values(f"joints.{name}", t)
    base = vals.pop("parameter_set", "ucl-arm-measured")
    values = parameter_set_values(base)
    if "hydraulic_stiffness" in vals and "trapped_volume" not in vals:
        values.pop("trapped_volume")
    values.update(vals)
    values["name"] = name
    return ArmJoint(name=name, servo=build_joint(values, f"joints.{name}"), **extra)


def _angle(field, v) -> float:
    return quantity(field, v, "angle")


def _inputs(doc_inputs: dict, joints, init: dict, base_dir: Path) -> dict:
    out = {}
    csv_levers = {}
    if "csv" in doc_inputs:
        csv_levers = _read_csv(doc_inputs, joints, base_dir)
    for j in joints:
        n = j.name
        if n in csv_levers:
            if n in doc_inputs:
                raise HydroarmError(f"inputs.{n}", "is also a column of inputs.csv")
            out[n] = csv_levers[n]
            continue
        t = _table(f"inputs.{n}", doc_inputs.get(n, {"type": "hold"}))
        kind = t.get("type", "step")
        sec = f"inputs.{n}"
        if kind == "hold":
            _unknown(sec, t, {"type"})
            y = j.lever_for_angle(init[n])
            out[n] = inp.step(y, y, 0.0)
        elif kind == "step":
            _unknown(sec, t, {"type", "to", "at"})
            if "to" not in t:
                raise HydroarmError(f"{sec}.to", "is missing")
            at = quantity(f"{sec}.at", t.get("at", "0 s"), "time", nonnegative=True)
            out[n] = inp.step(
                j.lever_for_angle(init[n]), j.lever_for_angle(_angle(f"{sec}.to", t["to"])), at
            )
        elif kind == "ramp":
            _unknown(sec, t, {"type", "to", "start", "end"})
            for k in ("to", "end"):
                if k not in t:
                    raise HydroarmError(f"{sec}.{k}", "is missing")
            t0 = quantity(f"{sec}.start", t.get("start", "0 s"), "time", nonnegative=True)
            t1 = quantity(f"{sec}.end", t["end"], "time", positive=True)
            if not t1 > t0:
                raise HydroarmError(f"{sec}.end", "must be after start")
            out[n] = inp.ramp(
                j.lever_for_angle(init[n]), j.lever_for_angle(_angle(f"{sec}.to", t["to"])), t0, t1
            )
        else:
            raise HydroarmError(f"{sec}.type", f"must be hold, step or ramp, got {kind!r}")
    return out


def _read_csv(t: dict, joints, base_dir: Path) -> dict:
    """Lever positions (articulation angles in degrees) against time, one column per joint."""
    _unknown("inputs", t, {"csv", "time_column", *JOINT_NAMES})
    path = (base_dir / t["csv"]).resolve()
    if not path.is_file():
        raise HydroarmError("inputs.csv", f"{path} does not exist")
    with open(path, newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    if len(rows) < 2:
        raise HydroarmError("inputs.csv", f"{path.name} has no data rows")
    head = [h.strip() for h in rows[0]]
    tcol = t.get("time_column", "t_s")
    if tcol not in head:
        raise HydroarmError("inputs.csv", f"{path.name} has no column {tcol!r}")
    data = {}
    for k, r in enumerate(rows[1:], start=2):
        try:
            vals = [float(v) for v in r]
        except ValueError:
            raise HydroarmError("inputs.csv", f"{path.name} line {k}: not a number") from None
        if len(vals) != len(head):
            raise HydroarmError(
                "inputs.csv", f"{path.name} line {k}: {len(vals)} values for {len(head)} columns"
            )
        for h, v in zip(head, vals, strict=True):
            data.setdefault(h, []).append(v)
    times = np.array(data[tcol])
    if np.any(np.diff(times) < 0) or not np.all(np.isfinite(times)):
        raise HydroarmError("inputs.csv", f"{path.name}: times must be finite and not decrease")
    out = {}
    for j in joints:
        col = f"{j.name}_deg"
        if col in data:
            ys = [j.lever_for_angle(math.radians(a)) for a in data[col]]
            out[j.name] = inp.LeverInput(times, np.array(ys), description=f"csv:{path.name}")
    unknown = [h for h in head if h != tcol and h[:-4] not in {j.name for j in joints}]
    if unknown:
        raise HydroarmError(
            "inputs.csv",
            f"{path.name}: column {unknown[0]!r} is not <joint>_deg of a joint of this arm",
        )
    return out


def load_arm_text(text: str, base_dir: Path = Path("."), source: str = "arm") -> ArmScenario:
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise HydroarmError(source, f"malformed TOML ({exc})") from None
    _unknown(
        "arm config",
        doc,
        {"name", "description", "arm", "power_pack", "joints", "initial", "inputs", "solver"},
    )
    geometry = _geometry(_table("arm", doc.get("arm", {})))
    pack = _pack(_table("power_pack", doc.get("power_pack", {})))
    jt = _table("joints", doc.get("joints", {}))
    if not jt:
        raise HydroarmError("joints", "section is missing (give at least one joint)")
    joints = tuple(_joint(n, _table(f"joints.{n}", t)) for n, t in jt.items())
    it = _table("initial", doc.get("initial", {}))
    _unknown("initial", it, {j.name for j in joints})
    init = {j.name: _angle(f"initial.{j.name}", it.get(j.name, "0 deg")) for j in joints}
    for j in joints:
        j.servo_angle(init[j.name])  # within reach
    inputs = _inputs(_table("inputs", doc.get("inputs", {})), joints, init, base_dir)
    sol = _table("solver", doc.get("solver", {}))
    _unknown("solver", sol, {"method", "step", "duration", "record_every"})
    kw = {}
    if "method" in sol:
        kw["method"] = sol["method"]
    if "step" in sol:
        kw["step"] = quantity("solver.step", sol["step"], "time", positive=True)
    if "duration" in sol:
        kw["duration"] = quantity("solver.duration", sol["duration"], "time", positive=True)
    if "record_every" in sol:
        kw["record_every"] = record_every_value(sol["record_every"])
    return ArmScenario(
        joints=joints,
        inputs=inputs,
        initial_angles=init,
        geometry=geometry,
        power_pack=pack,
        name=str(doc.get("name", source)),
        **kw,
    )


def load_arm(path) -> ArmScenario:
    """Read a whole-arm TOML config into an :class:`ArmScenario`."""
    text, path = read_text_file(path)
    return load_arm_text(text, path.parent, source=path.name)
