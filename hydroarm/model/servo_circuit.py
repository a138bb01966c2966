"""A component servo as the circuit it stands for (issue 28: the fixed-shape servo
``[actuator] [valve] [feedback] [load] [supply]`` is a shorthand for a circuit).

`scenario_circuit` maps a [`ServoScenario`][hydroarm.ServoScenario]'s parameters
(SI, the names of `hydroarm.core.servo.PARAMETERS`) onto circuit components joined at
named nodes::

    T        the tank            (tank, pressure = the supply's tank_pressure)
    supply   the valve's P port  (tank at the fixed supply pressure; or fixed_pump + volume
                                  + relief_valve + accumulator)
    A, B     the chambers        (cylinder or rotary_actuator)
    rod      the rod             (mass: the load on the rod)
    joint    the load's angle    (inertia; a rotary actuator's shaft, a crank_linkage's
                                  master with the rod its slave)
    reference, measurement, demand   signals: signal_source → pid ← position_sensor → valve
    measurement_rate                 the sensor's rate into the pid (a derivative gain)

It needs no units: the file boundary (reading a servo file, writing the circuit file of
``hydroarm expand``) is `hydroarm.io.servo_circuit`. ``ServoScenario`` runs this circuit
on the system kernel ([`circuit`][hydroarm.ServoScenario.circuit]).

A crank load's dry friction (piston and gearbox) goes on its ``crank_linkage``, driven by
the cylinder's pressure force (`crank_friction`). What the circuit library does not
have yet is refused with one line naming the field: a relief valve's opening at the start
where the supply has none. The actuator's air is at the servo's ``atmospheric_pressure``
(the chambers' ``atmospheric_pressure``).

Every state of the servo (`hydroarm.core.servo.STATES`) given in
[`initial`][hydroarm.ServoScenario.initial] starts its circuit's: the load's position and
velocity (the load's ``initial_position``/``initial_angle``, ``initial_velocity``), the
chambers' and the supply's pressures (the circuit's node pressures; a fixed supply's source
at that pressure, which the servo kernel holds), the valve's ``initial_spool`` and
``initial_spool_velocity``, the pid's ``initial_integral`` and the relief valve's
``initial_opening``; a mechanical feedback's integral and the energies (which no circuit
state carries: their start is an offset) are added back by `hydroarm.model.servo.servo_states`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..core.circuit.components import TYPES
from ..core.circuit.system import SYSTEM
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    LOAD_MASS,
    LOAD_ROTARY,
    PARAMETERS,
    STATE_INDEX,
    SUPPLY_PUMP,
    VALVE_LINEARISED,
    default_parameters,
)
from ..errors import HydroarmError
from ..integrators import stability
from .circuit import Circuit, CompiledCircuit, ComponentSpec
from .lever import LeverInput

if TYPE_CHECKING:
    from .servo import ServoScenario

#: the circuit's accumulator neck: an oil volume [m³] taken from the supply volume (the
#: servo's accumulator has none), small enough to leave the supply's compliance unchanged
ACCUMULATOR_NECK = 1.0e-9
NAMES = tuple(name for name, _, _ in PARAMETERS)
EDGES = ("pa", "at", "pb", "bt")  # the 4/3 valve's metering edges (parameters edge_*, lap_*)
NOMINAL_RELIEF_DROP = 7.0e6  # p_nom [Pa] of the relief valve's nominal flow (Hopsan's 70 bar)


def valve_spec(
    P: Mapping[str, float],
    geometry: Mapping[str, float] | None = None,
    initial_spool: float = 0.0,
    initial_spool_velocity: float = 0.0,
) -> ComponentSpec:
    """The valve of servo parameters ``P`` (SI): a ``linear_valve``, or a ``valve_4_3``
    whose spool diameter gives the edges' flow coefficient k = C_d·π·d·f·√(2/ρ) with the
    ``geometry`` (``discharge_coefficient``, ``density``, ``circumference_fraction``, SI)
    where the file gave it, else the component's defaults (the same k to round-off); the
    spool starts at ``initial_spool`` [m] moving at ``initial_spool_velocity`` [m/s]."""
    ports = {"P": "supply", "T": "T", "A": "A", "B": "B", "command": "demand"}
    dyn = ("none", "first_order", "second_order")[int(P["spool_order"])]
    common: dict[str, float | str] = {
        "max_stroke": P["spool_max"],
        "dynamics": dyn,
        "time_constant": P["spool_time_constant"] if dyn == "first_order" else 1.0e-3,
        "natural_frequency": P["spool_frequency"] if dyn == "second_order" else 600.0,
        "damping_ratio": P["spool_damping"] if dyn == "second_order" else 0.7,
    }
    if initial_spool != 0.0:
        common["initial_spool"] = initial_spool
    if initial_spool_velocity != 0.0:
        common["initial_spool_velocity"] = initial_spool_velocity
    if P["valve_kind"] == VALVE_LINEARISED:
        values = {"flow_gain": P["flow_gain"], "area_ratio": P["area_b"] / P["area_a"]}
        return ComponentSpec("linear_valve", "valve", ports, {**values, **common})
    # edges that differ: P→A's coefficient and overlap are the valve's, the others' the
    # valve_4_3's width ratios and extra overlaps (omitted where they are 1 and 0)
    k = P["edge_pa"]
    lap = P["lap_pa"]
    edges: dict[str, float | str] = {}
    for e in EDGES[1:]:
        if P[f"edge_{e}"] != k:
            edges[f"width_ratio_{e}"] = P[f"edge_{e}"] / k
        if P[f"lap_{e}"] != lap:
            edges[f"extra_overlap_{e}"] = P[f"lap_{e}"] - lap
    geometry = geometry or {}
    decl = TYPES["valve_4_3"].DECLARATION
    cd_default = decl.parameter("discharge_coefficient").default
    cd = float(geometry.get("discharge_coefficient", cd_default))
    rho = float(geometry.get("density", decl.parameter("density").default))
    f = float(geometry.get("circumference_fraction", 1.0))
    diameter = k / (cd * math.pi * f * math.sqrt(2.0 / rho))
    values = {
        "spool_diameter": diameter,
        "circumference_fraction": f,
        "discharge_coefficient": cd,
        "density": rho,
        "overlap": lap,
        "transition_pressure": P["transition_pressure"],
    }
    return ComponentSpec("valve_4_3", "valve", ports, {**values, **edges, **common})


def actuator_spec(P: Mapping[str, float]) -> ComponentSpec:
    hydraulic = {
        "dead_volume_a": P["dead_volume_a"],
        "dead_volume_b": P["dead_volume_b"],
        "bulk_modulus": P["bulk_modulus"],
        "air_fraction": P["air_fraction"],
        "air_exponent": P["air_exponent"],
        "internal_leakage": P["internal_leakage"],
        "external_leakage_a": P["external_leakage_a"],
        "external_leakage_b": P["external_leakage_b"],
        "tank_pressure": P["tank_pressure"],
        "viscous_friction": P["viscous_friction"],
    }
    atmosphere = TYPES["cylinder"].DECLARATION.parameter("atmospheric_pressure").default
    if P["atmospheric_pressure"] != atmosphere:  # the air fraction's reference
        hydraulic["atmospheric_pressure"] = P["atmospheric_pressure"]
    travel = P["stroke_max"] - P["stroke_min"]
    if P["load_kind"] == LOAD_ROTARY:
        geometry = {
            "displacement_a": P["area_a"],
            "displacement_b": P["area_b"],
            "travel": travel,
            "angle_at_a_end": P["stroke_min"],
        }
        ports = {"a": "A", "b": "B", "shaft": "joint"}
        return ComponentSpec("rotary_actuator", "actuator", ports, {**geometry, **hydraulic})
    geometry = {
        "area_a": P["area_a"],
        "area_b": P["area_b"],
        "stroke": travel,
        "position_at_a_end": P["stroke_min"],
    }
    ports = {"a": "A", "b": "B", "rod": "rod"}
    if P["load_kind"] == LOAD_CRANK and crank_has_friction(P):
        ports["force"] = "actuator_force"  # the crank's drive force (crank_friction)
    return ComponentSpec("cylinder", "actuator", ports, {**geometry, **hydraulic})


def _load(P: Mapping[str, float], initial: Mapping[str, float]) -> list[ComponentSpec]:
    if P["load_kind"] == LOAD_MASS:
        values = {
            "mass": P["mass"],
            "spring_rate": P["spring_rate"],
            "spring_free_position": P["spring_free_position"],
            "damping": P["damping"],
            "force": -P["external_force"],
            "coulomb_friction": P["coulomb_friction"],
            "breakaway_friction": P["breakaway_friction"],
            "position_min": P["position_min"],
            "position_max": P["position_max"],
            "initial_position": initial.get("position", 0.0),
            "initial_velocity": initial.get("velocity", 0.0),
        }
        return [ComponentSpec("mass", "load", {"body": "rod"}, values)]
    values = {
        "inertia": P["mass"],
        "spring_rate": P["spring_rate"],
        "spring_free_angle": P["spring_free_position"],
        "damping": P["damping"],
        "torque": -P["external_force"],
        "gravity_moment": P["gravity_moment"],
        "gravity_angle": P["gravity_angle"],
        "angle_min": P["position_min"],
        "angle_max": P["position_max"],
        "initial_angle": initial.get("position", 0.0),
        "initial_velocity": initial.get("velocity", 0.0),
    }
    if P["load_kind"] == LOAD_ROTARY:
        values["coulomb_friction"] = P["coulomb_friction"]
        values["breakaway_friction"] = P["breakaway_friction"]
        return [ComponentSpec("inertia", "load", {"body": "joint"}, values)]
    return [ComponentSpec("inertia", "load", {"body": "joint"}, values), crank_spec(P)]


def crank_spec(P: Mapping[str, float], angle_offset: float = 0.0) -> ComponentSpec:
    """The ``crank_linkage`` named ``crank`` of a crank load (servo parameters ``P``, SI)
    between the nodes ``joint`` and ``rod``, with its dry friction (`crank_friction`,
    driven by the signal ``actuator_force``) and the angle datum ``angle_offset`` [rad]."""
    crank: dict[str, float | str] = {
        "crank_radius": P["crank_radius"],
        "gear_ratio": P["gear_ratio"],
        "torque_arm": "kinematic" if P["kinematic_torque_arm"] != 0.0 else "paper",
        **crank_friction(P),
    }
    if angle_offset != 0.0:
        crank["angle_offset"] = angle_offset
    ports = {"joint": "joint", "rod": "rod"}
    if crank_has_friction(P):
        ports["drive_force"] = "actuator_force"
    return ComponentSpec("crank_linkage", "crank", ports, crank)


def crank_has_friction(P: Mapping[str, float]) -> bool:
    """Whether a crank load of servo parameters ``P`` has dry friction (piston or gearbox)."""
    names = ("coulomb_friction", "breakaway_friction", "gearbox_friction_torque")
    return any(P[n] != 0.0 for n in (*names, "gearbox_loss_at_stall"))


def crank_friction(P: Mapping[str, float]) -> dict[str, float]:
    """The dry friction of a crank load (servo parameters ``P``, SI) as its
    ``crank_linkage``'s values: the piston's Coulomb and breakaway force through the torque
    arm, the gearbox's no-load torque and its loss c·γᵏ, γ the actuator's pressure force
    (its ``force`` signal, wired to the linkage's ``drive_force``) over the rated
    A_a·p_rated: the law of `hydroarm.reference.servo_kernel.dry_friction_capacity`, the
    crank's projection (the paper joint's rule: the torque arm at the step's start, the
    drive force at its end, as the servo kernel takes them) applying it."""
    if not crank_has_friction(P):
        return {}
    return {
        "coulomb_friction": P["coulomb_friction"],
        "breakaway_friction": P["breakaway_friction"],
        "gearbox_friction_torque": P["gearbox_friction_torque"],
        "gearbox_loss_at_stall": P["gearbox_loss_at_stall"],
        "gearbox_loss_exponent": P["gearbox_loss_exponent"],
        "rated_force": P["area_a"] * P["rated_load_pressure"],
    }


def feedback_specs(P: Mapping[str, float]) -> list[ComponentSpec]:
    """The ``position_sensor`` and ``pid`` of servo parameters ``P`` (SI) between the
    signals ``reference``, ``measurement`` and ``demand``; a derivative gain takes the
    sensor's rate g·ẋ (the signal ``measurement_rate``): the exact derivative on the
    measurement, the servo kernel's (`hydroarm.reference.servo_kernel.spool_demand`)."""
    ports = {"reference": "reference", "measurement": "measurement", "out": "demand"}
    if P["feedback_kind"] == FEEDBACK_MECHANICAL:
        # spool demand = gain·(lever − jack): a proportional controller on the rod's position
        sensed, gain = "rod", 1.0
        pid = {"proportional_gain": P["feedback_gain"]}
    else:
        angular = P["load_kind"] != LOAD_MASS
        sensed = "rod" if P["sense_actuator"] != 0.0 or not angular else "joint"
        gain = P["sensor_gain"]
        pid = {
            "proportional_gain": P["proportional_gain"],
            "integral_gain": P["integral_gain"],
            "output_min": P["output_min"],
            "output_max": P["output_max"],
        }
        if P["derivative_gain"] != 0.0:
            pid["derivative_gain"] = P["derivative_gain"]
            ports["measurement_rate"] = "measurement_rate"
    sensor_ports = {"body": sensed, "out": "measurement"}
    if "measurement_rate" in ports:
        sensor_ports["rate"] = "measurement_rate"
    sensor = ComponentSpec("position_sensor", "sensor", sensor_ports, {"gain": gain})
    return [sensor, ComponentSpec("pid", "controller", ports, pid)]


