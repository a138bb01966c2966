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
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .joint import (
    P_AREA,
    P_ARM,
    P_BETA,
    P_CRANK,
    P_E_SAT,
    P_FLOW_COEFF,
    P_HORIZ,
    P_INERTIA,
    P_LEAK,
    P_RATIO,
    P_SUPPLY,
    P_TORQUE_ARM,
    P_VOLUME,
    P_WEIGHT,
)


@njit(cache=True, nogil=True)
def jack_position(theta, P):
    """Jack position x = r·sin(θ₂/n) [m], eq. (4). Works on floats and arrays."""
    return P[P_CRANK] * np.sin(theta / P[P_RATIO])


@njit(cache=True, nogil=True)
def jack_velocity(theta, omega, P):
    """Jack velocity ẋ = r·cos(θ₂/n)·θ̇₂/n [m/s], time derivative of eq. (4)."""
    n = P[P_RATIO]
    return P[P_CRANK] * np.cos(theta / n) * omega / n


@njit(cache=True, nogil=True)
def valve_opening(y, x, P):
    """Valve opening e = y − x saturated at ±e_o [m], eq. (2)."""
    e_o = P[P_E_SAT]
    return np.minimum(np.maximum(y - x, -e_o), e_o)


@njit(cache=True, nogil=True)
def flow_gain(P):
    """K_q = K·√(p_s/2) [m²/s], the linearised valve flow gain of eq. (1)."""
    return P[P_FLOW_COEFF] * np.sqrt(0.5 * P[P_SUPPLY])


@njit(cache=True, nogil=True)
def torque_arm(theta, P):
    """Jack force to joint torque lever [m]: r/n (eq. (3) as printed) or r·cos(θ₂/n)/n."""
    n = P[P_RATIO]
    if P[P_TORQUE_ARM] > 0.5:
        return P[P_CRANK] * np.cos(theta / n) / n
    return P[P_CRANK] / n


@njit(cache=True, nogil=True)
def gravity_torque(theta, P):
    """Gravity load torque W·X·cos(θ₂ − θ_h) [N m], last term of eq. (3)."""
    return P[P_WEIGHT] * P[P_ARM] * np.cos(theta - P[P_HORIZ])


@njit(cache=True, nogil=True)
def pressure_rate(theta, omega, p, y, P):
    """ṗ [Pa/s] from eq. (1) with the valve opening of eq. (2)."""
    x = jack_position(theta, P)
    xdot = jack_velocity(theta, omega, P)
    e = valve_opening(y, x, P)
    # eq. (1): (V/β)·ṗ = K_q·e − A·ẋ − 2·L·p
    q_net = flow_gain(P) * e - P[P_AREA] * xdot - 2.0 * P[P_LEAK] * p
    return P[P_BETA] / P[P_VOLUME] * q_net


@njit(cache=True, nogil=True)
def angular_acceleration(theta, p, P):
    """θ̈₂ [rad/s²] from eq. (3): (A·p·r/n − W·X·cos(θ₂ − θ_h)) / I."""
    return (P[P_AREA] * p * torque_arm(theta, P) - gravity_torque(theta, P)) / P[P_INERTIA]


@njit(cache=True, nogil=True)
def derivatives(theta, omega, p, y, P):
    """Right-hand side (θ̇₂, θ̈₂, ṗ) of eqs. (1)–(4)."""
    return omega, angular_acceleration(theta, p, P), pressure_rate(theta, omega, p, y, P)


@njit(cache=True, nogil=True)
def holding_pressure(theta, P):
    """Load pressure [Pa] that holds the load still at θ₂ (eq. (3) with θ̈₂ = 0)."""
    return gravity_torque(theta, P) / (P[P_AREA] * torque_arm(theta, P))
