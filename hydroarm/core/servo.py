"""A valve-controlled hydraulic servo built from components (issue 14; docs/components.md).

One right-hand side for every combination of

* actuator: two chambers A and B with their own pressures, areas A_A and A_B (double-rod:
  equal; single-rod: A_B < A_A; a rotary actuator: displacements per radian), chamber
  volumes that change with stroke plus dead volumes, bulk modulus with entrained air,
  internal and external leakage, stroke limits, piston friction;
* valve: a 4/3 spool valve with four turbulent metering edges, each with its own flow
  coefficient and overlap, or the paper's linearised valve (Q_A = K_q·x_v and, matched to
  the area ratio, Q_B = −(A_B/A_A)·K_q·x_v; equal and opposite for equal areas); the spool
  with no, first- or second-order dynamics and a stroke limit;
* feedback: mechanical (spool demand = gain × (lever − jack), the paper's) or electronic (a
  position or angle sensor and a PID controller with output limits and anti-windup);
* load: a mass-spring-damper on the rod, a rotary inertia with gravity (rotary actuator), or
  the paper's crank and gearbox joint (eq. (3)–(4), with its gearbox friction);
* supply: a fixed pressure, or a fixed-displacement pump into a supply volume with a relief
  valve and a gas accumulator.

Parameters are one float64 vector (indices ``P_*``, names in `PARAMETERS`) so that a
single run and the batch engine (one row of a table per scenario) call the same compiled
function with the same type. The state is a vector (indices ``S_*``, names in
`STATES`); energies are states too (integrated with the same method), so that a run
reports its energy flows exactly.

Equations (the laws of `hydroarm.reference.servo_kernel`, the oracle of the tests; the
product runs the servo's circuit, `hydroarm.model.servo_circuit`, on the components' laws)::

    x, ẋ    = q, q̇                    (mass, rotary)   or  crank_position/velocity(θ)  (crank)
    ṗ_A     = β_e(p_A)/V_A · (Q_A − A_A·ẋ − C_i·(p_A − p_B) − C_eA·(p_A − p_T))
    ṗ_B     = β_e(p_B)/V_B · (Q_B + A_B·ẋ + C_i·(p_A − p_B) − C_eB·(p_B − p_T))
    V_A     = V_0A + A_A·(x − x_min),     V_B = V_0B + A_B·(x_max − x)
    F       = A_A·p_A − A_B·p_B − b·ẋ     (dry friction: a velocity projection after the step)
    M·q̈     = F·λ(q) − k·(q − q_0) − c·q̇ − F_ext − W·X·cos(q − θ_h)
                                      (λ = 1, or the crank's torque arm r/n or r·cos(θ/n)/n)
    spool:   x_v = clip(u)  |  τ·ẋ_v = clip(u) − x_v  |  ẍ_v = ω²·(clip(u) − x_v) − 2ζω·ẋ_v
    supply:  (V_s/β_s + C_acc(p_s))·ṗ_s = Q_pump − C_pl·(p_s − p_T) − Q_P − Q_relief

The paper's joint (lumped load pressure, `hydroarm.core.equations`) is not this model:
it stays the default of every paper scenario and runs in its own kernels.
"""

from __future__ import annotations

import numpy as np

