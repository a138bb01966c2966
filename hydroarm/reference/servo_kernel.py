"""The component servo's hand-fused kernel, held apart as a reference (`hydroarm.reference`).

The component servo runs on the system kernel (`hydroarm.model.servo_circuit` writes a
`ServoScenario` as a circuit). This kernel is no product path's physics: the tests and
benchmarks compare with it (`hydroarm.reference.servo`, `hydroarm.reference.servo_metrics`,
`hydroarm.reference.servo_adaptive`, `hydroarm.reference.arm_decoupled`). Its declarations
(parameters, states, their indices, kinds and defaults) stay the shorthand's,
`hydroarm.core.servo`; here are its laws (`servo_rhs` and the terms it is made of, the
equations of `hydroarm.core.servo`'s module doc), its fixed-step integration and its
stability check (`servo_step_limit`).

Its fixed-step integration: the same two methods as the paper's joint
(`hydroarm.integrators.fixed`), on the servo's state vector:

* ``euler``: the paper's order of eqs. (5)–(7) generalised: every state but the load's
  position and velocity is advanced first (pressures, spool, controller, supply, energies),
  then the velocity from the new pressures, then the position from the new velocity
  (semi-implicit Euler, first order);
* ``rk4``: classical fourth-order Runge–Kutta.

After the smooth update the step applies the non-smooth parts as projections, as the
paper's kernel does: dry friction (`stick_or_slide`, the
one rule), inelastic end stops of the load and of the actuator's stroke, the spool's stroke
limit, the cavitation floor of the chambers and the supply, and the relief valve's opening
range. One compiled step serves a single run and every row of the batch engine
(`run_many`), so the two are equal bit for bit.

`advance_steps` is the one loop (steps from a state); `integrate` runs it from a
state to each record, `run_many` for every row of a parameter table in parallel,
`advance` piece by piece for a caller that owns the clock.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..core.components import (
    accumulator_capacitance,
    effective_bulk_modulus,
    linearised_valve_flows,
    pid_output,
    relief_flow,
    relief_static_opening,
    spool_valve_flows,
)
from ..core.equations import friction_capacity
from ..core.kinematics import crank_position, crank_torque_arm, crank_velocity
from ..core.lever import evaluate
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    N_STATES,
    P_ACC_N,
    P_ACC_P0,
    P_ACC_V0,
    P_AIR,
    P_AIR_EXP,
    P_AREA_A,
    P_AREA_B,
    P_BETA,
    P_CRANK_N,
    P_CRANK_R,
    P_DAMPING,
    P_DEAD_A,
    P_DEAD_B,
    P_F_COULOMB,
    P_F_STATIC,
    P_FB_GAIN,
    P_FEEDBACK,
    P_FLOW_GAIN,
    P_FORCE,
    P_GB_EXP,
    P_GB_LOSS,
    P_GB_T0,
    P_GRAV_ANGLE,
    P_GRAV_MOMENT,
    P_K_AT,
    P_K_BT,
    P_K_PA,
    P_K_PB,
    P_KD,
    P_KI,
    P_KIN_ARM,
    P_KP,
    P_LAP_AT,
    P_LAP_BT,
    P_LAP_PA,
    P_LAP_PB,
    P_LEAK_EXT_A,
    P_LEAK_EXT_B,
    P_LEAK_INT,
    P_LOAD,
    P_MASS,
    P_P_ATM,
    P_P_CAV,
    P_P_SUPPLY,
    P_P_TANK,
    P_P_TRANS,
    P_PUMP_LEAK,
    P_PUMP_Q,
    P_Q_MAX,
    P_Q_MIN,
    P_RATED,
    P_RELIEF_CF,
    P_RELIEF_CS,
    P_RELIEF_P,
    P_RELIEF_TAU,
    P_RELIEF_XMAX,
    P_SENSE_ACT,
    P_SENSOR_GAIN,
    P_SPOOL_MAX,
    P_SPOOL_OMEGA,
    P_SPOOL_ORDER,
    P_SPOOL_TAU,
    P_SPOOL_ZETA,
    P_SPRING,
    P_SPRING_FREE,
    P_STROKE_MAX,
    P_STROKE_MIN,
    P_SUPPLY,
    P_SUPPLY_BETA,
    P_SUPPLY_VOL,
    P_U_MAX,
    P_U_MIN,
    P_VALVE,
    P_VISCOUS,
    S_E_ACT,
    S_E_COMP,
    S_E_LEAK,
    S_E_RELIEF,
    S_E_SUPPLY,
    S_E_THROTTLE,
    S_INT,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_VV,
    S_XR,
    S_XV,
    SUPPLY_PUMP,
    VALVE_LINEARISED,
)
from ..core.trig import cos
from ..integrators.finite import all_finite
from ..integrators.fixed import EULER, stick_or_slide
from ..integrators.stability import SCAN_LOW, all_stable, largest_stable_step_for


# ------------------------------------------------------------------------- laws ---
@njit(cache=True, nogil=True, error_model="numpy")
def actuator_motion(q, v, P):
    """(x, ẋ, λ): actuator position [m], velocity [m/s] and the lever λ from actuator force
    to the load's generalised force (1, or the crank's torque arm [m]) at load state (q, q̇)."""
    if P[P_LOAD] == LOAD_CRANK:
        r = P[P_CRANK_R]
        n = P[P_CRANK_N]
        return (
            crank_position(q, r, n),
            crank_velocity(q, v, r, n),
            crank_torque_arm(q, r, n, P[P_KIN_ARM] != 0.0),
        )
    return q, v, 1.0


@njit(cache=True, nogil=True, error_model="numpy")
def chamber_volumes(x, P):
    """(V_A, V_B) [m³] at actuator position x [m]."""
    v_a = P[P_DEAD_A] + P[P_AREA_A] * (x - P[P_STROKE_MIN])
    v_b = P[P_DEAD_B] + P[P_AREA_B] * (P[P_STROKE_MAX] - x)
    return v_a, v_b


@njit(cache=True, nogil=True, error_model="numpy")
def spool_demand(t_ref, s, x, v_x, P):
    """(u, İ): the spool demand [m] of the feedback at reference ``t_ref`` (a lever position
    in actuator coordinates for mechanical feedback; the sensor's reference for electronic),
    limited to the spool stroke, and the rate of the controller's error integral."""
    if P[P_FEEDBACK] == FEEDBACK_MECHANICAL:
        u = P[P_FB_GAIN] * (t_ref - x)
        rate_i = 0.0
    else:
        if P[P_SENSE_ACT] != 0.0:
            meas, rate = x, v_x
        else:
            meas, rate = s[S_Q], s[S_V]
        k = P[P_SENSOR_GAIN]
        err = t_ref - k * meas
        u, runs = pid_output(
            err, s[S_INT], -k * rate, P[P_KP], P[P_KI], P[P_KD], P[P_U_MIN], P[P_U_MAX]
        )
        rate_i = runs * err
    lim = P[P_SPOOL_MAX]
    return min(max(u, -lim), lim), rate_i


@njit(cache=True, nogil=True, error_model="numpy")
def valve_flows(x_v, s, P):
    """(Q_A, Q_B, Q_P, throttle power) of the valve at spool position x_v [m] and state s
    (`spool_valve_flows`). The linearised valve passes
    q = K_q·x_v into A and α·q out of B, α = A_B/A_A (a valve matched to the actuator's
    area ratio, so that both chambers see the same piston speed; α = 1: the paper's valve),
    P→A and B→T for x_v > 0, P→B and A→T otherwise, each edge throttling q·Δp."""
    if P[P_VALVE] == VALVE_LINEARISED:
        return linearised_valve_flows(
            x_v, P[P_FLOW_GAIN], P[P_AREA_B] / P[P_AREA_A], s[S_PS], P[P_P_TANK], s[S_PA], s[S_PB]
        )
    return spool_valve_flows(
        x_v,
        s[S_PS],
        P[P_P_TANK],
        s[S_PA],
        s[S_PB],
        P[P_K_PA],
        P[P_K_AT],
        P[P_K_PB],
        P[P_K_BT],
        P[P_LAP_PA],
        P[P_LAP_AT],
        P[P_LAP_PB],
        P[P_LAP_BT],
        P[P_P_TRANS],
    )


@njit(cache=True, nogil=True, error_model="numpy")
def actuator_force(s, v_x, P):
    """Piston force [N] (rotary: torque [N m]) A_A·p_A − A_B·p_B − b·ẋ (no dry friction)."""
    return P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB] - P[P_VISCOUS] * v_x


