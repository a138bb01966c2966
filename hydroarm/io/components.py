"""Component servo files (TOML, a unit on every quantity; docs/components.md "Files").

A file with an ``[actuator]`` section describes a servo built from components::

    name = "position servo"
    [actuator]   type = "double_rod" | "single_rod" | "rotary", areas or diameters, stroke,
                 dead volumes, bulk modulus, air, leakage, friction
    [valve]      type = "spool" (four metering edges) | "linearised"
    [feedback]   type = "mechanical" | "electronic" (sensor + PID)
    [load]       type = "mass" | "rotary" | "crank"
    [supply]     type = "fixed" | "pump" (relief valve, accumulator)
    [initial]    position, velocity, pressure_a, pressure_b (absolute), spool (spool dynamics)
    [input]      the reference: type = "steps" | "ramp" | "sine" | "csv"
    [solver]     method, step, duration, record_every

Pressures are absolute. Every value is converted to SI here, once; unknown keys, wrong
dimensions and bad values are one-line errors naming the field.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core.params import STANDARD_GRAVITY as G0
from ..core.servo import (
    FEEDBACK_ELECTRONIC,
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    LOAD_MASS,
    LOAD_ROTARY,
    SUPPLY_FIXED,
    SUPPLY_PUMP,
    VALVE_LINEARISED,
    VALVE_SPOOL,
)
from ..errors import HydroarmError
from ..metrics import power
from ..model.lever import LeverInput
from ..model.servo import SERVO_METHODS, ServoScenario
from ..model.servo_circuit import EDGES, NOMINAL_RELIEF_DROP
from .sections import (
    check_run_size,
    check_times,
    number_or_quantity,
    optional_table,
    read_csv_columns,
    reject_unknown_keys,
    require_keys,
    require_table,
    solver_values,
    text_value,
)
from .units import energy_or_charge, quantity

SECTIONS = {
    "name",
    "description",
    "actuator",
    "valve",
    "feedback",
    "load",
    "supply",
    "initial",
    "input",
    "solver",
    "explore",  # read by hydroarm explore only (hydroarm/explore/system.py)
}
RELIEF_FLOW_FORCE_SLOPE = 1.0e-8  # k_cf [m³/(s Pa)] by default: Hopsan's (k_cs = k_cf = 1e-8)


def is_component_file(doc: dict) -> bool:
    """Whether a parsed scenario file describes a component servo (has ``[actuator]``)."""
    return "actuator" in doc


def _get(section, table, key, dimension, default=None, *, positive=False, nonnegative=False):
    """A value of ``table[key]`` in SI (``default`` when absent; None: required)."""
    field = f"{section}.{key}"
    if key not in table:
        if default is None:
            raise HydroarmError(field, "is required")
        return default
    return number_or_quantity(
        field, table[key], dimension, positive=positive, nonnegative=nonnegative
    )


def _limit(section: str, table: dict, key: str, dimension: str, default: float) -> float:
    """An optional limit in SI: ``default`` (±inf: none) when absent."""
    if key not in table:
        return default
    return quantity(f"{section}.{key}", table[key], dimension)


def _frequency(field: str, value) -> float:
    """An angular frequency [rad/s]: "200 rad/s" as it is, "30 Hz" times 2π (pint reads Hz
    as 1/s, which would silently lose the 2π)."""
    v = quantity(field, value, "frequency", positive=True)
    if isinstance(value, str) and "hz" in value.lower():
        v *= 2.0 * math.pi
    return v


# ------------------------------------------------------------------ actuator ---
ACTUATOR_KEYS = {
    "type",
    "piston_area",
    "area_a",
    "area_b",
    "piston_diameter",
    "rod_diameter",
    "displacement",
    "stroke",
    "stroke_min",
    "stroke_max",
    "dead_volume",
    "dead_volume_a",
    "dead_volume_b",
    "line_volume_a",
    "line_volume_b",
    "bulk_modulus",
    "air_fraction",
    "air_exponent",
    "internal_leakage",
    "external_leakage",
    "external_leakage_a",
    "external_leakage_b",
    "coulomb_friction",
    "breakaway_friction",
    "viscous_friction",
    "cavitation_pressure",
}


def actuator_values(t: dict) -> tuple[dict, str]:
    s = "actuator"
    reject_unknown_keys(s, t, ACTUATOR_KEYS)
    kind = text_value(
        f"{s}.type", t.get("type", "double_rod"), ("double_rod", "single_rod", "rotary")
    )
    v: dict = {}
    if kind == "rotary":
        require_keys(s, t, ("displacement",), ' (volume per radian, e.g. "10 cm**3/rev")')
        v["area_a"] = v["area_b"] = _get(s, t, "displacement", "volume", positive=True)
        lo = quantity(f"{s}.stroke_min", t.get("stroke_min", "-180 deg"), "angle")
        hi = quantity(f"{s}.stroke_max", t.get("stroke_max", "180 deg"), "angle")
    else:
        if "area_a" in t or "area_b" in t:
            require_keys(s, t, ("area_a", "area_b"))
            v["area_a"] = _get(s, t, "area_a", "area", positive=True)
            v["area_b"] = _get(s, t, "area_b", "area", positive=True)
        elif "piston_diameter" in t:
            d = _get(s, t, "piston_diameter", "length", positive=True)
            rod = _get(s, t, "rod_diameter", "length", 0.0, nonnegative=True)
            if rod >= d:
                raise HydroarmError(f"{s}.rod_diameter", "must be smaller than the piston")
            full = math.pi * d * d / 4.0
            annulus = full - math.pi * rod * rod / 4.0
            v["area_a"] = full if kind == "single_rod" else annulus
            v["area_b"] = annulus
        else:
            require_keys(s, t, ("piston_area",), " (or area_a/area_b, or piston_diameter)")
            v["area_a"] = v["area_b"] = _get(s, t, "piston_area", "area", positive=True)
        if kind == "double_rod" and v["area_a"] != v["area_b"]:
            raise HydroarmError(f"{s}.area_b", "a double_rod actuator has equal areas")
        if "stroke" in t:
            lo, hi = 0.0, _get(s, t, "stroke", "length", positive=True)
        else:
            require_keys(s, t, ("stroke_min", "stroke_max"), ' (or stroke = "…")')
            lo = quantity(f"{s}.stroke_min", t["stroke_min"], "length")
            hi = quantity(f"{s}.stroke_max", t["stroke_max"], "length")
    if not hi > lo:
        raise HydroarmError(f"{s}.stroke_max", "must be above stroke_min")
    v["stroke_min"], v["stroke_max"] = lo, hi
    dead = _get(s, t, "dead_volume", "volume", 0.0, nonnegative=True)
    for side in ("a", "b"):
        own = _get(s, t, f"dead_volume_{side}", "volume", dead, nonnegative=True)
        own += _get(s, t, f"line_volume_{side}", "volume", 0.0, nonnegative=True)
        if not own > 0.0:
            raise HydroarmError(
                f"{s}.dead_volume_{side}", "must be positive (a chamber never empties)"
            )
        v[f"dead_volume_{side}"] = own
    v["bulk_modulus"] = _get(s, t, "bulk_modulus", "pressure", positive=True)
    v["air_fraction"] = _get(s, t, "air_fraction", "dimensionless", 0.0, nonnegative=True)
    if v["air_fraction"] >= 1.0:
        raise HydroarmError(f"{s}.air_fraction", "must be below 1")
    v["air_exponent"] = _get(s, t, "air_exponent", "dimensionless", 1.0, positive=True)
    v["internal_leakage"] = _get(s, t, "internal_leakage", "leakage", 0.0, nonnegative=True)
    ext = _get(s, t, "external_leakage", "leakage", 0.0, nonnegative=True)
    for side in ("a", "b"):
        v[f"external_leakage_{side}"] = _get(
            s, t, f"external_leakage_{side}", "leakage", ext, nonnegative=True
        )
    force = "torque" if kind == "rotary" else "force"
    v["coulomb_friction"] = _get(s, t, "coulomb_friction", force, 0.0, nonnegative=True)
    v["breakaway_friction"] = _get(
        s, t, "breakaway_friction", force, v["coulomb_friction"], nonnegative=True
    )
    viscous = "torque_s" if kind == "rotary" else "viscous"
    v["viscous_friction"] = _get(s, t, "viscous_friction", viscous, 0.0, nonnegative=True)
    v["cavitation_pressure"] = _get(s, t, "cavitation_pressure", "pressure", 0.0, nonnegative=True)
    return v, kind


# --------------------------------------------------------------------- valve ---
VALVE_KEYS = {
    "type",
    "discharge_coefficient",
    "density",
    "spool_diameter",
    "circumference_fraction",
    "area_gradient",
    "rated_flow",
    "rated_pressure_drop",
    "overlap",
    "overlap_pa",
    "overlap_at",
    "overlap_pb",
    "overlap_bt",
    "max_stroke",
    "dynamics",
    "time_constant",
    "natural_frequency",
    "damping_ratio",
    "transition_pressure",
    "flow_gain",
}


def valve_values(t: dict) -> dict:
    s = "valve"
    reject_unknown_keys(s, t, VALVE_KEYS)
    kind = text_value(f"{s}.type", t.get("type", "spool"), ("spool", "linearised"))
    v: dict = {"spool_max": _get(s, t, "max_stroke", "length", positive=True)}
    if kind == "linearised":
        v["valve_kind"] = VALVE_LINEARISED
        v["flow_gain"] = _get(s, t, "flow_gain", "flow_per_length", positive=True)
    else:
        v["valve_kind"] = VALVE_SPOOL
        if "rated_flow" in t:
            # datasheet: rated flow at the rated drop across the valve (two edges in series)
            q_n = _get(s, t, "rated_flow", "flow", positive=True)
            dp_n = _get(s, t, "rated_pressure_drop", "pressure", positive=True)
            k = q_n / (v["spool_max"] * math.sqrt(0.5 * dp_n))
            for e in EDGES:
                v[f"edge_{e}"] = k
        else:
            cq = _get(s, t, "discharge_coefficient", "dimensionless", positive=True)
            rho = _get(s, t, "density", "density", positive=True)
            if "area_gradient" in t:
                w = _get(s, t, "area_gradient", "length", positive=True)
            else:
                d = _get(s, t, "spool_diameter", "length", positive=True)
                f = _get(s, t, "circumference_fraction", "dimensionless", 1.0, positive=True)
                if f > 1.0:
                    raise HydroarmError(f"{s}.circumference_fraction", "must be at most 1")
                w = math.pi * d * f
            for e in EDGES:
                v[f"edge_{e}"] = cq * w * math.sqrt(2.0 / rho)
        lap = quantity(f"{s}.overlap", t.get("overlap", "0 m"), "length")
        for e in EDGES:
            v[f"lap_{e}"] = quantity(
                f"{s}.overlap_{e}", t.get(f"overlap_{e}", f"{lap} m"), "length"
            )
        v["transition_pressure"] = _get(
            s, t, "transition_pressure", "pressure", 1.0e4, positive=True
        )
    dyn = text_value(
        f"{s}.dynamics", t.get("dynamics", "none"), ("none", "first_order", "second_order")
    )
    v["spool_order"] = {"none": 0, "first_order": 1, "second_order": 2}[dyn]
    if dyn == "first_order":
        v["spool_time_constant"] = _get(s, t, "time_constant", "time", positive=True)
    elif dyn == "second_order":
        require_keys(s, t, ("natural_frequency",))
        v["spool_frequency"] = _frequency(f"{s}.natural_frequency", t["natural_frequency"])
        v["spool_damping"] = _get(s, t, "damping_ratio", "dimensionless", 1.0, positive=True)
    return v


# ------------------------------------------------------------------ feedback ---
FEEDBACK_KEYS = {
    "type",
    "gain",
    "sensor",
    "sensor_gain",
    "proportional_gain",
    "integral_gain",
    "derivative_gain",
    "output_min",
    "output_max",
}


def feedback_values(t: dict, linear: bool) -> dict:
    s = "feedback"
    reject_unknown_keys(s, t, FEEDBACK_KEYS)
    kind = text_value(f"{s}.type", t.get("type", "mechanical"), ("mechanical", "electronic"))
    if kind == "mechanical":
        for k in t:
            if k not in ("type", "gain"):
                raise HydroarmError(f"{s}.{k}", "belongs to electronic feedback")
        return {
            "feedback_kind": FEEDBACK_MECHANICAL,
            "feedback_gain": _get(s, t, "gain", "dimensionless", 1.0, positive=True),
        }
    if "gain" in t:
        raise HydroarmError(f"{s}.gain", "is the mechanical feedback's; use proportional_gain")
    # gains in spool metres per unit of the sensed quantity (m or rad)
    per = "dimensionless" if linear else "length"
    v = {
        "feedback_kind": FEEDBACK_ELECTRONIC,
        "sense_actuator": 1.0
        if text_value(f"{s}.sensor", t.get("sensor", "load"), ("load", "actuator")) == "actuator"
        else 0.0,
        "sensor_gain": _get(s, t, "sensor_gain", "dimensionless", 1.0, positive=True),
        "proportional_gain": _get(s, t, "proportional_gain", per, 0.0, nonnegative=True),
        "integral_gain": _get(
            s,
            t,
            "integral_gain",
            "frequency" if linear else "length_per_time",
            0.0,
            nonnegative=True,
        ),
        "derivative_gain": _get(
            s, t, "derivative_gain", "time" if linear else "length_time", 0.0, nonnegative=True
        ),
        "output_min": _limit(s, t, "output_min", "length", -math.inf),
        "output_max": _limit(s, t, "output_max", "length", math.inf),
    }
    if not v["output_max"] > v["output_min"]:
        raise HydroarmError(f"{s}.output_max", "must be above output_min")
    if v["proportional_gain"] == 0.0 and v["integral_gain"] == 0.0:
        raise HydroarmError(f"{s}.proportional_gain", "or integral_gain must be positive")
    return v


# ---------------------------------------------------------------------- load ---
LOAD_KEYS = {
    "type",
    "mass",
    "inertia",
    "spring_rate",
    "spring_free_position",
    "damping",
    "external_force",
    "external_torque",
    "incline",
    "weight",
    "arm",
    "gravity_angle",
    "plane_tilt",
    "position_min",
    "position_max",
    "crank_radius",
    "gear_ratio",
    "torque_arm",
    "gearbox_friction_torque",
    "gearbox_loss_at_stall",
    "gearbox_loss_exponent",
    "rated_pressure",
}


def load_values(t: dict, actuator: str) -> dict:
    s = "load"
    reject_unknown_keys(s, t, LOAD_KEYS)
    default = "rotary" if actuator == "rotary" else "mass"
    kind = text_value(f"{s}.type", t.get("type", default), ("mass", "rotary", "crank"))
    if (kind == "rotary") != (actuator == "rotary"):
        raise HydroarmError(
            f"{s}.type", "a rotary load needs a rotary actuator and the other way round"
        )
    v: dict = {}
    if kind == "mass":
        v["load_kind"] = LOAD_MASS
        v["mass"] = _get(s, t, "mass", "mass", positive=True)
        v["spring_rate"] = _get(s, t, "spring_rate", "stiffness", 0.0, nonnegative=True)
        v["spring_free_position"] = _get(s, t, "spring_free_position", "length", 0.0)
        v["damping"] = _get(s, t, "damping", "viscous", 0.0, nonnegative=True)
        force = _get(s, t, "external_force", "force", 0.0)
        incline = quantity(f"{s}.incline", t.get("incline", "0 deg"), "angle")
        v["external_force"] = force + v["mass"] * G0 * math.sin(incline)
        unit = "length"
    else:
        v["load_kind"] = LOAD_ROTARY if kind == "rotary" else LOAD_CRANK
        v["mass"] = _get(s, t, "inertia", "inertia", positive=True)
        v["spring_rate"] = _get(s, t, "spring_rate", "torque", 0.0, nonnegative=True)
        v["spring_free_position"] = quantity(
            f"{s}.spring_free_position", t.get("spring_free_position", "0 deg"), "angle"
        )
        v["damping"] = _get(s, t, "damping", "torque_s", 0.0, nonnegative=True)
        v["external_force"] = _get(s, t, "external_torque", "torque", 0.0)
        weight = _get(s, t, "weight", "force", 0.0, nonnegative=True)
        arm = _get(s, t, "arm", "length", 0.0, nonnegative=True)
        tilt = quantity(f"{s}.plane_tilt", t.get("plane_tilt", "0 deg"), "angle")
        v["gravity_moment"] = weight * arm * math.cos(tilt)
        default_angle = "30 deg" if kind == "crank" else "0 deg"
        v["gravity_angle"] = quantity(
            f"{s}.gravity_angle", t.get("gravity_angle", default_angle), "angle"
        )
        unit = "angle"
        if kind == "crank":
            v["crank_radius"] = _get(s, t, "crank_radius", "length", positive=True)
            v["gear_ratio"] = _get(s, t, "gear_ratio", "dimensionless", 1.0, positive=True)
            arm_kind = text_value(
                f"{s}.torque_arm", t.get("torque_arm", "paper"), ("paper", "kinematic")
            )
            v["kinematic_torque_arm"] = 1.0 if arm_kind == "kinematic" else 0.0
            v["gearbox_friction_torque"] = _get(
                s, t, "gearbox_friction_torque", "torque", 0.0, nonnegative=True
            )
            v["gearbox_loss_at_stall"] = _get(
                s, t, "gearbox_loss_at_stall", "dimensionless", 0.0, nonnegative=True
            )
            v["gearbox_loss_exponent"] = _get(
                s, t, "gearbox_loss_exponent", "dimensionless", 1.0, positive=True
            )
            v["rated_load_pressure"] = _get(
                s, t, "rated_pressure", "pressure", math.inf, positive=True
            )
    lo = _limit(s, t, "position_min", unit, -math.inf)
    hi = _limit(s, t, "position_max", unit, math.inf)
    if not hi > lo:
        raise HydroarmError(f"{s}.position_max", "must be above position_min")
    v["position_min"], v["position_max"] = lo, hi
    return v


# -------------------------------------------------------------------- supply ---
SUPPLY_KEYS = {
    "type",
    "pressure",
    "tank_pressure",
    "displacement",
    "speed",
    "pump_flow",
    "leakage",
    "volume",
    "bulk_modulus",
    "initial_pressure",
    "relief_pressure",
    "relief_time_constant",
    "relief_slope",
    "relief_flow_force_slope",
    "relief_nominal_flow",
    "accumulator_precharge",
    "accumulator_volume",
    "accumulator_exponent",
    "motor_efficiency",
    "pump_efficiency",
    "battery_capacity",
    "battery_voltage",
    "usable_fraction",
    "cycles",
}
ELECTRIC_KEYS = (
    "motor_efficiency",
    "pump_efficiency",
    "battery_capacity",
    "battery_voltage",
    "usable_fraction",
    "cycles",
)


def electric_values(t: dict) -> dict | None:
    """The supply's electric side (``motor_efficiency`` and ``pump_efficiency`` together; a
    battery optional), or None: {pump_efficiency, motor_efficiency, usable_battery_energy,
    cycles} in SI (docs/components.md; the laws of `hydroarm.metrics.power`)."""
    s = "supply"
    if not any(k in t for k in ELECTRIC_KEYS):
        return None
    require_keys(s, t, ("motor_efficiency", "pump_efficiency"), " (the electric side)")
    out: dict = {
        k: power.check_efficiency(
            f"{s}.{k}", number_or_quantity(f"{s}.{k}", t[k], "dimensionless", positive=True)
        )
        for k in ("motor_efficiency", "pump_efficiency")
    }
    out["cycles"] = _get(s, t, "cycles", "dimensionless", 1.0, positive=True)
    out["usable_battery_energy"] = None
    if "battery_capacity" in t:
        kind, cap = energy_or_charge(f"{s}.battery_capacity", t["battery_capacity"])
        volts = None
        if "battery_voltage" in t:
            volts = quantity(f"{s}.battery_voltage", t["battery_voltage"], "voltage", positive=True)
        frac = _get(s, t, "usable_fraction", "dimensionless", 1.0, positive=True)
        try:
            out["usable_battery_energy"] = power.battery_energy(
                **{kind: cap}, voltage=volts, usable_fraction=frac
            )
        except HydroarmError as exc:
            raise HydroarmError(f"{s}.{exc.field}", exc.problem) from None
    else:
        for k in ("battery_voltage", "usable_fraction"):
            if k in t:
                raise HydroarmError(f"{s}.{k}", "needs battery_capacity")
    return out


def supply_values(t: dict) -> dict:
    s = "supply"
    reject_unknown_keys(s, t, SUPPLY_KEYS)
    kind = text_value(f"{s}.type", t.get("type", "fixed"), ("fixed", "pump"))
    v: dict = {"tank_pressure": _get(s, t, "tank_pressure", "pressure", 1.0e5, nonnegative=True)}
    if kind == "fixed":
        for k in t:
            if k not in ("type", "pressure", "tank_pressure", *ELECTRIC_KEYS):
                raise HydroarmError(f"{s}.{k}", 'belongs to a pump supply (type = "pump")')
        v["supply_kind"] = SUPPLY_FIXED
        v["supply_pressure"] = _get(s, t, "pressure", "pressure", positive=True)
        if not v["supply_pressure"] > v["tank_pressure"]:
            raise HydroarmError(f"{s}.pressure", "must be above the tank pressure (absolute)")
        return v
    v["supply_kind"] = SUPPLY_PUMP
    if "pump_flow" in t:
        v["pump_flow"] = _get(s, t, "pump_flow", "flow", positive=True)
    else:
        require_keys(s, t, ("displacement", "speed"), " (or pump_flow)")
        disp = _get(s, t, "displacement", "volume", positive=True)  # per radian
        v["pump_flow"] = disp * _get(s, t, "speed", "frequency", positive=True)
    v["pump_leakage"] = _get(s, t, "leakage", "leakage", 0.0, nonnegative=True)
    v["supply_volume"] = _get(s, t, "volume", "volume", positive=True)
    v["supply_bulk_modulus"] = _get(s, t, "bulk_modulus", "pressure", positive=True)
    v["supply_pressure"] = _get(
        s, t, "initial_pressure", "pressure", v["tank_pressure"], nonnegative=True
    )
    if "relief_pressure" in t:
        v["relief_pressure"] = _get(s, t, "relief_pressure", "pressure", positive=True)
        v["relief_time_constant"] = _get(
            s, t, "relief_time_constant", "time", 0.0, nonnegative=True
        )
        k_cs = _get(s, t, "relief_slope", "leakage", positive=True)
        q_nom = _get(s, t, "relief_nominal_flow", "flow", positive=True)
        v["relief_spring_term"] = math.sqrt(NOMINAL_RELIEF_DROP) / k_cs
        k_cf = _get(
            s, t, "relief_flow_force_slope", "leakage", RELIEF_FLOW_FORCE_SLOPE, positive=True
        )
        v["relief_flow_term"] = 1.0 / (k_cf * math.sqrt(NOMINAL_RELIEF_DROP))
        v["relief_max_opening"] = q_nom / math.sqrt(NOMINAL_RELIEF_DROP)
    else:
        for k in t:
            if k.startswith("relief_"):
                raise HydroarmError(f"{s}.{k}", "needs relief_pressure")
    if "accumulator_volume" in t:
        v["accumulator_volume"] = _get(s, t, "accumulator_volume", "volume", positive=True)
        v["accumulator_precharge"] = _get(s, t, "accumulator_precharge", "pressure", positive=True)
        v["accumulator_exponent"] = _get(
            s, t, "accumulator_exponent", "dimensionless", 1.4, positive=True
        )
    return v


# --------------------------------------------------------------------- input ---
INPUT_KEYS = {
    "type",
    "times",
    "values",
    "start",
    "end",
    "from",
    "to",
    "offset",
    "amplitude",
    "frequency",
    "file",
    "time_column",
    "value_column",
}


def reference_input(t: dict, unit: str, base_dir: Path) -> LeverInput:
    s = "input"
    reject_unknown_keys(s, t, INPUT_KEYS)
    kind = text_value(f"{s}.type", t.get("type", "steps"), ("steps", "ramp", "sine", "csv"))

    def val(key, value):
        return quantity(f"{s}.{key}", value, unit)

    if kind == "steps":
        require_keys(s, t, ("times", "values"))
        times, values = t["times"], t["values"]
        if not isinstance(times, list) or not isinstance(values, list) or not times:
            raise HydroarmError(f"{s}.times", "and values must be lists of equal length")
        if len(times) != len(values):
            raise HydroarmError(f"{s}.values", "must have as many entries as times")
        ts = [quantity(f"{s}.times", x, "time", nonnegative=True) for x in times]
        ys = [val("values", y) for y in values]
        tab_t, tab_y = [ts[0]], [ys[0]]
        for tk, yk in zip(ts[1:], ys[1:], strict=True):
            tab_t += [tk, tk]
            tab_y += [tab_y[-1], yk]
        check_times(f"{s}.times", "times", np.array(ts))
        return LeverInput(np.array(tab_t), np.array(tab_y), description="steps")
    if kind == "ramp":
        require_keys(s, t, ("from", "to", "end"))
        t0 = quantity(f"{s}.start", t.get("start", "0 s"), "time", nonnegative=True)
        t1 = quantity(f"{s}.end", t["end"], "time", positive=True)
        if not t1 > t0:
            raise HydroarmError(f"{s}.end", "must be after start")
        return LeverInput(
            np.array([t0, t1]),
            np.array([val("from", t["from"]), val("to", t["to"])]),
            description="ramp",
        )
    if kind == "sine":
        require_keys(s, t, ("amplitude", "frequency"))
        f_hz = quantity(f"{s}.frequency", t["frequency"], "frequency", positive=True)
        t0 = quantity(f"{s}.start", t.get("start", "0 s"), "time", nonnegative=True)
        off = val("offset", t.get("offset", "0 m" if unit == "length" else "0 deg"))
        return LeverInput(
            np.array([t0]),
            np.array([off]),
            val("amplitude", t["amplitude"]),
            f_hz,
            t0,
            description="sine",
        )
    require_keys(s, t, ("file",))
    tc = text_value(f"{s}.time_column", t.get("time_column", "t_s"))
    vc = text_value(f"{s}.value_column", t.get("value_column", "reference"))
    cols = read_csv_columns(f"{s}.file", base_dir / text_value(f"{s}.file", t["file"]), (tc, vc))
    times = check_times(f"{s}.file", tc, np.asarray(cols[tc], float))
    return LeverInput(times, np.asarray(cols[vc], float), description="csv")


INITIAL_KEYS = {"position", "velocity", "pressure_a", "pressure_b", "spool"}


def _initial_spool(value, valve: dict) -> float:
    """``[initial] spool`` [m]: the spool's start position, a state of spool dynamics of first
    or second order only (with none the spool is its demand at once), within its stroke."""
    x = quantity("initial.spool", value, "length")
    if valve["spool_order"] == 0:
        raise HydroarmError(
            "initial.spool",
            "the spool has no dynamics (valve.dynamics = 'none': it follows its demand at "
            "once); give valve.dynamics = 'first_order' or 'second_order', or leave it out",
        )
    if abs(x) > valve["spool_max"]:
        raise HydroarmError(
            "initial.spool",
            f"is outside the spool's stroke ±{valve['spool_max'] * 1e3:.6g} mm (valve.max_stroke)",
        )
    return x


def servo_from_doc(doc: dict, base_dir: Path, source: str = "scenario") -> ServoScenario:
    """A [`ServoScenario`][hydroarm.ServoScenario] from a parsed component servo file."""
    reject_unknown_keys("", doc, SECTIONS)
    act, act_kind = actuator_values(require_table(doc, "actuator"))
    valve = valve_values(require_table(doc, "valve"))
    load = load_values(require_table(doc, "load"), act_kind)
    linear = load["load_kind"] == LOAD_MASS
    feedback = feedback_values(optional_table(doc, "feedback"), linear)
    if feedback["feedback_kind"] == FEEDBACK_ELECTRONIC:
        # the controller's output is the spool demand: unless limited tighter, it saturates
        # where the spool does, so that the anti-windup knows the stroke limit
        feedback["output_min"] = max(feedback["output_min"], -valve["spool_max"])
        feedback["output_max"] = min(feedback["output_max"], valve["spool_max"])
    supply_table = require_table(doc, "supply")
    supply = supply_values(supply_table)
    electric = electric_values(supply_table)
    unit = "length" if linear or feedback["feedback_kind"] == FEEDBACK_MECHANICAL else "angle"
    if load["load_kind"] == LOAD_CRANK and feedback["feedback_kind"] == FEEDBACK_MECHANICAL:
        unit = "length"  # the lever, in jack coordinates
    reference = reference_input(require_table(doc, "input"), unit, base_dir)
    params = {**act, **valve, **load, **feedback, **supply}
    it = optional_table(doc, "initial")
    reject_unknown_keys("initial", it, INITIAL_KEYS)
    initial: dict = {}
    if "position" in it:
        initial["position"] = quantity(
            "initial.position", it["position"], "length" if linear else "angle"
        )
    if "velocity" in it:
        initial["velocity"] = quantity(
            "initial.velocity", it["velocity"], "velocity" if linear else "frequency"
        )
    for k in ("pressure_a", "pressure_b"):
        if k in it:
            initial[k] = quantity(f"initial.{k}", it[k], "pressure", nonnegative=True)
    if "spool" in it:
        initial["spool"] = _initial_spool(it["spool"], valve)
    solver = solver_values("solver", optional_table(doc, "solver"), SERVO_METHODS)
    kw = {k: solver[k] for k in ("method", "step", "duration", "record_every") if k in solver}
    kw.setdefault("duration", 1.0)
    kw.setdefault("step", 1e-5)
    check_run_size(kw["duration"], kw["step"], kw.get("record_every", 1))
    name = doc.get("name", source)
    if not isinstance(name, str):
        raise HydroarmError("name", "must be a string")
    pos = initial.get("position", 0.0)
    lo = (
        load["position_min"]
        if load["load_kind"] == LOAD_CRANK
        else max(load["position_min"], act["stroke_min"])
    )
    hi = (
        load["position_max"]
        if load["load_kind"] == LOAD_CRANK
        else min(load["position_max"], act["stroke_max"])
    )
    if not lo <= pos <= hi:
        raise HydroarmError("initial.position", "is outside the stroke and end stops")
    return ServoScenario(params, reference, initial, name=name, electric=electric, **kw)


# ------------------------------------------------------------------- sweeps ---
# The servo parameters a sweep may vary (docs/batch.md "Component servos"), by their names in
# hydroarm.core.servo.PARAMETERS: name -> (dimension, dimension when angular or None, sign
# rule: "positive", "nonnegative" or "any"). "Angular" is a rotary actuator for the
# actuator's fields and an angular load (rotary, crank) for the load's and the controller's.
# The kind codes (valve_kind, spool_order, …) and the relief valve's derived terms are not
# sweepable: a different component is a different base scenario.
_ACTUATOR_ANGULAR = {"area_a", "area_b", "stroke_min", "stroke_max"}
_ACTUATOR_ANGULAR |= {"coulomb_friction", "breakaway_friction", "viscous_friction"}
SWEEP_PARAMETERS: dict[str, tuple[str, str | None, str]] = {
    # actuator
    "area_a": ("area", "volume", "positive"),
    "area_b": ("area", "volume", "positive"),
    "stroke_min": ("length", "angle", "any"),
    "stroke_max": ("length", "angle", "any"),
    "dead_volume_a": ("volume", None, "positive"),
    "dead_volume_b": ("volume", None, "positive"),
    "bulk_modulus": ("pressure", None, "positive"),
    "air_fraction": ("dimensionless", None, "nonnegative"),
    "air_exponent": ("dimensionless", None, "positive"),
    "internal_leakage": ("leakage", None, "nonnegative"),
    "external_leakage_a": ("leakage", None, "nonnegative"),
    "external_leakage_b": ("leakage", None, "nonnegative"),
    "coulomb_friction": ("force", "torque", "nonnegative"),
    "breakaway_friction": ("force", "torque", "nonnegative"),
    "viscous_friction": ("viscous", "torque_s", "nonnegative"),
    "cavitation_pressure": ("pressure", None, "nonnegative"),
    # valve
    "edge_pa": ("flow_coefficient", None, "positive"),
    "edge_at": ("flow_coefficient", None, "positive"),
    "edge_pb": ("flow_coefficient", None, "positive"),
    "edge_bt": ("flow_coefficient", None, "positive"),
    "lap_pa": ("length", None, "any"),
    "lap_at": ("length", None, "any"),
    "lap_pb": ("length", None, "any"),
    "lap_bt": ("length", None, "any"),
    "flow_gain": ("flow_per_length", None, "positive"),
    "spool_max": ("length", None, "positive"),
    "spool_time_constant": ("time", None, "positive"),
    "spool_frequency": ("frequency", None, "positive"),
    "spool_damping": ("dimensionless", None, "positive"),
    "transition_pressure": ("pressure", None, "positive"),
    # feedback
    "feedback_gain": ("dimensionless", None, "positive"),
    "sensor_gain": ("dimensionless", None, "positive"),
    "proportional_gain": ("dimensionless", "length", "nonnegative"),
    "integral_gain": ("frequency", "length_per_time", "nonnegative"),
    "derivative_gain": ("time", "length_time", "nonnegative"),
    "output_min": ("length", None, "any"),
    "output_max": ("length", None, "any"),
    # load
    "mass": ("mass", "inertia", "positive"),
    "spring_rate": ("stiffness", "torque", "nonnegative"),
    "spring_free_position": ("length", "angle", "any"),
    "damping": ("viscous", "torque_s", "nonnegative"),
    "external_force": ("force", "torque", "any"),
    "gravity_moment": ("torque", None, "any"),
    "gravity_angle": ("angle", None, "any"),
    "position_min": ("length", "angle", "any"),
    "position_max": ("length", "angle", "any"),
    "crank_radius": ("length", None, "positive"),
    "gear_ratio": ("dimensionless", None, "positive"),
    "gearbox_friction_torque": ("torque", None, "nonnegative"),
    "gearbox_loss_at_stall": ("dimensionless", None, "nonnegative"),
    "gearbox_loss_exponent": ("dimensionless", None, "positive"),
    "rated_load_pressure": ("pressure", None, "positive"),
    # supply
    "supply_pressure": ("pressure", None, "positive"),
    "tank_pressure": ("pressure", None, "nonnegative"),
    "pump_flow": ("flow", None, "positive"),
    "pump_leakage": ("leakage", None, "nonnegative"),
    "supply_volume": ("volume", None, "positive"),
    "supply_bulk_modulus": ("pressure", None, "positive"),
    "relief_pressure": ("pressure", None, "positive"),
    "relief_time_constant": ("time", None, "positive"),
    "accumulator_precharge": ("pressure", None, "positive"),
    "accumulator_volume": ("volume", None, "positive"),
    "accumulator_exponent": ("dimensionless", None, "positive"),
}
# convenience names that set several parameters to one value
SWEEP_ALIASES: dict[str, tuple[str, ...]] = {
    "overlap": ("lap_pa", "lap_at", "lap_pb", "lap_bt"),
    "piston_area": ("area_a", "area_b"),
    "dead_volume": ("dead_volume_a", "dead_volume_b"),
    "external_leakage": ("external_leakage_a", "external_leakage_b"),
    "flow_coefficient": ("edge_pa", "edge_at", "edge_pb", "edge_bt"),
}
# parameters that only mean something with one kind of component: name -> (test on the base
# parameters {name: value}, what the base servo lacks)
_NEEDS = {
    "spool": (lambda p: p.get("valve_kind") == VALVE_SPOOL, "a spool valve"),
    "linearised": (lambda p: p.get("valve_kind") == VALVE_LINEARISED, "a linearised valve"),
    "first_order": (lambda p: p.get("spool_order") == 1, "first-order spool dynamics"),
    "second_order": (lambda p: p.get("spool_order") == 2, "second-order spool dynamics"),
    "mechanical": (
        lambda p: p.get("feedback_kind") == FEEDBACK_MECHANICAL,
        "mechanical feedback",
    ),
    "electronic": (
        lambda p: p.get("feedback_kind") == FEEDBACK_ELECTRONIC,
        "electronic feedback",
    ),
    "crank": (lambda p: p.get("load_kind") == LOAD_CRANK, "a crank load"),
    "angular": (lambda p: p.get("load_kind") != LOAD_MASS, "a rotary or crank load"),
    "pump": (lambda p: p.get("supply_kind") == SUPPLY_PUMP, "a pump supply"),
    "relief": (lambda p: math.isfinite(p.get("relief_pressure", math.inf)), "a relief valve"),
    "accumulator": (lambda p: p.get("accumulator_volume", 0.0) > 0.0, "an accumulator"),
}
_NEEDED_BY = {
    **dict.fromkeys(
        ("lap_pa", "lap_at", "lap_pb", "lap_bt", "edge_pa", "edge_at", "edge_pb", "edge_bt"),
        "spool",
    ),
    "transition_pressure": "spool",
    "flow_gain": "linearised",
    "spool_time_constant": "first_order",
    "spool_frequency": "second_order",
    "spool_damping": "second_order",
    "feedback_gain": "mechanical",
    **dict.fromkeys(
        (
            "sensor_gain",
            "proportional_gain",
            "integral_gain",
            "derivative_gain",
            "output_min",
            "output_max",
        ),
        "electronic",
    ),
    **dict.fromkeys(
        (
            "crank_radius",
            "gear_ratio",
            "gearbox_friction_torque",
            "gearbox_loss_at_stall",
            "gearbox_loss_exponent",
            "rated_load_pressure",
        ),
        "crank",
    ),
    "gravity_moment": "angular",
    "gravity_angle": "angular",
    **dict.fromkeys(
        ("pump_flow", "pump_leakage", "supply_volume", "supply_bulk_modulus", "relief_pressure"),
        "pump",
    ),
    "relief_time_constant": "relief",
    **dict.fromkeys(
        ("accumulator_precharge", "accumulator_volume", "accumulator_exponent"), "accumulator"
    ),
}


def sweep_names() -> list[str]:
    """Every name a servo sweep may vary (parameters, then the convenience names)."""
    return [*SWEEP_PARAMETERS, *SWEEP_ALIASES]


def sweep_targets(name: str) -> tuple[str, ...]:
    """The parameters a sweep name sets (itself, or those of a convenience name)."""
    return SWEEP_ALIASES.get(name, (name,))


def sweep_rule(name: str) -> str:
    return SWEEP_PARAMETERS[sweep_targets(name)[0]][2]


def sweep_dimension(name: str, parameters: dict) -> str:
    """The dimension a sweep value of ``name`` is read in, for the base servo's parameters:
    the actuator's fields follow a rotary actuator, the load's and the controller's an
    angular load."""
    target = sweep_targets(name)[0]
    dim, angular_dim, _ = SWEEP_PARAMETERS[target]
    if angular_dim is None:
        return dim
    if target in _ACTUATOR_ANGULAR:
        angular = parameters.get("load_kind") == LOAD_ROTARY
    else:
        angular = parameters.get("load_kind") != LOAD_MASS
    return angular_dim if angular else dim


def check_sweep_name(field: str, name: str, parameters: dict) -> None:
    """Refuse a sweep name that the base servo's components do not use."""
    for target in sweep_targets(name):
        need = _NEEDED_BY.get(target)
        if need is not None and not _NEEDS[need][0](parameters):
            raise HydroarmError(field, f"needs {_NEEDS[need][1]}; the base servo has none")
    if name == "piston_area" and parameters.get("area_a") != parameters.get("area_b"):
        raise HydroarmError(
            field, "sets both areas, but the base actuator's differ: vary area_a and area_b"
        )


def sweep_value(field: str, name: str, value, parameters: dict) -> float:
    """A sweep value of ``name`` in SI with its dimension and sign rule (an angular
    frequency: "200 rad/s" as it is, "30 Hz" times 2π, as in the [valve] section)."""
    rule = sweep_rule(name)
    dim = sweep_dimension(name, parameters)
    if name == "spool_frequency":
        return _frequency(field, value)
    return number_or_quantity(
        field, value, dim, positive=rule == "positive", nonnegative=rule == "nonnegative"
    )
