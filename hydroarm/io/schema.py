"""Scenario files (TOML, a unit on every quantity) and parameter sets.

Units are parsed and converted to SI here, once; unknown keys, wrong dimensions, missing or
negative values are one-line :class:`~hydroarm.errors.HydroarmError` s naming the field.

Example::

    name = "load 6, raising"
    [joint]
    parameter_set = "paper-calibrated"   # the base; any field below overrides it
    supply_pressure = "450 psi"
    [load]
    builtin = 6                          # or weight/arm/inertia with units
    [input]
    type = "step"                        # step | ramp | sine | csv
    direction = "raise"                  # the paper's test: -60 deg -> +60 deg
    [solver]
    method = "euler"
    step = "10 us"
    duration = "1.5 s"
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np

from ..core.params import STANDARD_GRAVITY as G0
from ..errors import HydroarmError, check_number
from ..model import lever as inp
from ..model.joint import Load, ServoJoint
from ..model.scenario import DEFAULT_STEP, Scenario, default_duration
from .catalog import DEFAULT_SET, paper_load, parameter_set_tables
from .units import _parse, length_or_angle, quantity, registry

JOINT_KEYS = {
    "piston_area": "area",
    "flow_coefficient": "flow_coefficient",
    "valve_saturation": "length",
    "leakage_coefficient": "leakage",
    "trapped_volume": "volume",
    "hydraulic_stiffness": "stiffness",
    "bulk_modulus": "pressure",
    "supply_pressure": "pressure",
    "crank_radius": "length",
    "gear_ratio": "dimensionless",
    "horizontal_angle": "angle",
}
JOINT_TEXT_KEYS = {
    "torque_arm",
    "name",
    "parameter_set",
    "description",
    "base",
    "source",
    "valve_model",
}
# physics options (docs/physics.md): in a scenario's [physics] section or a parameter set
PHYSICS_KEYS = {
    "transition_pressure": "pressure",
    "atmospheric_pressure": "pressure",
    "coulomb_friction": "force",
    "static_friction": "force",
    "viscous_friction": "viscous",
    "gearbox_friction_torque": "torque",
    "gearbox_loss_at_stall": "dimensionless",
    "gearbox_loss_exponent": "dimensionless",
    "end_stop_angle": "angle",
    "backlash": "angle",
}
PHYSICS_TEXT_KEYS = {"valve_model", "torque_arm"}


def _unknown(section: str, table: dict, allowed) -> None:
    for k in table:
        if k not in allowed:
            raise HydroarmError(
                f"{section}.{k}", f"unknown key (allowed: {', '.join(sorted(allowed))})"
            )


def _table(section: str, v) -> dict:
    if not isinstance(v, dict):
        raise HydroarmError(section, "must be a table")
    return v


def joint_values(section: str, table: dict) -> dict:
    """Parse joint fields with units into SI floats (no defaults applied)."""
    _unknown(section, table, set(JOINT_KEYS) | JOINT_TEXT_KEYS | set(PHYSICS_KEYS))
    out: dict = {}
    for key, val in table.items():
        field = f"{section}.{key}"
        if key in PHYSICS_KEYS:
            dim = PHYSICS_KEYS[key]
            if (
                dim == "dimensionless"
                and isinstance(val, (int, float))
                and not isinstance(val, bool)
            ):
                out[key] = check_number(field, float(val), nonnegative=True)
            else:
                out[key] = quantity(field, val, dim, nonnegative=True)
        elif key in JOINT_TEXT_KEYS:
            if not isinstance(val, str):
                raise HydroarmError(field, "must be a string")
            out[key] = val
        elif key == "gear_ratio":
            if isinstance(val, (int, float)) and not isinstance(val, bool):
                out[key] = check_number(field, float(val), positive=True)
            else:
                out[key] = quantity(field, val, "dimensionless", positive=True)
        elif key == "leakage_coefficient":
            out[key] = quantity(field, val, JOINT_KEYS[key], nonnegative=True)
        elif key == "horizontal_angle":
            out[key] = quantity(field, val, "angle")
        else:
            out[key] = quantity(field, val, JOINT_KEYS[key], positive=True)
    return out


def build_joint(values: dict, section: str = "joint") -> ServoJoint:
    """ServoJoint from parsed SI values; V may be given as hydraulic stiffness β·A²/V."""
    v = dict(values)
    for k in ("parameter_set", "description", "base", "source"):
        v.pop(k, None)
    lam = v.pop("hydraulic_stiffness", None)
    if lam is not None and "trapped_volume" not in v:  # an explicit volume wins
        try:
            v["trapped_volume"] = v["bulk_modulus"] * v["piston_area"] ** 2 / lam
        except KeyError as exc:
            raise HydroarmError(
                f"{section}.hydraulic_stiffness", f"needs {exc.args[0]} to give the trapped volume"
            ) from None
    required = (
        "piston_area",
        "flow_coefficient",
        "valve_saturation",
        "leakage_coefficient",
        "trapped_volume",
        "bulk_modulus",
        "supply_pressure",
        "crank_radius",
        "gear_ratio",
    )
    for k in required:
        if k not in v:
            raise HydroarmError(f"{section}.{k}", "is missing")
    return ServoJoint(**v)


# ---------------------------------------------------------------- parameter sets ---
def parameter_set_values(name: str) -> dict:
    """SI values of a built-in parameter set (``paper-printed``, ``paper-calibrated``…)."""
    sets = parameter_set_tables()
    if name not in sets:
        raise HydroarmError(
            "joint.parameter_set", f"unknown parameter set {name!r} (known: {', '.join(sets)})"
        )
    raw = dict(sets[name])
    values: dict = {}
    base = raw.get("base")
    if base:
        values.update(parameter_set_values(base))
    mine = joint_values(f"parameter_set.{name}", raw)
    if "trapped_volume" in mine or "hydraulic_stiffness" in mine:
        values.pop("trapped_volume", None)
    values.update(mine)
    values["name"] = name
    # resolve V = β·A²/λ_o once, so that a later override of β or A keeps the set's volume
    lam = values.pop("hydraulic_stiffness", None)
    if lam is not None and "trapped_volume" not in values:
        values["trapped_volume"] = values["bulk_modulus"] * values["piston_area"] ** 2 / lam
    return values


def parameter_set(name: str) -> ServoJoint:
    """The built-in joint ``name`` as a :class:`ServoJoint`."""
    v = parameter_set_values(name)
    return build_joint(v, f"parameter_set.{name}")


def shoulder_elevation(parameter_set_name: str = DEFAULT_SET) -> ServoJoint:
    """The paper's shoulder-elevation joint (a built-in parameter set)."""
    return parameter_set(parameter_set_name)