# ---------------------------------------------------------------------------------------
# parameters: (name, unit, description); P_<NAME> is its index in the parameter vector
PARAMETERS: tuple[tuple[str, str, str], ...] = (
    # actuator
    ("area_a", "m²", "piston area of chamber A (rotary: displacement per radian, m³/rad)"),
    ("area_b", "m²", "piston area of chamber B (annulus of a single-rod jack)"),
    ("stroke_min", "m", "actuator position at the A-side stroke end (chamber A smallest)"),
    ("stroke_max", "m", "actuator position at the B-side stroke end"),
    ("dead_volume_a", "m³", "chamber A volume at stroke_min, lines included"),
    ("dead_volume_b", "m³", "chamber B volume at stroke_max, lines included"),
    ("bulk_modulus", "Pa", "oil bulk modulus"),
    ("air_fraction", "-", "free-air volume fraction at atmospheric pressure"),
    ("air_exponent", "-", "polytropic exponent of the entrained air"),
    ("internal_leakage", "m³/(s Pa)", "leakage A to B across the piston"),
    ("external_leakage_a", "m³/(s Pa)", "leakage from chamber A to tank"),
    ("external_leakage_b", "m³/(s Pa)", "leakage from chamber B to tank"),
    ("coulomb_friction", "N", "piston Coulomb (sliding) friction"),
    ("breakaway_friction", "N", "piston breakaway (stiction) force"),
    ("viscous_friction", "N s/m", "piston viscous friction"),
    ("cavitation_pressure", "Pa", "lowest absolute chamber pressure (cavitation floor)"),
    ("atmospheric_pressure", "Pa", "atmospheric pressure (the air fraction's reference)"),
    # valve
    ("valve_kind", "-", "VALVE_SPOOL or VALVE_LINEARISED"),
    ("edge_pa", "m² s⁻¹ Pa⁻¹ᐟ²", "flow coefficient C_q·w·√(2/ρ) of edge P→A"),
    ("edge_at", "m² s⁻¹ Pa⁻¹ᐟ²", "flow coefficient of edge A→T"),
    ("edge_pb", "m² s⁻¹ Pa⁻¹ᐟ²", "flow coefficient of edge P→B"),
    ("edge_bt", "m² s⁻¹ Pa⁻¹ᐟ²", "flow coefficient of edge B→T"),
    ("lap_pa", "m", "overlap of edge P→A (negative: underlap)"),
    ("lap_at", "m", "overlap of edge A→T"),
    ("lap_pb", "m", "overlap of edge P→B"),
    ("lap_bt", "m", "overlap of edge B→T"),
    ("flow_gain", "m²/s", "linearised valve: Q_A = K_q·x_v, Q_B = −(A_B/A_A)·K_q·x_v"),
    ("spool_max", "m", "largest spool stroke |x_v|"),
    ("spool_order", "-", "spool dynamics: 0 none, 1 first order, 2 second order"),
    ("spool_time_constant", "s", "first-order spool time constant"),
    ("spool_frequency", "rad/s", "second-order spool natural frequency"),
    ("spool_damping", "-", "second-order spool damping ratio"),
    ("transition_pressure", "Pa", "orifice laminar-turbulent regularisation pressure"),
    # feedback
    ("feedback_kind", "-", "FEEDBACK_MECHANICAL or FEEDBACK_ELECTRONIC"),
    ("feedback_gain", "m/m", "mechanical: spool demand per metre of lever minus jack"),
    ("sense_actuator", "-", "electronic: 1 senses the actuator position, 0 the load's"),
    ("sensor_gain", "-", "electronic: sensor output per unit of position or angle"),
    ("proportional_gain", "m/unit", "PID proportional gain"),
    ("integral_gain", "m/(unit s)", "PID integral gain"),
    ("derivative_gain", "m s/unit", "PID derivative gain (on the measurement)"),
    ("output_min", "m", "lower limit of the controller output (spool demand)"),
    ("output_max", "m", "upper limit of the controller output"),
    # load
    ("load_kind", "-", "LOAD_MASS, LOAD_ROTARY or LOAD_CRANK"),
    ("mass", "kg", "moving mass (rotary and crank: inertia about the joint, kg m²)"),
    ("spring_rate", "N/m", "spring to ground (rotary, crank: N m/rad)"),
    ("spring_free_position", "m", "position at which the spring is free (rad)"),
    ("damping", "N s/m", "viscous damping to ground (N m s/rad)"),
    ("external_force", "N", "constant force opposing positive motion (N m)"),
    ("gravity_moment", "N m", "W·X of a rotary or crank load"),
    ("gravity_angle", "rad", "angle at which the gravity torque is largest"),
    ("position_min", "m", "load end stop, lower (rad)"),
    ("position_max", "m", "load end stop, upper (rad)"),
    ("crank_radius", "m", "crank radius r"),
    ("gear_ratio", "-", "gearbox ratio n"),
    ("kinematic_torque_arm", "-", "1: torque arm r·cos(θ/n)/n, 0: r/n (eq. 3 as printed)"),
    ("gearbox_friction_torque", "N m", "gearbox no-load friction torque"),
    ("gearbox_loss_at_stall", "-", "gearbox loss fraction at the rated load"),
    ("gearbox_loss_exponent", "-", "exponent of the gearbox loss law"),
    ("rated_load_pressure", "Pa", "load pressure of the gearbox's rated load"),
    # supply
    ("supply_kind", "-", "SUPPLY_FIXED or SUPPLY_PUMP"),
    ("supply_pressure", "Pa", "fixed supply pressure (pump: initial pressure)"),
    ("tank_pressure", "Pa", "tank (return) pressure"),
    ("pump_flow", "m³/s", "geometric pump flow D·ω/(2π)"),
    ("pump_leakage", "m³/(s Pa)", "pump leakage coefficient"),
    ("supply_volume", "m³", "oil volume between pump, valve and relief valve"),
    ("supply_bulk_modulus", "Pa", "bulk modulus of the supply volume"),
    ("relief_pressure", "Pa", "relief valve cracking pressure (inf: no relief valve)"),
    ("relief_time_constant", "s", "relief valve spool time constant (0: static)"),
    ("relief_spring_term", "Pa¹ᐟ² s/m³", "C_s = √p_nom/k_cs of the relief valve"),
    ("relief_flow_term", "Pa⁻¹ᐟ² s/m³", "C_f = 1/(k_cf·√p_nom) of the relief valve"),
    ("relief_max_opening", "m³ s⁻¹ Pa⁻¹ᐟ²", "x_max = q_nom/√p_nom of the relief valve"),
    ("accumulator_precharge", "Pa", "gas precharge pressure"),
    ("accumulator_volume", "m³", "gas volume at precharge (0: none)"),
    ("accumulator_exponent", "-", "polytropic exponent of the gas"),
)
N_PARAMETERS = len(PARAMETERS)
PARAMETER_INDEX = {name: i for i, (name, _, _) in enumerate(PARAMETERS)}

