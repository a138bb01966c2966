"""Equations of motion of the hydraulic servo joint (Appendix I of the UCL arm paper).

Pure functions on SI floats, compiled with numba. ``J`` is the joint
(`JointParams`), ``L`` its load
(`LoadParams`). State: joint angle θ₂ [rad], angular velocity
ω [rad/s], load pressure p [Pa]; input: lever (valve spool) position y [m] in jack coordinates.

Equations (numbers as in the paper's Appendix I; reading adopted in docs/model.md):

(1) valve flow = displacement + leakage + compressibility::

        K_q·e = A·ẋ + 2·L·p + (V/β)·ṗ,          K_q = K·√(p_s/2)

(2) saturating valve opening::

        e = clip(y − x, −e_o, +e_o)

(3) torque balance at the joint::

        A·p·r/n = I·θ̈₂ + W·X·cos(θ₂ − θ_h)      (θ_h = 30° in the paper's datum)

(4) crank and gearbox kinematics::

        θ₂ = n·asin(x/r)   ⇔   x = r·sin(θ₂/n),  ẋ = r·cos(θ₂/n)·θ̇₂/n

    (in `hydroarm.core.kinematics`, with the torque arm of eq. (3))

Physics options beyond the paper (docs/physics.md), selected by fields of ``J``:

(O1) orifice valve: the flow K_q·e of eq. (1) becomes K·e·√((p_s − sgn(e)·p)/2), with the
     square root regularised below the transition pressure p_t;
(O2) viscous piston friction b·ẋ, in `angular_acceleration`;
(O3) dry friction (piston Coulomb/stiction, gearbox load-dependent loss) and end stops:
     not part of this smooth right-hand side; the step kernel applies them as a velocity
     projection (`hydroarm.integrators.fixed`), so that sticking is exact;
(O6) valve leakage at null: a flow 2·L₀·p·(1 − (e/e_o)²) from the high- to the low-pressure
     side, the flow-pressure coefficient K_c0 = 2·L₀ of a real critically-centred valve at
     null (radial clearance), fading to none at full opening; in `pressure_rate`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kinematics import crank_position, crank_torque_arm, crank_velocity
from .params import TORQUE_ARM_KINEMATIC, VALVE_LINEAR
from .trig import cos


@njit(cache=True, nogil=True, error_model="numpy")
def jack_position(theta, J):
    """Jack position x = r·sin(θ₂/n) [m], eq. (4)."""
    return crank_position(theta, J.crank_radius, J.gear_ratio)


@njit(cache=True, nogil=True, error_model="numpy")
def jack_velocity(theta, omega, J):
    """Jack velocity ẋ = r·cos(θ₂/n)·θ̇₂/n [m/s], time derivative of eq. (4)."""
    return crank_velocity(theta, omega, J.crank_radius, J.gear_ratio)


@njit(cache=True, nogil=True, error_model="numpy")
def jack_position_trace(theta, J):
    """`jack_position` of every angle of an array [m]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = jack_position(theta[i], J)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def jack_velocity_trace(theta, omega, J):
    """`jack_velocity` of every (angle, velocity) pair of two arrays [m/s]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = jack_velocity(theta[i], omega[i], J)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def valve_opening(y, x, J):
    """Valve opening e = y − x saturated at ±e_o [m], eq. (2). Floats or arrays."""
    e_o = J.valve_saturation
    return np.minimum(np.maximum(y - x, -e_o), e_o)


@njit(cache=True, nogil=True, error_model="numpy")
def flow_gain(J):
    """K_q = K·√(p_s/2) [m²/s], the linearised valve flow gain of eq. (1)."""
    return J.flow_coefficient * np.sqrt(0.5 * J.supply_pressure)


@njit(cache=True, nogil=True, error_model="numpy")
def torque_arm(theta, J):
    """Jack force to joint torque lever [m]: r/n (eq. (3) as printed) or r·cos(θ₂/n)/n."""
    return crank_torque_arm(
        theta, J.crank_radius, J.gear_ratio, J.torque_arm == TORQUE_ARM_KINEMATIC
    )


@njit(cache=True, nogil=True, error_model="numpy")
def gravity_torque(theta, J, L):
    """Gravity load torque W·X·cos(θ₂ − θ_h) + T [N m], last term of eq. (3) (T: a torque
    given directly, the whole arm's pose load)."""
    g = L.weight * L.arm * cos(theta - J.horizontal_angle)
    if L.torque != 0.0:
        g += L.torque
    return g


@njit(cache=True, nogil=True, error_model="numpy")
def signed_sqrt(u, u_t):
    """Regularised signed square root u/(u² + u_t²)^¼: √u for u ≫ u_t, linear near 0 [√Pa].

    The fourth root as two square roots, √√x: within an ulp of pow(x, ¼) (the same law,
    rounded otherwise) and 2.4 times cheaper; pow was the largest single cost of a valve's or
    an orifice's law (benchmarks/circuit_throughput.py). Its round-off once left the
    excavator's operating point 2.3e-7 off; the steady solve's Newton polish has since made
    that solve robust to it (`hydroarm.model.circuit_steady.newton_polish`)."""
    return u / np.sqrt(np.sqrt(u * u + u_t * u_t))


@njit(cache=True, nogil=True, error_model="numpy")
def valve_flow(e, p, J):
    """Load flow delivered by the joint's valve [m³/s] at opening e [m] and load pressure p
    [Pa]: `load_flow` with the joint's valve (eq. 1, or option O1)."""
    return load_flow(
        e,
        p,
        J.supply_pressure,
        J.flow_coefficient,
        J.valve_model != VALVE_LINEAR,
        J.transition_pressure,
    )


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def load_flow(e, p, supply, flow_coefficient, orifice, transition):
    """Load flow [m³/s] of the paper's servo valve at opening e [m], load pressure p [Pa] and
    supply pressure p_s [Pa] (K: ``flow_coefficient`` [m² s⁻¹ Pa⁻¹ᐟ²]; p_t: ``transition``
    [Pa]). One law for the paper's joint and the circuit's ``servo_jack``.

    Paper (eq. 1): K_q·e with K_q = K·√(p_s/2). Orifice option (O1, ``orifice`` true): a
    critically-centred 4-way valve whose two metering edges pass K·e·√(p_s − p_A) into one
    chamber and K·e·√(p_B) out of the other; with p_A + p_B = p_s and p = p_A − p_B both
    equal K·e·√((p_s − sgn(e)·p)/2), the classical load-flow law (Merritt 1967, eq. 5-35),
    its square root regularised below p_t.
    """
    if not orifice:
        return flow_coefficient * np.sqrt(0.5 * supply) * e
    s = 1.0 if e >= 0.0 else -1.0
    return flow_coefficient * e * signed_sqrt(0.5 * (supply - s * p), 0.5 * transition)


@njit(cache=True, nogil=True, error_model="numpy")
def null_leakage_flow(e, p, J):
    """The joint valve's leakage at null [m³/s] (option O6): `lumped_null_leakage`."""
    return lumped_null_leakage(e, p, J.valve_saturation, J.null_leakage_coefficient)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def lumped_null_leakage(e, p, saturation, coefficient):
    """Valve leakage at null [m³/s] (option O6): 2·L₀·p·(1 − (e/e_o)²) at opening e [m]
    (|e| ≤ e_o, the ``saturation``) and load pressure p [Pa], L₀ the ``coefficient``.

    The flow-pressure coefficient K_c0 = 2·L₀ that the clearance of a real critically-centred
    spool gives at null (Merritt 1967, §5.4), where the orifice law of (O1) has none; it
    fades smoothly (no slope at null, so the flow gain there is the orifice's) to nothing at
    full opening, where the orifice's own K_c = ∂Q/∂p dominates and the saturated flow is
    the orifice law's alone."""
    u = e / saturation
    return 2.0 * coefficient * p * (1.0 - u * u)


@njit(cache=True, nogil=True, error_model="numpy")
def supply_flow(e, p, J):
    """Flow drawn from the supply [m³/s] at opening e [m] and load pressure p [Pa]: the
    supply edge passes the load flow of `valve_flow`, whichever way the valve is open
    (negative: flow driven back into the supply, p above it). The whole arm's pump balance
    sums it over the joints."""
    q = valve_flow(e, p, J)
    return q if e >= 0 else -q


@njit(cache=True, nogil=True, error_model="numpy")
def joint_outputs(theta, omega, p, y, J):
    """What follows from a joint's state (θ₂ [rad], ω [rad/s], p [Pa]) and lever y [m], in one
    call: (x [m], ẋ [m/s], actuator torque [N m], supply flow [m³/s], valve opening [m])."""
    x = jack_position(theta, J)
    e = valve_opening(y, x, J)
    return x, jack_velocity(theta, omega, J), actuator_torque(theta, p, J), supply_flow(e, p, J), e


@njit(cache=True, nogil=True, error_model="numpy")
def pressure_limit(J):
    """Largest |p| [Pa] with no chamber below zero absolute pressure (orifice option), for
    chamber pressures (p_rated ± p)/2 about the rated supply: a joint whose supply sags on a
    shared pump (the whole arm) keeps the load pressure its closed valve traps."""
    return lumped_pressure_limit(J.rated_supply_pressure, J.atmospheric_pressure)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def lumped_pressure_limit(rated_supply, atmospheric):
    """Largest |p| [Pa] with no chamber below zero absolute pressure, p_rated + 2·p_atm, for
    chamber pressures (p_rated ± p)/2 about the rated supply [Pa] (the orifice valve's
    cavitation floor; `pressure_limit`)."""
    return rated_supply + 2.0 * atmospheric


@njit(cache=True, nogil=True, error_model="numpy")
def pressure_rate(theta, omega, p, y, J):
    """ṗ [Pa/s] from eq. (1) with the valve opening of eq. (2)."""
    x = jack_position(theta, J)
    xdot = jack_velocity(theta, omega, J)
    e = valve_opening(y, x, J)
    return load_pressure_rate(
        valve_flow(e, p, J),
        xdot,
        p,
        e,
        J.piston_area,
        J.leakage_coefficient,
        J.null_leakage_coefficient,
        J.valve_saturation,
        J.bulk_modulus,
        J.trapped_volume,
    )


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def load_pressure_rate(q, xdot, p, e, area, leakage, null_leakage, saturation, bulk, volume):
    """ṗ [Pa/s] of the lumped load pressure, eq. (1): (V/β)·ṗ = q − A·ẋ − 2·L·p, with q the
    valve's load flow [m³/s] (`load_flow`), ẋ the jack's velocity [m/s], L the
    leakage coefficient [m³ s⁻¹ Pa⁻¹] and, with L₀ = ``null_leakage`` ≠ 0, less the valve's
    leakage at null at opening e (option O6). One law for the paper's joint and the
    circuit's ``servo_jack``."""
    q_net = q - area * xdot - 2.0 * leakage * p
    if null_leakage != 0.0:  # option O6: the valve's leakage at null
        q_net -= lumped_null_leakage(e, p, saturation, null_leakage)
    return bulk / volume * q_net


@njit(cache=True, nogil=True, error_model="numpy")
def actuator_torque(theta, p, J):
    """Jack torque at the joint A·p·r/n (eq. 3) or A·p·r·cos(θ₂/n)/n (kinematic) [N m]."""
    return J.piston_area * p * torque_arm(theta, J)


@njit(cache=True, nogil=True, error_model="numpy")
def angular_acceleration(theta, omega, p, J, L):
    """θ̈₂ [rad/s²] from eq. (3): (A·p·r/n − W·X·cos(θ₂ − θ_h) − viscous) / I (no dry friction)."""
    lever = torque_arm(theta, J)
    torque = J.piston_area * p * lever - gravity_torque(theta, J, L)
    if J.viscous_friction != 0.0:  # option O2: b·ẋ at the piston
        torque -= J.viscous_friction * jack_velocity(theta, omega, J) * lever
    return torque * (1.0 / L.inertia)


@njit(cache=True, nogil=True, error_model="numpy")
def derivatives(theta, omega, p, y, J, L):
    """Smooth right-hand side (θ̇₂, θ̈₂, ṗ) of eqs. (1)–(4) (dry friction excluded)."""
    return (
        omega,
        angular_acceleration(theta, omega, p, J, L),
        pressure_rate(theta, omega, p, y, J),
    )


@njit(cache=True, nogil=True, error_model="numpy")
def dry_friction_torque(theta, p, breakaway, J):
    """Dry friction torque capacity at the joint [N m] (option O3), always ≥ 0.

    Piston friction F (Coulomb, or the stiction force when ``breakaway``) through the crank,
    plus the gearbox: a load-independent torque T_g0 and a load-dependent loss
    c_stall·γᵏ·|A·p·arm| with γ = |p|/p_rated the actuator load as a fraction of its rated
    stall (capped at 1: a pressure above the rated supply loses no more than at stall).
    """
    lever = torque_arm(theta, J)
    f = J.breakaway_friction if breakaway else J.coulomb_friction
    gamma = min(abs(p) / J.rated_supply_pressure, 1.0)
    return friction_capacity(
        f,
        lever,
        J.gearbox_friction_torque,
        J.gearbox_loss_at_stall,
        J.gearbox_loss_exponent,
        gamma,
        J.piston_area * p * lever,
    )


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def friction_capacity(force, lever, gearbox_torque, loss_at_stall, loss_exponent, gamma, drive):
    """Dry friction torque capacity [N m] (option O3): a piston force [N] through the lever
    [m], the gearbox's no-load torque [N m] and its load-dependent loss c·γᵏ·|drive| with
    γ ≤ 1 the load fraction and ``drive`` the actuator torque [N m]. One law for the paper's
    joint and the component servo's crank (`hydroarm.core.servo`)."""
    loss = loss_at_stall * gamma**loss_exponent
    return force * abs(lever) + gearbox_torque + loss * abs(drive)


# A state with |p| above PRESSURE_BOUND_FACTOR × the largest pressure scale of the joint
# (supply, start pressure, the load held with the paper's torque arm, the oil column's
# surge when the jack is stopped from full speed) is out of the physics' reach: the run
# stops there (docs/errors.md).
PRESSURE_BOUND_FACTOR = 4.0


@njit(cache=True, nogil=True, error_model="numpy")
def pressure_bound(p0, J, L):
    """Largest |p| [Pa] a valid run can reach: 4 × max(p_s, |p₀|, p_hold, p_surge).

    p_hold = (W·X + |T|)·n/(A·r) holds the load with the paper's torque arm; p_surge =
    v·(n/r)·√(β·I/V), v = K_q·e_o/A the full-opening velocity, is the pressure of the oil
    column stopping (or starting) the load from full speed: the linear valve of eq. (1)
    delivers its flow at any pressure, so the model's own pressure can exceed the supply by
    that much. Beyond the bound the state has left the physics (a numerically unstable step);
    the fixed-step kernels stop there and report it."""
    lever = J.crank_radius / J.gear_ratio
    hold = (abs(L.weight * L.arm) + abs(L.torque)) / (J.piston_area * lever)
    k_q = J.flow_coefficient * np.sqrt(0.5 * J.rated_supply_pressure)  # at the rated supply
    v_full = k_q * J.valve_saturation / J.piston_area
    surge = v_full / lever * np.sqrt(J.bulk_modulus * L.inertia / J.trapped_volume)
    return PRESSURE_BOUND_FACTOR * max(J.rated_supply_pressure, abs(p0), hold, surge)


@njit(cache=True, nogil=True, error_model="numpy")
def crank_reach(J):
    """Largest |θ₂| [rad] the crank can reach, n·90° (the dead centre, x = ±r)."""
    return J.gear_ratio * (0.5 * np.pi)


@njit(cache=True, nogil=True, error_model="numpy")
def holding_pressure(theta, J, L):
    """Load pressure [Pa] that holds the load still at θ₂ (eq. (3) with θ̈₂ = 0)."""
    return gravity_torque(theta, J, L) / (J.piston_area * torque_arm(theta, J))


@njit(cache=True, nogil=True, error_model="numpy")
def valve_flow_trace(e, p, J):
    """`valve_flow` of every (opening, pressure) pair of two arrays [m³/s]."""
    out = np.empty(e.shape)
    for i in range(e.size):
        out[i] = valve_flow(e[i], p[i], J)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def null_leakage_trace(e, p, J):
    """`null_leakage_flow` of every (opening, pressure) pair of two arrays [m³/s]."""
    out = np.empty(e.shape)
    for i in range(e.size):
        out[i] = null_leakage_flow(e[i], p[i], J)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def dry_friction_trace(theta, p, J):
    """`dry_friction_torque` (sliding) of every (angle, pressure) pair [N m]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = dry_friction_torque(theta[i], p[i], False, J)
    return out


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def stick_or_slide(v, v_star, slide, hold):
    """Velocity after one step of dry friction (module doc): v the velocity before the step,
    v* the one the step reaches without dry friction, ``slide`` and ``hold`` the velocities
    the sliding and (from rest) breakaway friction can remove in one step. One rule for
    every kernel (the paper's joint, the component servo)."""
    if v == 0.0:  # at rest: stuck unless the drive exceeds the breakaway torque
        if abs(v_star) <= hold:
            return 0.0
    elif abs(v_star) <= slide:
        return 0.0
    return v_star - slide if v_star > 0.0 else v_star + slide
