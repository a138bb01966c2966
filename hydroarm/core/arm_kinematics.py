"""Kinematics of the whole arm: points of the arm and pose-dependent gravity loads.

Articulation angles q = (α shoulder elevation from hanging, ψ humeral rotation, ε elbow
flexion, ρ wrist rotation), in the order of ``JOINT_NAMES``; ``G`` is the arm geometry
(:class:`~hydroarm.core.params.ArmGeometryParams`, from
:meth:`hydroarm.arm.model.ArmGeometry.params`; docs/arm.md).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

JOINT_NAMES = ("shoulder_elevation", "humeral_rotation", "elbow_reach", "wrist_rotation")
ELEVATION, ROTATION, REACH, WRIST = range(4)


@njit(cache=True, nogil=True)
def _rotate(v, axis, angle):
    """Rodrigues rotation of v about the unit vector ``axis``."""
    c, s = math.cos(angle), math.sin(angle)
    kx, ky, kz = axis[0], axis[1], axis[2]
    d = kx * v[0] + ky * v[1] + kz * v[2]
    cx = ky * v[2] - kz * v[1]
    cy = kz * v[0] - kx * v[2]
    cz = kx * v[1] - ky * v[0]
    out = np.empty(3)
    out[0] = v[0] * c + cx * s + kx * d * (1 - c)
    out[1] = v[1] * c + cy * s + ky * d * (1 - c)
    out[2] = v[2] * c + cz * s + kz * d * (1 - c)
    return out


@njit(cache=True, nogil=True)
def arm_points(q, G):
    """Points of the arm [m] for articulation angles q = (α, ψ, ε, ρ).

    Returns a (5, 3) array: elbow, wrist, hand, upper-arm centre of mass, forearm centre of
    mass. The wrist rotation ρ turns the hand about the forearm axis and moves no point.
    """
    beta = q[0] - G.reach_shoulder_ratio * q[2]
    u = np.array([math.sin(beta), 0.0, -math.cos(beta)])
    f0 = np.array([math.sin(beta + q[2]), 0.0, -math.cos(beta + q[2])])
    f = _rotate(f0, u, q[1])
    out = np.empty((5, 3))
    for k in range(3):
        e = G.upper_arm_length * u[k]
        out[0, k] = e
        out[1, k] = e + G.forearm_length * f[k]
        out[2, k] = e + (G.forearm_length + G.hand_length) * f[k]
        out[3, k] = G.upper_arm_com * u[k]
        out[4, k] = e + G.forearm_com * f[k]
    return out


@njit(cache=True, nogil=True)
def potential_energy(q, G):
    """U = g·(m_u·z_u + m_f·z_f + m_hand·z_hand) [J]."""
    pts = arm_points(q, G)
    return G.gravity * (
        G.upper_arm_mass * pts[3, 2] + G.forearm_mass * pts[4, 2] + G.hand_mass * pts[2, 2]
    )


@njit(cache=True, nogil=True)
def pose_load(q, j, G):
    """(gravity torque ∂U/∂q_j [N m], inertia Σ m|∂r/∂q_j|² [kg m²]) by central differences."""
    d = 1e-6
    qp = q.copy()
    qm = q.copy()
    qp[j] += d
    qm[j] -= d
    torque = (potential_energy(qp, G) - potential_energy(qm, G)) / (2 * d)
    a = arm_points(qp, G)
    b = arm_points(qm, G)
    inertia = 0.0
    masses = (G.hand_mass, G.upper_arm_mass, G.forearm_mass)  # hand, upper-arm CoM, forearm CoM
    rows = (2, 3, 4)
    for k in range(3):
        r = rows[k]
        v2 = 0.0
        for c in range(3):
            dv = (a[r, c] - b[r, c]) / (2 * d)
            v2 += dv * dv
        inertia += masses[k] * v2
    return torque, inertia