# ----------------------------------------------------------------------- loads ---
def parse_load(section: str, table: dict) -> Load:
    _unknown(section, table, {"builtin", "weight", "mass", "arm", "inertia", "name"})
    if "builtin" in table:
        extra = set(table) - {"builtin", "name"}
        if extra:
            raise HydroarmError(f"{section}.{sorted(extra)[0]}", "cannot be combined with builtin")
        return paper_load(table["builtin"], field=f"{section}.builtin")
    if "weight" in table and "mass" in table:
        raise HydroarmError(f"{section}.mass", "give weight or mass, not both")
    if "mass" in table:
        w = quantity(f"{section}.mass", table["mass"], "mass", positive=True) * G0
    elif "weight" in table:
        w = weight_quantity(f"{section}.weight", table["weight"])
    else:
        raise HydroarmError(f"{section}.weight", "is missing (or give builtin = 1..10)")
    for k in ("arm", "inertia"):
        if k not in table:
            raise HydroarmError(f"{section}.{k}", "is missing")
    arm = quantity(f"{section}.arm", table["arm"], "length", nonnegative=True)
    inertia = quantity(f"{section}.inertia", table["inertia"], "inertia", positive=True)
    return Load(weight=w, arm=arm, inertia=inertia, name=str(table.get("name", "custom load")))


def weight_quantity(field: str, value) -> float:
    """A load given as a force (N, lbf) or as a mass (kg, lb) under standard gravity."""
    q = _parse(field, value)
    if q.dimensionality == registry().Quantity(1, "kg").dimensionality:
        return quantity(field, value, "mass", positive=True) * G0
    return quantity(field, value, "force", nonnegative=True)


# ---------------------------------------------------------------------- inputs ---
def _position(field, value, joint: ServoJoint) -> float:
    kind, v = length_or_angle(field, value)
    if kind == "angle":
        if abs(v) >= joint.max_angle:
            raise HydroarmError(field, "is beyond the crank's reach")
        return joint.jack_position(v)
    if abs(v) > joint.crank_radius:
        raise HydroarmError(field, "is beyond the crank radius")
    return v