def reference_source(ref: LeverInput, name: str = "reference") -> ComponentSpec:
    """A ``signal_source`` named ``name`` writing the signal ``name``: the steps, table or
    sine of a lever (reference) input; a sine on top of steps or a table is the source's
    added sine (`hydroarm.core.lever.evaluate`: the table's value plus the sine from its
    start)."""
    t, y = ref.times, ref.positions
    ports = {"out": name}
    sine: dict[str, float | str] = {}
    if ref.sine_amplitude != 0.0:
        sine = {
            "amplitude": ref.sine_amplitude,
            "frequency": ref.sine_frequency,
            "start_time": ref.sine_start,
        }
        if not np.any(y != y[0]):
            wave = {"waveform": "sine", "offset": float(y[0]), **sine}
            return ComponentSpec("signal_source", name, ports, wave)
    steps = (
        t.size >= 3
        and t.size % 2 == 1
        and np.array_equal(t[1::2], t[2::2])
        and np.array_equal(y[0:-1:2], y[1::2])
    )
    if t.size == 2 and t[0] == t[1]:  # one step at t0 from y0 to y1
        arrays0: dict[str, tuple[float, ...]] = {"times": (float(t[1]),), "values": (float(y[1]),)}
        start: dict[str, float | str] = {"waveform": "steps", "offset": float(y[0]), **sine}
        return ComponentSpec("signal_source", name, ports, start, arrays0)
    if steps:  # [t0, t1, t1, t2, t2 …], [y0, y0, y1, y1, y2 …]: steps at t1, t2 …
        arrays: dict[str, tuple[float, ...]] = {
            "times": (float(t[0]), *map(float, t[1::2])),
            "values": (float(y[0]), *map(float, y[2::2])),
        }
        spec: dict[str, float | str] = {"waveform": "steps", "offset": float(y[0]), **sine}
        return ComponentSpec("signal_source", name, ports, spec, arrays)
    if t.size == 1:
        return ComponentSpec(
            "signal_source", name, ports, {"waveform": "constant", "offset": float(y[0])}
        )
    table = {"times": tuple(map(float, t)), "values": tuple(map(float, y))}
    return ComponentSpec("signal_source", name, ports, {"waveform": "table", **sine}, table)