(
    P_AREA_A,
    P_AREA_B,
    P_STROKE_MIN,
    P_STROKE_MAX,
    P_DEAD_A,
    P_DEAD_B,
    P_BETA,
    P_AIR,
    P_AIR_EXP,
    P_LEAK_INT,
    P_LEAK_EXT_A,
    P_LEAK_EXT_B,
    P_F_COULOMB,
    P_F_STATIC,
    P_VISCOUS,
    P_P_CAV,
    P_P_ATM,
    P_VALVE,
    P_K_PA,
    P_K_AT,
    P_K_PB,
    P_K_BT,
    P_LAP_PA,
    P_LAP_AT,
    P_LAP_PB,
    P_LAP_BT,
    P_FLOW_GAIN,
    P_SPOOL_MAX,
    P_SPOOL_ORDER,
    P_SPOOL_TAU,
    P_SPOOL_OMEGA,
    P_SPOOL_ZETA,
    P_P_TRANS,
    P_FEEDBACK,
    P_FB_GAIN,
    P_SENSE_ACT,
    P_SENSOR_GAIN,
    P_KP,
    P_KI,
    P_KD,
    P_U_MIN,
    P_U_MAX,
    P_LOAD,
    P_MASS,
    P_SPRING,
    P_SPRING_FREE,
    P_DAMPING,
    P_FORCE,
    P_GRAV_MOMENT,
    P_GRAV_ANGLE,
    P_Q_MIN,
    P_Q_MAX,
    P_CRANK_R,
    P_CRANK_N,
    P_KIN_ARM,
    P_GB_T0,
    P_GB_LOSS,
    P_GB_EXP,
    P_RATED,
    P_SUPPLY,
    P_P_SUPPLY,
    P_P_TANK,
    P_PUMP_Q,
    P_PUMP_LEAK,
    P_SUPPLY_VOL,
    P_SUPPLY_BETA,
    P_RELIEF_P,
    P_RELIEF_TAU,
    P_RELIEF_CS,
    P_RELIEF_CF,
    P_RELIEF_XMAX,
    P_ACC_P0,
    P_ACC_V0,
    P_ACC_N,
) = range(N_PARAMETERS)