@njit(cache=True, nogil=True, error_model="numpy")
def load_force(q, v, P):
    """Generalised force [N or N m] of the load on itself: spring, damper, external force
    and gravity, k·(q − q₀) + c·q̇ + F_ext + W·X·cos(q − θ_h)."""
    f = P[P_SPRING] * (q - P[P_SPRING_FREE]) + P[P_DAMPING] * v + P[P_FORCE]
    if P[P_GRAV_MOMENT] != 0.0:
        f += P[P_GRAV_MOMENT] * cos(q - P[P_GRAV_ANGLE])
    return f


@njit(cache=True, nogil=True, error_model="numpy")
def acceleration(s, P):
    """q̈ [m/s² or rad/s²] of the load at state s (no dry friction, no stops)."""
    x, v_x, lever = actuator_motion(s[S_Q], s[S_V], P)
    return (actuator_force(s, v_x, P) * lever - load_force(s[S_Q], s[S_V], P)) / P[P_MASS]


@njit(cache=True, nogil=True, error_model="numpy")
def servo_rhs(t_ref, s, P, d):
    """Write ṡ into d: the servo's smooth right-hand side at state s with reference t_ref
    (module doc). Dry friction, end stops, the spool stroke and the cavitation floor are the
    step kernel's projections (`hydroarm.reference.servo_kernel`)."""
    x, v_x, lever = actuator_motion(s[S_Q], s[S_V], P)
    p_a = s[S_PA]
    p_b = s[S_PB]
    p_s = s[S_PS]
    p_t = P[P_P_TANK]
    # feedback and spool
    u, d[S_INT] = spool_demand(t_ref, s, x, v_x, P)
    order = P[P_SPOOL_ORDER]
    x_v = s[S_XV]
    if order == 0:
        x_v = u  # algebraic (the step kernel records it in the state)
        d[S_XV] = 0.0
        d[S_VV] = 0.0
    elif order == 1:
        d[S_XV] = (u - s[S_XV]) / P[P_SPOOL_TAU]
        d[S_VV] = 0.0
    else:
        w = P[P_SPOOL_OMEGA]
        d[S_XV] = s[S_VV]
        d[S_VV] = w * w * (u - s[S_XV]) - 2.0 * P[P_SPOOL_ZETA] * w * s[S_VV]
    # valve and chambers
    q_a, q_b, q_p, throttle = valve_flows(x_v, s, P)
    q_i = P[P_LEAK_INT] * (p_a - p_b)
    q_ea = P[P_LEAK_EXT_A] * (p_a - p_t)
    q_eb = P[P_LEAK_EXT_B] * (p_b - p_t)
    v_a, v_b = chamber_volumes(x, P)
    beta = P[P_BETA]
    floor = max(P[P_P_CAV], 1.0)
    b_a = effective_bulk_modulus(p_a, beta, P[P_AIR], P[P_AIR_EXP], P[P_P_ATM], floor)
    b_b = effective_bulk_modulus(p_b, beta, P[P_AIR], P[P_AIR_EXP], P[P_P_ATM], floor)
    d[S_PA] = b_a / v_a * (q_a - P[P_AREA_A] * v_x - q_i - q_ea)
    d[S_PB] = b_b / v_b * (q_b + P[P_AREA_B] * v_x + q_i - q_eb)
    # cavitation: a chamber at the floor does not fall further (the oil parts, vapour fills
    # the difference); the step kernel also projects onto the floor
    cav = P[P_P_CAV]
    if p_a <= cav and d[S_PA] < 0.0:
        d[S_PA] = 0.0
    if p_b <= cav and d[S_PB] < 0.0:
        d[S_PB] = 0.0
    comp = (p_a - p_t) * v_a / b_a * d[S_PA] + (p_b - p_t) * v_b / b_b * d[S_PB]
    # load
    f_act = actuator_force(s, v_x, P)
    d[S_Q] = s[S_V]
    d[S_V] = (f_act * lever - load_force(s[S_Q], s[S_V], P)) / P[P_MASS]
    # supply
    leak_power = q_i * (p_a - p_b) + q_ea * (p_a - p_t) + q_eb * (p_b - p_t)
    if P[P_SUPPLY] == SUPPLY_PUMP:
        q_pump = P[P_PUMP_Q]
        q_pl = P[P_PUMP_LEAK] * (p_s - p_t)
        x_r = s[S_XR]
        d[S_XR] = 0.0
        if P[P_RELIEF_P] < np.inf:
            x_star = relief_static_opening(
                p_s, p_t, P[P_RELIEF_P], P[P_RELIEF_CS], P[P_RELIEF_CF], P[P_RELIEF_XMAX]
            )
            tau = P[P_RELIEF_TAU]
            if tau > 0.0:
                d[S_XR] = (x_star - x_r) / tau
            else:  # static valve: the opening is x* (the step kernel records it in the state)
                x_r = x_star
        q_r = relief_flow(x_r, p_s, p_t, P[P_P_TRANS])
        cap = P[P_SUPPLY_VOL] / P[P_SUPPLY_BETA] + accumulator_capacitance(
            p_s, P[P_ACC_P0], P[P_ACC_V0], P[P_ACC_N]
        )
        d[S_PS] = (q_pump - q_pl - q_p - q_r) / cap
        comp += (p_s - p_t) * cap * d[S_PS]
        d[S_E_SUPPLY] = (p_s - p_t) * q_pump
        d[S_E_RELIEF] = (p_s - p_t) * q_r
        leak_power += q_pl * (p_s - p_t)
    else:
        d[S_PS] = 0.0
        d[S_XR] = 0.0
        d[S_E_SUPPLY] = (p_s - p_t) * q_p
        d[S_E_RELIEF] = 0.0
    d[S_E_THROTTLE] = throttle
    d[S_E_ACT] = (P[P_AREA_A] * (p_a - p_t) - P[P_AREA_B] * (p_b - p_t)) * v_x
    d[S_E_LEAK] = leak_power
    d[S_E_COMP] = comp


