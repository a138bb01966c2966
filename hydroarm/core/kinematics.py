"""Crank and gearbox kinematics of a servo joint, eq. (4), and the jack's torque arm, eq. (3).

One home for these formulas: the kernels, the model layer and the plots all call them.
The crank of radius r turns by θ₂/n when the joint turns by θ₂ (gearbox ratio n)::

    x = r·sin(θ₂/n),   ẋ = r·cos(θ₂/n)·θ̇₂/n,   θ₂ = n·asin(x/r)

The inverse has one clipping rule: x is first limited to ±reach·r (``reach`` = 1: the
crank's full stroke; a scenario's target uses 0.999 to stay off the singular end), then
θ₂ = n·asin(x/r). They use the inlined sin/cos of `hydroarm.core.trig`, so that a loop
over scenarios that calls them can be vectorised.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .trig import cos, sin


@njit(cache=True, nogil=True, error_model="numpy")
def crank_position(theta, r, n):
    """Jack position x = r·sin(θ₂/n) [m], eq. (4)."""
    return r * sin(theta * (1.0 / n))


@njit(cache=True, nogil=True, error_model="numpy")
def crank_velocity(theta, omega, r, n):
    """Jack velocity ẋ = r·cos(θ₂/n)·θ̇₂/n [m/s], time derivative of eq. (4)."""
    inv_n = 1.0 / n  # a loop invariant: the step loop multiplies, not divides
    return r * inv_n * cos(theta * inv_n) * omega


@njit(cache=True, nogil=True, error_model="numpy")
def crank_angle(x, r, n, reach=1.0):
    """Joint angle θ₂ = n·asin(x/r) [rad] of a jack position, eq. (4) inverted, with x
    clipped to ±reach·r first."""
    lim = reach * r
    return n * math.asin(min(max(x, -lim), lim) / r)


@njit(cache=True, nogil=True, error_model="numpy")
def crank_torque_arm(theta, r, n, kinematic):
    """Jack force to joint torque lever [m]: r/n (eq. (3) as printed) or, ``kinematic``,
    r·cos(θ₂/n)/n (virtual work with eq. (4))."""
    r_n = r / n
    if kinematic:
        return r_n * cos(theta * (1.0 / n))
    return r_n


@njit(cache=True, nogil=True, error_model="numpy")
def crank_position_trace(theta, r, n):
    """`crank_position` of every angle of an array [m]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = crank_position(theta[i], r, n)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def crank_velocity_trace(theta, omega, r, n):
    """`crank_velocity` of every (angle, velocity) pair of two arrays [m/s]."""
    out = np.empty(theta.shape)
    for i in range(theta.size):
        out[i] = crank_velocity(theta[i], omega[i], r, n)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def crank_angle_trace(x, r, n, reach=1.0):
    """`crank_angle` of every jack position of an array [rad]."""
    out = np.empty(x.shape)
    for i in range(x.size):
        out[i] = crank_angle(x[i], r, n, reach)
    return out