def _supply(
    P: Mapping[str, float],
    pump_speed: float | None,
    supply_pressure: float,
    relief_opening: float = 0.0,
) -> tuple[list[ComponentSpec], dict[str, float]]:
    """The supply's components and the node pressures they start at: the supply at
    ``supply_pressure`` [Pa] (the servo's initial ``supply_pressure``: a fixed supply holds
    it), a pump's relief valve at the flow coefficient ``relief_opening``."""
    p_t = P["tank_pressure"]
    tank = ComponentSpec("tank", "tank", {"port": "T"}, {"pressure": p_t})
    relief_valve = P["supply_kind"] == SUPPLY_PUMP and P["relief_pressure"] < math.inf
    # the servo kernel holds the opening within [0, x_max] (its projection at the start)
    relief_opening = min(max(relief_opening, 0.0), P["relief_max_opening"])
    if relief_opening != 0.0 and not relief_valve:
        raise HydroarmError("initial.relief_opening", "the supply has no relief valve to open")
    if P["supply_kind"] != SUPPLY_PUMP:
        source = ComponentSpec("tank", "source", {"port": "supply"}, {"pressure": supply_pressure})
        return [tank, source], {}
    # the pump's flow as a displacement per radian at 1 rad/s, unless the file gives the
    # speed it was turned at
    speed = 1.0 if pump_speed is None else pump_speed
    pump = ComponentSpec(
        "fixed_pump",
        "pump",
        {"inlet": "T", "outlet": "supply"},
        {"displacement": P["pump_flow"] / speed, "speed": speed, "leakage": P["pump_leakage"]},
    )
    parts = [tank, pump]
    volume = P["supply_volume"]
    if P["accumulator_volume"] > 0.0:
        volume -= ACCUMULATOR_NECK
        acc = {
            "gas_volume": P["accumulator_volume"],
            "precharge_pressure": P["accumulator_precharge"],
            "exponent": P["accumulator_exponent"],
            "connection_volume": ACCUMULATOR_NECK,
            "bulk_modulus": P["supply_bulk_modulus"],
        }
        parts.append(ComponentSpec("accumulator", "accumulator", {"port": "supply"}, acc))
    parts.append(
        ComponentSpec(
            "volume",
            "supply_line",
            {"port": "supply"},
            {"volume": volume, "bulk_modulus": P["supply_bulk_modulus"]},
        )
    )
    if P["relief_pressure"] < math.inf:
        root = math.sqrt(NOMINAL_RELIEF_DROP)
        relief = {
            "cracking_pressure": P["relief_pressure"],
            "time_constant": P["relief_time_constant"],
            "spring_slope": root / P["relief_spring_term"],
            "flow_force_slope": 1.0 / (P["relief_flow_term"] * root),
            "nominal_flow": P["relief_max_opening"] * root,
            "nominal_pressure_drop": NOMINAL_RELIEF_DROP,
            "transition_pressure": P["transition_pressure"],
        }
        if relief_opening != 0.0:
            relief["initial_opening"] = relief_opening
        parts.append(
            ComponentSpec("relief_valve", "relief", {"inlet": "supply", "outlet": "T"}, relief)
        )
    return parts, {"supply": supply_pressure}