@njit(cache=True, nogil=True, error_model="numpy")
def relief_flow_of(states, P):
    """The relief valve's flow [m³/s] in every recorded state (rows of ``states``)."""
    out = np.zeros(states.shape[0])
    if P[P_SUPPLY] != SUPPLY_PUMP:
        return out
    for i in range(states.shape[0]):
        out[i] = relief_flow(states[i, S_XR], states[i, S_PS], P[P_P_TANK], P[P_P_TRANS])
    return out


# -------------------------------------------------------------- integration ---
@njit(cache=True, nogil=True, error_model="numpy")
def dry_friction_capacity(s_old, s, breakaway, P):
    """Dry friction capacity [N or N m] at the load over the step from ``s_old`` to ``s``
    (the smooth update's state): the piston's Coulomb (or breakaway) force through the
    lever, plus for a crank load the gearbox's torque and load-dependent loss
    (`friction_capacity`, the paper joint's law) with γ = |A_A·p_A − A_B·p_B| / (A_A·p_rated).
    The lever (a crank's torque arm) is taken at the step's start and the pressures at its
    end, as the paper joint's rule takes them (`hydroarm.integrators.fixed`, and the
    circuit's ``crank_linkage``): the friction's geometry at the configuration the step
    starts from, not at the smooth update's position, which the projection then moves
    (to the start itself when the load sticks)."""
    x, v_x, lever = actuator_motion(s_old[S_Q], s_old[S_V], P)
    f = P[P_F_STATIC] if breakaway else P[P_F_COULOMB]
    drive = P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB]
    if P[P_LOAD] != LOAD_CRANK:
        return f * abs(lever)
    gamma = min(abs(drive) / (P[P_AREA_A] * P[P_RATED]), 1.0)
    return friction_capacity(f, lever, P[P_GB_T0], P[P_GB_LOSS], P[P_GB_EXP], gamma, drive * lever)