def parse_input(section: str, table: dict, joint: ServoJoint, base_dir: Path):
    """Return (LeverInput, initial angle or None, direction or None)."""
    kind = table.get("type", "step")
    common = {"type"}
    if kind == "step":
        _unknown(section, table, common | {"direction", "from", "to", "at"})
        direction = table.get("direction")
        if direction is not None and direction not in ("raise", "lower"):
            raise HydroarmError(
                f"{section}.direction", f"must be 'raise' or 'lower', got {direction!r}"
            )
        lo, hi = joint.jack_position(math.radians(-60)), joint.jack_position(math.radians(60))
        if direction == "lower":
            lo, hi = hi, lo
        y0 = _position(f"{section}.from", table["from"], joint) if "from" in table else lo
        y1 = _position(f"{section}.to", table["to"], joint) if "to" in table else hi
        if direction is None and ("from" not in table or "to" not in table):
            raise HydroarmError(
                f"{section}.direction", "is missing (give direction, or both from and to)"
            )
        t0 = (
            quantity(f"{section}.at", table["at"], "time", nonnegative=True)
            if "at" in table
            else 0.0
        )
        return inp.step(y0, y1, t0), joint.joint_angle(y0), direction
    if kind == "ramp":
        _unknown(section, table, common | {"from", "to", "start", "end"})
        for k in ("from", "to", "end"):
            if k not in table:
                raise HydroarmError(f"{section}.{k}", "is missing")
        y0 = _position(f"{section}.from", table["from"], joint)
        y1 = _position(f"{section}.to", table["to"], joint)
        t0 = quantity(f"{section}.start", table.get("start", "0 s"), "time", nonnegative=True)
        t1 = quantity(f"{section}.end", table["end"], "time", positive=True)
        if not t1 > t0:
            raise HydroarmError(f"{section}.end", "must be after start")
        return inp.ramp(y0, y1, t0, t1), joint.joint_angle(y0), None
    if kind == "sine":
        _unknown(section, table, common | {"offset", "amplitude", "frequency", "start"})
        for k in ("amplitude", "frequency"):
            if k not in table:
                raise HydroarmError(f"{section}.{k}", "is missing")
        off = _position(f"{section}.offset", table.get("offset", "0 mm"), joint)
        kind_a, amp = length_or_angle(f"{section}.amplitude", table["amplitude"])
        if kind_a == "angle":
            amp = joint.crank_radius * math.sin(amp / joint.gear_ratio)
        f = quantity(f"{section}.frequency", table["frequency"], "frequency", positive=True)
        t0 = quantity(f"{section}.start", table.get("start", "0 s"), "time", nonnegative=True)
        if abs(off) + abs(amp) > joint.crank_radius:
            raise HydroarmError(f"{section}.amplitude", "takes the lever beyond the crank radius")
        return inp.sine(off, amp, f, t0), joint.joint_angle(off), None
    if kind == "csv":
        _unknown(
            section,
            table,
            common | {"file", "time_column", "position_column", "time_unit", "position_unit"},
        )
        if "file" not in table:
            raise HydroarmError(f"{section}.file", "is missing")
        path = (base_dir / table["file"]).resolve()
        lev = read_lever_csv(
            path,
            table.get("time_column", "t"),
            table.get("position_column", "y"),
            table.get("time_unit", "s"),
            table.get("position_unit", "mm"),
            joint,
            f"{section}",
        )
        return lev, joint.joint_angle(float(lev.positions[0])), None
    raise HydroarmError(f"{section}.type", f"must be step, ramp, sine or csv, got {kind!r}")


