"""Equations of motion of the hydraulic servo joint (Appendix I of the UCL arm paper).

Pure functions on SI floats, compiled with numba. ``P`` is the packed parameter vector of
:func:`hydroarm.core.joint.pack`. State: joint angle θ₂ [rad], angular velocity ω [rad/s],
load pressure p [Pa]; input: lever (valve spool) position y [m] in jack coordinates.

Equations (numbers as in the paper's Appendix I; reading adopted in docs/model.md):

(1) valve flow = displacement + leakage + compressibility::

        K_q·e = A·ẋ + 2·L·p + (V/β)·ṗ,          K_q = K·√(p_s/2)

(2) saturating valve opening::

        e = clip(y − x, −e_o, +e_o)

(3) torque balance at the joint::

        A·p·r/n = I·θ̈₂ + W·X·cos(θ₂ − θ_h)      (θ_h = 30° in the paper's datum)

(4) crank and gearbox kinematics::

        θ₂ = n·asin(x/r)   ⇔   x = r·sin(θ₂/n),  ẋ = r·cos(θ₂/n)·θ̇₂/n

Physics options beyond the paper (docs/physics.md), selected by entries of ``P``:

(O1) orifice valve: the flow K_q·e of eq. (1) becomes K·e·√((p_s − sgn(e)·p)/2), with the
     square root regularised below the transition pressure p_t;
(O2) viscous piston friction b·ẋ, in :func:`angular_acceleration`;
(O3) dry friction (piston Coulomb/stiction, gearbox load-dependent loss) and end stops:
     not part of this smooth right-hand side; the step kernel applies them as a velocity
     projection (:mod:`hydroarm.integrators.fixed`), so that sticking is exact.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .params import (
    P_AREA,
    P_ARM,
    P_BETA,
    P_CRANK,
    P_E_SAT,
    P_F_COULOMB,
    P_F_STATIC,
    P_FLOW_COEFF,
    P_GB_EXP,
    P_GB_LOSS,
    P_GB_T0,
    P_HORIZ,
    P_INERTIA,
    P_LEAK,
    P_P_ATM,
    P_P_TRANS,
    P_RATIO,
    P_SUPPLY,
    P_TORQUE_ARM,
    P_VALVE,
    P_VISCOUS,
    P_VOLUME,
    P_WEIGHT,
)
from .trig import cos, sin


@njit(cache=True, nogil=True, error_model="numpy")
def jack_position(theta, P):
    """Jack position x = r·sin(θ₂/n) [m], eq. (4)."""
    return P[P_CRANK] * sin(theta * (1.0 / P[P_RATIO]))


@njit(cache=True, nogil=True, error_model="numpy")
def jack_velocity(theta, omega, P):
    """Jack velocity ẋ = r·cos(θ₂/n)·θ̇₂/n [m/s], time derivative of eq. (4)."""
    inv_n = 1.0 / P[P_RATIO]  # a loop invariant: the step loop multiplies, not divides
    return P[P_CRANK] * inv_n * cos(theta * inv_n) * omega


@njit(cache=True, nogil=True, error_model="numpy")
def jack_position_trace(theta, P):
    """:func:`jack_position` of every angle of an array [m]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = jack_position(theta[i], P)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def jack_velocity_trace(theta, omega, P):
    """:func:`jack_velocity` of every (angle, velocity) pair of two arrays [m/s]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = jack_velocity(theta[i], omega[i], P)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def valve_opening(y, x, P):
    """Valve opening e = y − x saturated at ±e_o [m], eq. (2). Floats or arrays."""
    e_o = P[P_E_SAT]
    return np.minimum(np.maximum(y - x, -e_o), e_o)


@njit(cache=True, nogil=True, error_model="numpy")
def flow_gain(P):
    """K_q = K·√(p_s/2) [m²/s], the linearised valve flow gain of eq. (1)."""
    return P[P_FLOW_COEFF] * np.sqrt(0.5 * P[P_SUPPLY])


@njit(cache=True, nogil=True, error_model="numpy")
def torque_arm(theta, P):
    """Jack force to joint torque lever [m]: r/n (eq. (3) as printed) or r·cos(θ₂/n)/n."""
    r_n = P[P_CRANK] / P[P_RATIO]
    if P[P_TORQUE_ARM] > 0.5:
        return r_n * cos(theta * (1.0 / P[P_RATIO]))
    return r_n


@njit(cache=True, nogil=True, error_model="numpy")
def gravity_torque(theta, P):
    """Gravity load torque W·X·cos(θ₂ − θ_h) [N m], last term of eq. (3)."""
    return P[P_WEIGHT] * P[P_ARM] * cos(theta - P[P_HORIZ])


@njit(cache=True, nogil=True, error_model="numpy")
def signed_sqrt(u, u_t):
    """Regularised signed square root u/(u² + u_t²)^¼: √u for u ≫ u_t, linear near 0 [√Pa]."""
    return u / (u * u + u_t * u_t) ** 0.25


@njit(cache=True, nogil=True, error_model="numpy")
def valve_flow(e, p, P):
    """Load flow delivered by the valve [m³/s] at opening e [m] and load pressure p [Pa].

    Paper (eq. 1): K_q·e with K_q = K·√(p_s/2). Orifice option (O1): a critically-centred
    4-way valve whose two metering edges pass K·e·√(p_s − p_A) into one chamber and
    K·e·√(p_B) out of the other; with p_A + p_B = p_s and p = p_A − p_B both equal
    K·e·√((p_s − sgn(e)·p)/2), the classical load-flow law (Merritt 1967, eq. 5-35).
    """
    if P[P_VALVE] < 0.5:
        return flow_gain(P) * e
    s = 1.0 if e >= 0.0 else -1.0
    return P[P_FLOW_COEFF] * e * signed_sqrt(0.5 * (P[P_SUPPLY] - s * p), 0.5 * P[P_P_TRANS])


@njit(cache=True, nogil=True, error_model="numpy")
def pressure_limit(P):
    """Largest |p| [Pa] with no chamber below zero absolute pressure (orifice option)."""
    return P[P_SUPPLY] + 2.0 * P[P_P_ATM]


@njit(cache=True, nogil=True, error_model="numpy")
def pressure_rate(theta, omega, p, y, P):
    """ṗ [Pa/s] from eq. (1) with the valve opening of eq. (2)."""
    x = jack_position(theta, P)
    xdot = jack_velocity(theta, omega, P)
    e = valve_opening(y, x, P)
    # eq. (1): (V/β)·ṗ = K_q·e − A·ẋ − 2·L·p   (K_q·e → orifice flow with option O1)
    q_net = valve_flow(e, p, P) - P[P_AREA] * xdot - 2.0 * P[P_LEAK] * p
    return P[P_BETA] / P[P_VOLUME] * q_net


@njit(cache=True, nogil=True, error_model="numpy")
def actuator_torque(theta, p, P):
    """Jack torque at the joint A·p·r/n (eq. 3) or A·p·r·cos(θ₂/n)/n (kinematic) [N m]."""
    return P[P_AREA] * p * torque_arm(theta, P)


@njit(cache=True, nogil=True, error_model="numpy")
def angular_acceleration(theta, omega, p, P):
    """θ̈₂ [rad/s²] from eq. (3): (A·p·r/n − W·X·cos(θ₂ − θ_h) − viscous) / I (no dry friction)."""
    lever = torque_arm(theta, P)
    torque = P[P_AREA] * p * lever - gravity_torque(theta, P)
    if P[P_VISCOUS] != 0.0:  # option O2: b·ẋ at the piston
        torque -= P[P_VISCOUS] * jack_velocity(theta, omega, P) * lever
    return torque * (1.0 / P[P_INERTIA])


@njit(cache=True, nogil=True, error_model="numpy")
def derivatives(theta, omega, p, y, P):
    """Smooth right-hand side (θ̇₂, θ̈₂, ṗ) of eqs. (1)–(4) (dry friction excluded)."""
    return omega, angular_acceleration(theta, omega, p, P), pressure_rate(theta, omega, p, y, P)


@njit(cache=True, nogil=True, error_model="numpy")
def dry_friction_torque(theta, p, breakaway, P):
    """Dry friction torque capacity at the joint [N m] (option O3), always ≥ 0.

    Piston friction F (Coulomb, or the stiction force when ``breakaway``) through the crank,
    plus the gearbox: a load-independent torque T_g0 and a load-dependent loss
    c_stall·γᵏ·|A·p·arm| with γ = |p|/p_s the actuator load as a fraction of stall.
    """
    lever = torque_arm(theta, P)
    f = P[P_F_STATIC] if breakaway else P[P_F_COULOMB]
    gamma = min(abs(p) / P[P_SUPPLY], 1.0)
    loss = P[P_GB_LOSS] * gamma ** P[P_GB_EXP]
    return f * abs(lever) + P[P_GB_T0] + loss * abs(P[P_AREA] * p * lever)


@njit(cache=True, nogil=True, error_model="numpy")
def has_dry_friction(P):
    return P[P_F_STATIC] > 0.0 or P[P_GB_T0] > 0.0 or P[P_GB_LOSS] > 0.0


@njit(cache=True, nogil=True, error_model="numpy")
def holding_pressure(theta, P):
    """Load pressure [Pa] that holds the load still at θ₂ (eq. (3) with θ̈₂ = 0)."""
    return gravity_torque(theta, P) / (P[P_AREA] * torque_arm(theta, P))