def scenario_circuit(
    scenario: ServoScenario,
    valve_geometry: Mapping[str, float] | None = None,
    pump_speed: float | None = None,
) -> Circuit:
    """The circuit of a checked [`ServoScenario`][hydroarm.ServoScenario] (module doc);
    ``valve_geometry`` and ``pump_speed`` [rad/s] are what the parameter vector folds away
    (the valve's geometry, the speed the pump was turned at; `valve_spec`,
    `_supply`): they change how the circuit is written, not what it computes."""
    P = dict(zip(NAMES, default_parameters(), strict=True)) | dict(scenario.parameters)
    given = scenario.initial
    p_s = float(scenario.initial_state()[STATE_INDEX["supply_pressure"]])
    supply_parts, initial = _supply(P, pump_speed, p_s, given.get("relief_opening", 0.0))
    for k in ("pressure_a", "pressure_b"):
        if k in given:
            initial[k[-1].upper()] = given[k]
    valve = valve_spec(P, valve_geometry, given.get("spool", 0.0), given.get("spool_velocity", 0.0))
    feedback = feedback_specs(P)
    integral = given.get("integral", 0.0)
    if integral != 0.0 and P["feedback_kind"] != FEEDBACK_MECHANICAL:
        # the controller's integral (a mechanical feedback has none: `servo_states` holds
        # the servo kernel's constant)
        pid = feedback[-1]
        feedback[-1] = replace(pid, values={**pid.values, "initial_integral": integral})
    components = [
        *supply_parts,
        valve,
        actuator_spec(P),
        *_load(P, given),
        *feedback,
        reference_source(scenario.reference),
    ]
    system = {}
    if P["cavitation_pressure"] != SYSTEM.parameter("cavitation_pressure").default:
        system["cavitation_pressure"] = P["cavitation_pressure"]
    return Circuit(
        name=scenario.name,
        components=tuple(components),
        system=system,
        initial_pressure=P["tank_pressure"],
        initial=initial,
        method=scenario.method,
        step=scenario.step,
        duration=scenario.duration,
        record_every=scenario.record_every,
    )