@njit(cache=True, nogil=True, error_model="numpy")
def has_dry_friction(P):
    """Whether any dry friction is on (piston, or a crank load's gearbox)."""
    gearbox = P[P_LOAD] == LOAD_CRANK and (P[P_GB_T0] > 0.0 or P[P_GB_LOSS] > 0.0)
    return P[P_F_COULOMB] > 0.0 or P[P_F_STATIC] > 0.0 or gearbox


@njit(cache=True, nogil=True, error_model="numpy")
def project(method, s_old, s, h, t_ref, P):
    """The non-smooth parts of one step, applied to the new state s in place (module doc)."""
    if has_dry_friction(P) and h > 0.0:
        slide = h * dry_friction_capacity(s_old, s, False, P) / P[P_MASS]
        hold = (
            h * dry_friction_capacity(s_old, s, True, P) / P[P_MASS] if s_old[S_V] == 0.0 else slide
        )
        v = stick_or_slide(s_old[S_V], s[S_V], slide, hold)
        if method == EULER:  # the position from the new velocity, eq. (7)
            s[S_Q] = s_old[S_Q] + h * v
        elif v == 0.0 and s_old[S_V] == 0.0:
            s[S_Q] = s_old[S_Q]
        else:  # the friction impulse grows linearly over the step
            s[S_Q] += 0.5 * h * (v - s[S_V])
        s[S_V] = v
    # load end stops, and the actuator's stroke for a load driven directly
    lo = P[P_Q_MIN]
    hi = P[P_Q_MAX]
    if P[P_LOAD] != LOAD_CRANK:
        lo = max(lo, P[P_STROKE_MIN])
        hi = min(hi, P[P_STROKE_MAX])
    if s[S_Q] < lo:
        s[S_Q] = lo
        s[S_V] = max(s[S_V], 0.0)
    elif s[S_Q] > hi:
        s[S_Q] = hi
        s[S_V] = min(s[S_V], 0.0)
    # spool
    lim = P[P_SPOOL_MAX]
    if P[P_SPOOL_ORDER] == 0:
        x, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
        s[S_XV] = spool_demand(t_ref, s, x, v_x, P)[0]
    elif s[S_XV] > lim:
        s[S_XV] = lim
        s[S_VV] = min(s[S_VV], 0.0)
    elif s[S_XV] < -lim:
        s[S_XV] = -lim
        s[S_VV] = max(s[S_VV], 0.0)
    # cavitation floor, relief opening range
    floor = P[P_P_CAV]
    s[S_PA] = max(s[S_PA], floor)
    s[S_PB] = max(s[S_PB], floor)
    s[S_PS] = max(s[S_PS], min(floor, P[P_P_TANK]))
    if P[P_SUPPLY] == SUPPLY_PUMP and P[P_RELIEF_P] < np.inf and not P[P_RELIEF_TAU] > 0.0:
        # static relief valve: its opening is the static one at the new supply pressure
        s[S_XR] = relief_static_opening(
            s[S_PS], P[P_P_TANK], P[P_RELIEF_P], P[P_RELIEF_CS], P[P_RELIEF_CF], P[P_RELIEF_XMAX]
        )
    else:
        s[S_XR] = min(max(s[S_XR], 0.0), P[P_RELIEF_XMAX])


