"""Kinematics of the whole arm: points of the arm and pose-dependent gravity loads.

Articulation angles q = (α shoulder elevation from hanging, ψ humeral rotation, ε elbow
flexion, ρ wrist rotation), in the order of ``JOINT_NAMES``; ``G`` is the arm geometry
(`ArmGeometryParams`, from
`hydroarm.arm.model.ArmGeometry.params`; docs/arm.md).
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


@njit(cache=True, nogil=True, inline="always")
def _point_rows(lam, mu, k, se, ce, sp, cp):
    """∂r/∂(α, ψ, ε) of the point r = λ·u + μ·f in the orthonormal frame (u, w, ŷ), where
    w = ∂u/∂β = (cos β, 0, sin β) and ŷ = (0, 1, 0) (docs/arm.md, "Closed form")."""
    g = lam + mu * ce
    a_u, a_w = -mu * se * cp, g  # ∂r/∂α (no ŷ component)
    p_w, p_y = -mu * se * sp, -mu * se * cp  # ∂r/∂ψ (no u component)
    e_u = -k * a_u - mu * se  # ∂r/∂ε = −k·∂r/∂α + μ·∂f/∂ε|β
    e_w = -k * g + mu * ce * cp
    e_y = -mu * ce * sp
    return a_u, a_w, p_w, p_y, e_u, e_w, e_y


@njit(cache=True, nogil=True)
def pose_terms(alpha, psi, eps, G):
    """Closed-form pose loads of the arm at articulation angles (α, ψ, ε) (ρ moves no point).

    Returns (T_α, T_ψ, T_ε, M_αα, M_ψψ, M_εε, M_αψ, M_αε, M_ψε): the gravity torques
    ∂U/∂q [N m] that load the joints (the torque T of their loads) and the mass matrix
    M_ij = Σ m·(∂r/∂q_i · ∂r/∂q_j) [kg m²] of the three point masses (upper-arm CoM, forearm
    CoM, hand payload). Six trigonometric calls, scalars only (no heap allocation); every
    wrist-rotation term is zero. Derivation: docs/arm.md.
    """
    k = G.reach_shoulder_ratio
    beta = alpha - k * eps
    sb, cb = math.sin(beta), math.cos(beta)
    se, ce = math.sin(eps), math.cos(eps)
    sp, cp = math.sin(psi), math.cos(psi)
    ta = tp = te = 0.0
    maa = mpp = mee = map_ = mae = mpe = 0.0
    for i in range(3):
        if i == 0:
            m, lam, mu = G.upper_arm_mass, G.upper_arm_com, 0.0
        elif i == 1:
            m, lam, mu = G.forearm_mass, G.upper_arm_length, G.forearm_com
        else:
            m, lam, mu = G.hand_mass, G.upper_arm_length, G.forearm_length + G.hand_length
        a_u, a_w, p_w, p_y, e_u, e_w, e_y = _point_rows(lam, mu, k, se, ce, sp, cp)
        # gravity: ∂z/∂q with u_z = −cos β, w_z = sin β, ŷ_z = 0
        mg = m * G.gravity
        ta += mg * (sb * a_w - cb * a_u)
        tp += mg * sb * p_w
        te += mg * (sb * e_w - cb * e_u)
        maa += m * (a_u * a_u + a_w * a_w)
        mpp += m * (p_w * p_w + p_y * p_y)
        mee += m * (e_u * e_u + e_w * e_w + e_y * e_y)
        map_ += m * a_w * p_w
        mae += m * (a_u * e_u + a_w * e_w)
        mpe += m * (p_w * e_w + p_y * e_y)
    return ta, tp, te, maa, mpp, mee, map_, mae, mpe


@njit(cache=True, nogil=True)
def mass_matrix(q, G):
    """The (4, 4) mass matrix M(q) of the point masses [kg m²] (row/column ρ zero)."""
    t = pose_terms(q[ELEVATION], q[ROTATION], q[REACH], G)
    out = np.zeros((4, 4))
    out[ELEVATION, ELEVATION] = t[3]
    out[ROTATION, ROTATION] = t[4]
    out[REACH, REACH] = t[5]
    out[ELEVATION, ROTATION] = out[ROTATION, ELEVATION] = t[6]
    out[ELEVATION, REACH] = out[REACH, ELEVATION] = t[7]
    out[ROTATION, REACH] = out[REACH, ROTATION] = t[8]
    return out


@njit(cache=True, nogil=True)
def pose_load(q, j, G):
    """(gravity torque ∂U/∂q_j [N m], inertia M_jj = Σ m|∂r/∂q_j|² [kg m²]) of joint j, closed
    form (`pose_terms`)."""
    if j == WRIST:
        return 0.0, 0.0
    t = pose_terms(q[ELEVATION], q[ROTATION], q[REACH], G)
    if j == ELEVATION:
        return t[0], t[3]
    if j == ROTATION:
        return t[1], t[4]
    return t[2], t[5]


@njit(cache=True, nogil=True)
def pose_load_fd(q, j, G):
    """`pose_load` by central differences of `potential_energy` and
    `arm_points` (step 1e-6 rad): the reference the closed form is tested against."""
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