# ------------------------------------------------------------------ stability ---
def check_states(scenario: ServoScenario, compiled: CompiledCircuit) -> np.ndarray:
    """The states of the scenario's circuit at which its step is checked (rows), those of
    `hydroarm.reference.servo_kernel.servo_jacobians` in the circuit's layout: the
    start, and the load at rest mid-stroke with each chamber at tank, half and full supply
    pressure and the spool shut and fully open either way."""
    P = dict(zip(NAMES, default_parameters(), strict=True)) | dict(scenario.parameters)
    index = {name: i for i, (name, _) in enumerate(compiled.state_names)}
    s0 = compiled.s0
    out = [s0.copy()]
    p_t = P["tank_pressure"]
    p_s = max(scenario.initial_state()[STATE_INDEX["supply_pressure"]], P["supply_pressure"], p_t)
    if P["relief_pressure"] < math.inf:
        p_s = max(p_s, P["relief_pressure"])
    mid = s0.copy()
    if P["load_kind"] == LOAD_MASS:
        position, velocity = index["rod.position"], index["rod.velocity"]
    else:
        position, velocity = index["joint.angle"], index["joint.angular_velocity"]
    if P["load_kind"] != LOAD_CRANK and math.isfinite(P["stroke_min"] + P["stroke_max"]):
        mid[position] = 0.5 * (P["stroke_min"] + P["stroke_max"])
    mid[velocity] = 0.0
    if "supply.pressure" in index:
        mid[index["supply.pressure"]] = p_s
    spool = P["spool_max"]
    for pa in (p_t, 0.5 * (p_t + p_s), p_s):
        for pb in (p_t, 0.5 * (p_t + p_s), p_s):
            for xv in (0.0, spool, -spool):
                s = mid.copy()
                s[index["A.pressure"]] = pa
                s[index["B.pressure"]] = pb
                s[index["valve.spool"]] = xv
                out.append(compiled.couple_states(s))
    return np.array(out)


def circuit_step_limit(scenario: ServoScenario) -> float | None:
    """None if the scenario's fixed step is stable for its circuit on the system kernel
    (`hydroarm.integrators.stability.circuit_step_limit` at `check_states`),
    else the largest stable step [s]: the check [`check_step`][hydroarm.ServoScenario.check_step]
    makes on the servo kernel's Jacobians, on the circuit's."""
    compiled = scenario.compiled_circuit
    names = compiled.state_names
    pressure = np.array([unit == "Pa" for _, unit in names])
    order = stability.circuit_euler_order(
        len(names), len(compiled.hydraulic), len(compiled.mechanical)
    )
    return stability.circuit_step_limit(
        scenario.method,
        scenario.step,
        0.0,
        check_states(scenario, compiled),
        compiled.P,
        compiled.net,
        pressure,
        order,
    )