VALVE_SPOOL = 0  # 4/3 spool valve, four turbulent metering edges
VALVE_LINEARISED = 1  # linearised valve, Q_A = K_q·x_v, Q_B = −(A_B/A_A)·K_q·x_v
FEEDBACK_MECHANICAL = 0  # spool demand = gain·(lever − jack), the paper's
FEEDBACK_ELECTRONIC = 1  # sensor + PID
LOAD_MASS = 0  # mass-spring-damper on the rod: q = x
LOAD_ROTARY = 1  # rotary actuator driving an inertia: q = x (an angle)
LOAD_CRANK = 2  # the paper's crank and gearbox: x = r·sin(q/n)
SUPPLY_FIXED = 0
SUPPLY_PUMP = 1

# ---------------------------------------------------------------------------------------
# state: (name, unit, description); S_<NAME> is its index in the state vector
STATES: tuple[tuple[str, str, str], ...] = (
    ("position", "m", "load position (rotary, crank: angle, rad)"),
    ("velocity", "m/s", "load velocity (rad/s)"),
    ("pressure_a", "Pa", "chamber A pressure (absolute)"),
    ("pressure_b", "Pa", "chamber B pressure (absolute)"),
    ("spool", "m", "spool position"),
    ("spool_velocity", "m/s", "spool velocity (second-order spool)"),
    ("integral", "unit s", "integral of the controller error"),
    ("supply_pressure", "Pa", "supply pressure (absolute)"),
    ("relief_opening", "m³ s⁻¹ Pa⁻¹ᐟ²", "relief valve flow coefficient"),
    ("supply_energy", "J", "hydraulic energy delivered by the supply (pump: at its shaft)"),
    ("relief_energy", "J", "energy dissipated in the relief valve"),
    ("throttle_energy", "J", "energy dissipated in the valve's metering edges"),
    ("actuator_work", "J", "work of the chamber pressures above tank on the piston"),
    ("leakage_energy", "J", "energy dissipated by actuator and pump leakage"),
    ("compression_energy", "J", "energy stored by compressing the oil, ∫(p − p_T)·(V/β_e)·ṗ"),
)
N_STATES = len(STATES)
STATE_INDEX = {name: i for i, (name, _, _) in enumerate(STATES)}
(
    S_Q,
    S_V,
    S_PA,
    S_PB,
    S_XV,
    S_VV,
    S_INT,
    S_PS,
    S_XR,
    S_E_SUPPLY,
    S_E_RELIEF,
    S_E_THROTTLE,
    S_E_ACT,
    S_E_LEAK,
    S_E_COMP,
) = range(N_STATES)


def default_parameters() -> np.ndarray:
    """A parameter vector with every component off or neutral: no air, no leakage, no
    friction, no spring, no relief valve, no accumulator, unlimited stops and controller
    output, tank at 1 bar; the caller sets the rest."""
    P = np.zeros(N_PARAMETERS)
    P[P_AIR_EXP] = 1.0
    P[P_P_CAV] = 0.0
    P[P_P_ATM] = 101325.0
    P[P_P_TRANS] = 1.0e4
    P[P_SENSOR_GAIN] = 1.0
    P[P_FB_GAIN] = 1.0
    P[P_U_MIN] = -np.inf
    P[P_U_MAX] = np.inf
    P[P_Q_MIN] = -np.inf
    P[P_Q_MAX] = np.inf
    P[P_CRANK_N] = 1.0
    P[P_GB_EXP] = 1.0
    P[P_RATED] = np.inf
    P[P_P_TANK] = 1.0e5
    P[P_RELIEF_P] = np.inf
    P[P_ACC_N] = 1.0
    P[P_SUPPLY_BETA] = 1.0e9
    P[P_SPOOL_ZETA] = 1.0
    return P