def read_lever_csv(
    path: Path,
    tcol: str,
    ycol: str,
    tunit: str,
    yunit: str,
    joint: ServoJoint,
    section: str = "input",
):
    """Lever positions against time from a CSV file (columns named in its header)."""
    import csv

    if not path.is_file():
        raise HydroarmError(f"{section}.file", f"{path} does not exist")
    ts = quantity(f"{section}.time_unit", f"1 {tunit}", "time", positive=True)
    kind, ys = length_or_angle(f"{section}.position_unit", f"1 {yunit}")
    t, y = [], []
    with open(path, newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise HydroarmError(f"{section}.file", f"{path.name} is empty")
    header = [h.strip() for h in rows[0]]
    for c in (tcol, ycol):
        if c not in header:
            raise HydroarmError(
                f"{section}.file", f"{path.name} has no column {c!r} (columns: {', '.join(header)})"
            )
    it, iy = header.index(tcol), header.index(ycol)
    for n, r in enumerate(rows[1:], start=2):
        try:
            t.append(float(r[it]) * ts)
            yy = float(r[iy]) * ys
        except (ValueError, IndexError):
            raise HydroarmError(f"{section}.file", f"{path.name} line {n}: not a number") from None
        if kind == "angle":
            yy = joint.jack_position(yy)
        y.append(yy)
    if len(t) < 1:
        raise HydroarmError(f"{section}.file", f"{path.name} has no data rows")
    t_arr, y_arr = np.array(t), np.array(y)
    if np.any(np.diff(t_arr) < 0):
        raise HydroarmError(f"{section}.file", f"{path.name}: times must not decrease")
    if np.any(~np.isfinite(y_arr)) or np.any(~np.isfinite(t_arr)):
        raise HydroarmError(f"{section}.file", f"{path.name}: values must be finite")
    if np.any(np.abs(y_arr) > joint.crank_radius):
        raise HydroarmError(
            f"{section}.file", f"{path.name}: a lever position is beyond the crank radius"
        )
    return inp.LeverInput(t_arr, y_arr, description=f"csv:{path.name}")


# -------------------------------------------------------------------- scenario ---
def load_scenario_text(text: str, base_dir: Path = Path("."), source: str = "scenario"):
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise HydroarmError(source, f"malformed TOML ({exc})") from None
    return scenario_from_doc(doc, base_dir, source)


def scenario_from_doc(doc: dict, base_dir: Path = Path("."), source: str = "scenario"):
    """A :class:`~hydroarm.simulation.Scenario` from a parsed scenario document."""
    _unknown(
        "scenario",
        doc,
        {"name", "joint", "physics", "load", "input", "initial", "solver", "description"},
    )
    jt = _table("joint", doc.get("joint", {}))
    jvals = joint_values("joint", jt)
    phys = _table("physics", doc.get("physics", {}))
    _unknown("physics", phys, set(PHYSICS_KEYS) | PHYSICS_TEXT_KEYS)
    jvals.update(joint_values("physics", phys))
    base = jvals.pop("parameter_set", "paper-calibrated")
    values = parameter_set_values(base)
    if "hydraulic_stiffness" in jvals and "trapped_volume" not in jvals:
        values.pop("trapped_volume")  # the file gives V through the stiffness
    values.update(jvals)
    joint = build_joint(values)
    if "load" not in doc:
        raise HydroarmError("load", "section is missing")
    load = parse_load("load", _table("load", doc["load"]))
    lever, angle0, direction = parse_input(
        "input", _table("input", doc.get("input", {})), joint, base_dir
    )
    init = _table("initial", doc.get("initial", {}))
    _unknown("initial", init, {"angle", "pressure"})
    p0 = None
    if "angle" in init:
        angle0 = quantity("initial.angle", init["angle"], "angle")
    if "pressure" in init:
        p0 = quantity("initial.pressure", init["pressure"], "pressure")
    sol = _table("solver", doc.get("solver", {}))
    _unknown("solver", sol, {"method", "step", "duration", "record_every"})
    kw = {}
    if "method" in sol:
        kw["method"] = sol["method"]
    kw["step"] = (
        quantity("solver.step", sol["step"], "time", positive=True)
        if "step" in sol
        else DEFAULT_STEP
    )
    if "duration" in sol:
        kw["duration"] = quantity("solver.duration", sol["duration"], "time", positive=True)
    else:
        travel = abs(lever.final - joint.jack_position(angle0))
        span = float(lever.times[-1]) + (lever.sine_frequency and 2.0 / lever.sine_frequency)
        kw["duration"] = span + default_duration(joint, max(travel, joint.valve_saturation))
    if "record_every" in sol:
        re_ = sol["record_every"]
        kw["record_every"] = record_every_value(re_)
    name = doc.get("name", source)
    return Scenario(
        joint=joint,
        load=load,
        lever=lever,
        initial_angle=angle0,
        initial_pressure=p0,
        direction=direction,
        name=str(name),
        **kw,
    )


def read_text_file(path) -> tuple[str, Path]:
    """(text, path) of a UTF-8 input file, or a one-line error naming it."""
    path = Path(path)
    if not path.is_file():
        raise HydroarmError(str(path), "file not found")
    try:
        return path.read_text(encoding="utf-8"), path
    except (OSError, UnicodeDecodeError) as exc:
        raise HydroarmError(str(path), f"cannot read ({exc})") from None


def record_every_value(value) -> int:
    """The ``solver.record_every`` entry: a whole number ≥ 1."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise HydroarmError("solver.record_every", f"must be a whole number ≥ 1, got {value!r}")
    return value


def load_scenario(path) -> Scenario:
    """Read a scenario TOML file (units on every quantity) into a :class:`Scenario`."""
    text, path = read_text_file(path)
    return load_scenario_text(text, path.parent, source=path.name)