@njit(cache=True, nogil=True, error_model="numpy")
def step(method, t, h, s, out, tab_t, tab_y, sine, P, k1, k2, k3, k4, tmp):
    """Advance state s from t to t + h into ``out`` (work arrays k1…k4, tmp of the state's
    size). The single step of every fixed-step servo path."""
    r0 = evaluate(t, tab_t, tab_y, sine)
    n = s.shape[0]
    if method == EULER:
        servo_rhs(r0, s, P, k1)
        for i in range(n):
            out[i] = s[i] + h * k1[i]
        # velocity from the new pressures (and spool, supply) at the old position
        out[S_Q] = s[S_Q]
        out[S_V] = s[S_V]
        out[S_V] = s[S_V] + h * acceleration(out, P)
        out[S_Q] = s[S_Q] + h * out[S_V]
    else:
        rm = evaluate(t + 0.5 * h, tab_t, tab_y, sine)
        r1 = evaluate(t + h, tab_t, tab_y, sine)
        servo_rhs(r0, s, P, k1)
        for i in range(n):
            tmp[i] = s[i] + 0.5 * h * k1[i]
        servo_rhs(rm, tmp, P, k2)
        for i in range(n):
            tmp[i] = s[i] + 0.5 * h * k2[i]
        servo_rhs(rm, tmp, P, k3)
        for i in range(n):
            tmp[i] = s[i] + h * k3[i]
        servo_rhs(r1, tmp, P, k4)
        c = h / 6.0
        for i in range(n):
            out[i] = s[i] + c * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    project(method, s, out, h, evaluate(t + h, tab_t, tab_y, sine), P)


