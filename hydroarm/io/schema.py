"""Scenario files (TOML, a unit on every quantity) and parameter sets.

Units are parsed and converted to SI here, once; unknown keys, wrong dimensions, missing or
negative values are one-line [`HydroarmError`][hydroarm.HydroarmError] s naming the field.

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
    [metrics]                            # optional: the metric thresholds
    middle = 0.8

The section and value readers are those of `hydroarm.io.sections`, shared with arm and
sweep files.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core.params import STANDARD_GRAVITY as G0
from ..errors import HydroarmError
from ..files import checked_path
from ..model import lever as inp
from ..model.joint import Load, ServoJoint
from ..model.scenario import DEFAULT_STEP, METHODS, Scenario, default_duration
from ..model.servo import ServoScenario
from .catalog import DEFAULT_SET, paper_load
from .components import is_component_file, servo_from_doc
from .sections import (
    JOINT_KEYS,
    JOINT_TEXT_KEYS,
    PHYSICS_KEYS,
    PHYSICS_TEXT_KEYS,
    angle_value,
    as_table,
    build_joint,
    check_run_size,
    check_times,
    field_value,
    joint_from_table,
    joint_values,
    metric_options,
    optional_table,
    parameter_set_values,
    parse_toml,
    position_value,
    ramp_times,
    read_csv_columns,
    read_text_file,
    reject_unknown_keys,
    require_keys,
    require_table,
    solver_values,
    text_value,
    time_value,
    whole_number,
)
from .units import _parse, length_or_angle, quantity, registry

__all__ = [
    "JOINT_KEYS",
    "JOINT_TEXT_KEYS",
    "PHYSICS_KEYS",
    "PHYSICS_TEXT_KEYS",
    "build_joint",
    "joint_values",
    "load_scenario",
    "load_scenario_text",
    "parameter_set",
    "parameter_set_values",
    "parse_input",
    "parse_load",
    "read_lever_csv",
    "read_text_file",
    "record_every_value",
    "scenario_from_doc",
    "shoulder_elevation",
    "weight_quantity",
]
SCENARIO_SECTIONS = {
    "name",
    "joint",
    "physics",
    "load",
    "input",
    "initial",
    "solver",
    "metrics",
    "description",
}


# ---------------------------------------------------------------- parameter sets ---
def parameter_set(name: str, field: str = "joint.parameter_set") -> ServoJoint:
    """The built-in joint ``name``.

    Parameters
    ----------
    name : str
        One of [`parameter_set_names`][hydroarm.parameter_set_names] (``"paper-calibrated"``).
    field : str
        The field an error names (a file's key, a CLI option).

    Returns
    -------
    ServoJoint
        The joint, in SI units.
    """
    v = parameter_set_values(name, field)
    return build_joint(v, f"parameter_set.{name}")


def shoulder_elevation(parameter_set_name: str = DEFAULT_SET) -> ServoJoint:
    """The paper's shoulder-elevation joint (a built-in parameter set).

    Parameters
    ----------
    parameter_set_name : str
        One of [`parameter_set_names`][hydroarm.parameter_set_names].

    Returns
    -------
    ServoJoint
        The joint, in SI units.
    """
    return parameter_set(parameter_set_name)


# ----------------------------------------------------------------------- loads ---
def parse_load(section: str, table: dict) -> Load:
    reject_unknown_keys(section, table, {"builtin", "weight", "mass", "arm", "inertia", "name"})
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
    require_keys(section, table, ("arm", "inertia"))
    arm = field_value(f"{section}.arm", "arm", table["arm"])
    inertia = field_value(f"{section}.inertia", "inertia", table["inertia"])
    name = text_value(f"{section}.name", table.get("name", "custom load"))
    return Load(weight=w, arm=arm, inertia=inertia, name=name)


def weight_quantity(field: str, value) -> float:
    """A load given as a force (N, lbf) or as a mass (kg, lb) under standard gravity."""
    q = _parse(field, value)
    if q.dimensionality == registry().Quantity(1, "kg").dimensionality:
        return quantity(field, value, "mass", positive=True) * G0
    return field_value(field, "weight", value)


# ---------------------------------------------------------------------- inputs ---
def parse_input(section: str, table: dict, joint: ServoJoint, base_dir: Path):
    """Return (LeverInput, initial angle or None, direction or None)."""
    kind = table.get("type", "step")
    common = {"type"}
    if kind == "step":
        reject_unknown_keys(section, table, common | {"direction", "from", "to", "at"})
        direction = table.get("direction")
        if direction is not None and direction not in ("raise", "lower"):
            raise HydroarmError(
                f"{section}.direction", f"must be 'raise' or 'lower', got {direction!r}"
            )
        lo, hi = joint.jack_position(math.radians(-60)), joint.jack_position(math.radians(60))
        if direction == "lower":
            lo, hi = hi, lo
        y0 = position_value(f"{section}.from", table["from"], joint) if "from" in table else lo
        y1 = position_value(f"{section}.to", table["to"], joint) if "to" in table else hi
        if direction is None and ("from" not in table or "to" not in table):
            raise HydroarmError(
                f"{section}.direction", "is missing (give direction, or both from and to)"
            )
        t0 = time_value(f"{section}.at", table["at"]) if "at" in table else 0.0
        return inp.step(y0, y1, t0), joint.joint_angle(y0), direction
    if kind == "ramp":
        reject_unknown_keys(section, table, common | {"from", "to", "start", "end"})
        require_keys(section, table, ("from", "to", "end"))
        y0 = position_value(f"{section}.from", table["from"], joint)
        y1 = position_value(f"{section}.to", table["to"], joint)
        t0, t1 = ramp_times(section, table)
        return inp.ramp(y0, y1, t0, t1), joint.joint_angle(y0), None
    if kind == "sine":
        reject_unknown_keys(section, table, common | {"offset", "amplitude", "frequency", "start"})
        require_keys(section, table, ("amplitude", "frequency"))
        off = position_value(f"{section}.offset", table.get("offset", "0 mm"), joint)
        kind_a, amp = length_or_angle(f"{section}.amplitude", table["amplitude"])
        if kind_a == "angle":
            amp = joint.crank_radius * math.sin(amp / joint.gear_ratio)
        f = quantity(f"{section}.frequency", table["frequency"], "frequency", positive=True)
        t0 = time_value(f"{section}.start", table.get("start", "0 s"))
        if abs(off) + abs(amp) > joint.crank_radius:
            raise HydroarmError(f"{section}.amplitude", "takes the lever beyond the crank radius")
        return inp.sine(off, amp, f, t0), joint.joint_angle(off), None
    if kind == "csv":
        reject_unknown_keys(
            section,
            table,
            common | {"file", "time_column", "position_column", "time_unit", "position_unit"},
        )
        require_keys(section, table, ("file",))
        field = f"{section}.file"
        path = checked_path(field, text_value(field, table["file"]), base_dir)
        text = {
            k: text_value(f"{section}.{k}", table.get(k, default))
            for k, default in (
                ("time_column", "t"),
                ("position_column", "y"),
                ("time_unit", "s"),
                ("position_unit", "mm"),
            )
        }
        lev = read_lever_csv(
            path,
            text["time_column"],
            text["position_column"],
            text["time_unit"],
            text["position_unit"],
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
    field = f"{section}.file"
    path = Path(path)
    ts = quantity(f"{section}.time_unit", f"1 {tunit}", "time", positive=True)
    kind, ys = length_or_angle(f"{section}.position_unit", f"1 {yunit}")
    cols = read_csv_columns(field, path, (tcol, ycol))
    t_arr = check_times(field, path.name, cols[tcol] * ts)
    y_arr = cols[ycol] * ys
    if np.any(~np.isfinite(y_arr)):
        raise HydroarmError(field, f"{path.name}: values must be finite")
    if kind == "angle":
        y_arr = np.array([joint.jack_position(a) for a in y_arr])
    if np.any(np.abs(y_arr) > joint.crank_radius):
        raise HydroarmError(field, f"{path.name}: a lever position is beyond the crank radius")
    return inp.LeverInput(t_arr, y_arr, description=f"csv:{path.name}")


# -------------------------------------------------------------------- scenario ---
def load_scenario_text(text: str, base_dir: Path = Path("."), source: str = "scenario"):
    """A [`Scenario`][hydroarm.Scenario] of the paper's joint, or a
    [`ServoScenario`][hydroarm.ServoScenario] when the file has an ``[actuator]``
    (a servo built from components, `hydroarm.io.components`)."""
    doc = parse_toml(text, source)
    if is_component_file(doc):
        return servo_from_doc(doc, base_dir, source)
    return scenario_from_doc(doc, base_dir, source)


def scenario_from_doc(
    doc: dict, base_dir: Path = Path("."), source: str = "scenario", *, records: bool = True
):
    """A [`Scenario`][hydroarm.Scenario] from a parsed scenario document
    (``records`` False: the run keeps no trace, as in a sweep, so its size is its steps)."""
    reject_unknown_keys("", doc, SCENARIO_SECTIONS)
    joint = joint_from_table(
        "joint",
        optional_table(doc, "joint"),
        default_set="paper-calibrated",
        physics=optional_table(doc, "physics"),
        base_dir=base_dir,
    )
    load = parse_load("load", require_table(doc, "load"))
    lever, angle0, direction = parse_input("input", optional_table(doc, "input"), joint, base_dir)
    init = optional_table(doc, "initial")
    reject_unknown_keys("initial", init, {"angle", "pressure"})
    p0 = None
    if "angle" in init:
        angle0 = angle_value("initial.angle", init["angle"])
    if "pressure" in init:
        p0 = quantity("initial.pressure", init["pressure"], "pressure")
    kw = solver_values("solver", optional_table(doc, "solver"), METHODS)
    kw.setdefault("step", DEFAULT_STEP)
    if "duration" not in kw:
        travel = abs(lever.final - joint.jack_position(angle0))
        span = float(lever.times[-1]) + (lever.sine_frequency and 2.0 / lever.sine_frequency)
        kw["duration"] = span + default_duration(joint, max(travel, joint.valve_saturation))
    check_run_size(kw["duration"], kw["step"], kw.get("record_every", 1) if records else None)
    if "metrics" in doc:
        kw["metric_options"] = metric_options("metrics", as_table("metrics", doc["metrics"]))
    return Scenario(
        joint=joint,
        load=load,
        lever=lever,
        initial_angle=angle0,
        initial_pressure=p0,
        direction=direction,
        name=text_value("name", doc.get("name", source)),
        **kw,
    )


def record_every_value(value) -> int:
    """The ``solver.record_every`` entry: a whole number ≥ 1."""
    return whole_number("solver.record_every", value)


def load_scenario(path) -> Scenario | ServoScenario:
    """Read a scenario TOML file (units on every quantity).

    Parameters
    ----------
    path : str or pathlib.Path
        The scenario file (docs/model.md), the paper's joint's or a component servo's.

    Returns
    -------
    Scenario or ServoScenario
        A [`Scenario`][hydroarm.Scenario], or a [`ServoScenario`][hydroarm.ServoScenario] for
        a component servo's file.
    """
    text, path = read_text_file(path)
    return load_scenario_text(text, path.parent, source=path.name)