@njit(cache=True, nogil=True, error_model="numpy")
def advance_steps(method, t0, k0, h, nsteps, s, tab_t, tab_y, sine, P, out, k1, k2, k3, k4, tmp):
    """Take ``nsteps`` steps of `step` from step ``k0`` (time t0 + k0·h), ``s`` in
    place: the one loop of the servo (`integrate` records between its calls;
    `ServoStepper` runs it piece by piece). Step k
    starts at t0 + k·h, the same float whatever pieces the run is cut into.

    Returns (taken, bad): bad = 1 when the last state taken is not finite (the run stops
    there), else 0."""
    for i in range(nsteps):
        t = t0 + (k0 + i) * h
        step(method, t, h, s, out, tab_t, tab_y, sine, P, k1, k2, k3, k4, tmp)
        s[:] = out
        if not all_finite(s):
            return i + 1, 1
    return nsteps, 0


@njit(cache=True, nogil=True, error_model="numpy")
def advance(method, t0, k0, h, nsteps, s, tab_t, tab_y, sine, P):
    """`advance_steps` with its work arrays (a caller stepping piece by piece)."""
    n = s.shape[0]
    return advance_steps(
        method,
        t0,
        k0,
        h,
        nsteps,
        s,
        tab_t,
        tab_y,
        sine,
        P,
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
    )


@njit(cache=True, nogil=True, error_model="numpy")
def start_state(method, t0, s0, tab_t, tab_y, sine, P):
    """The state a run starts from: s0 projected at t0 (an algebraic spool at its demand;
    what `integrate` applies before its first step)."""
    s = s0.copy()
    project(method, s0, s, 0.0, evaluate(t0, tab_t, tab_y, sine), P)
    return s


@njit(cache=True, nogil=True, error_model="numpy")
def integrate(method, s0, t0, h, nsteps, record_every, tab_t, tab_y, sine, P):
    """Run ``nsteps`` fixed steps from state s0, keeping every ``record_every``-th state
    (`advance_steps` between the records).

    Returns (t, states (records × N_STATES), reference, bad_step): bad_step is −1 or the
    first step whose state was not finite; the run stops there (that state is the last)."""
    nrec = nsteps // record_every + 2
    T = np.empty(nrec)
    S = np.empty((nrec, N_STATES))
    R = np.empty(nrec)
    out = np.empty(N_STATES)
    k1 = np.empty(N_STATES)
    k2 = np.empty(N_STATES)
    k3 = np.empty(N_STATES)
    k4 = np.empty(N_STATES)
    tmp = np.empty(N_STATES)
    s = start_state(method, t0, s0, tab_t, tab_y, sine, P)  # x_v of an algebraic spool
    T[0] = t0
    S[0] = s
    R[0] = evaluate(t0, tab_t, tab_y, sine)
    j = 1
    bad = -1
    k = 0
    while k < nsteps:  # to the next record, or to the end
        m = min(record_every - k % record_every, nsteps - k)
        taken, failed = advance_steps(
            method, t0, k, h, m, s, tab_t, tab_y, sine, P, out, k1, k2, k3, k4, tmp
        )
        k += taken
        if failed:
            bad = k
        if k % record_every == 0 or failed:
            tk = t0 + k * h
            T[j] = tk
            S[j] = s
            R[j] = evaluate(tk, tab_t, tab_y, sine)
            j += 1
        if failed:
            break
    return T[:j], S[:j], R[:j], bad


@njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def run_many(method, S0, t0, h, nsteps, record_every, tab_t, tab_y, sine, table):
    """`integrate` for every row of a parameter table (one scenario a row, initial
    states S0 row by row), in parallel; returns (t, states (rows × records × N_STATES),
    bad_step per row). A row's run is the single run's, bit for bit."""
    n = table.shape[0]
    nrec = nsteps // record_every + 1
    out = np.full((n, nrec, N_STATES), np.nan)
    bad = np.empty(n, np.int64)
    T = t0 + (np.arange(nrec) * record_every) * h  # integrate's t0 + k·h, bit for bit
    for i in prange(n):
        t, S, R, b = integrate(
            method, S0[i], t0, h, nsteps, record_every, tab_t, tab_y, sine, table[i]
        )
        m = min(S.shape[0], nrec)
        out[i, :m] = S[:m]
        bad[i] = b
    return T, out, bad


# ------------------------------------------------------------- component servo ---
def servo_jacobian(s, reference, P):
    """Jacobian of the component servo's smooth right-hand side
    (`hydroarm.reference.servo_kernel.servo_rhs`) at state s, by central differences."""
    n = s.size
    f_p = np.empty(n)
    f_m = np.empty(n)
    J = np.empty((n, n))
    for j in range(n):
        dh = 1e-7 * max(abs(s[j]), 1e-3 if j not in (S_PA, S_PB, S_PS) else 1e3)
        sp = s.copy()
        sm = s.copy()
        sp[j] += dh
        sm[j] -= dh
        servo_rhs(reference, sp, P, f_p)
        servo_rhs(reference, sm, P, f_m)
        J[:, j] = (f_p - f_m) / (2.0 * dh)
    return J


def servo_jacobians(s0, reference, P):
    """Jacobians along the states a servo run passes: the start, and the actuator at rest
    mid-stroke with each chamber at tank, half and full supply pressure and the spool shut
    and fully open either way (the orifice edges are stiffest where their pressure drop
    vanishes: a chamber at supply pressure with its edge open)."""
    out = [servo_jacobian(s0, reference, P)]
    p_t = P[P_P_TANK]
    p_s = max(s0[S_PS], P[P_P_SUPPLY], p_t)
    if P[P_RELIEF_P] < np.inf:
        p_s = max(p_s, P[P_RELIEF_P])
    mid = s0.copy()
    if P[P_LOAD] != LOAD_CRANK and np.isfinite(P[P_STROKE_MIN] + P[P_STROKE_MAX]):
        mid[S_Q] = 0.5 * (P[P_STROKE_MIN] + P[P_STROKE_MAX])
    mid[S_V] = 0.0
    mid[S_PS] = p_s
    spool = P[P_SPOOL_MAX]
    for pa in (p_t, 0.5 * (p_t + p_s), p_s):
        for pb in (p_t, 0.5 * (p_t + p_s), p_s):
            for xv in (0.0, spool, -spool):
                s = mid.copy()
                s[S_PA] = pa
                s[S_PB] = pb
                s[S_XV] = xv
                out.append(servo_jacobian(s, reference, P))
    return out


# the component servo's Euler: every state but the load's, then its velocity, then position
SERVO_EULER_ORDER = (
    tuple(i for i in range(N_STATES) if i not in (S_Q, S_V)),
    (S_V,),
    (S_Q,),
)


def servo_step_limit(method: str, step: float, s0, reference, P):
    """None if ``step`` [s] is stable for the component servo (Jacobians of
    `servo_jacobians`), else the largest stable step [s]."""
    if step <= SCAN_LOW:
        return None
    jacobians = servo_jacobians(s0, reference, P)
    if all_stable(method, jacobians, step, SERVO_EULER_ORDER):
        return None
    return largest_stable_step_for(method, jacobians, order=SERVO_EULER_ORDER)
