"""Rigid-body dynamics of a kinematic tree (issue 30; docs/mechanism.md).

Small compiled functions in the style of Pinocchio and of R. Featherstone, *Rigid Body
Dynamics Algorithms* (Springer, 2008; "RBDA" below): joint transforms, forward kinematics, the
composite-rigid-body algorithm for the joint-space mass matrix (RBDA §6.2, Table 6.2), the
recursive Newton–Euler algorithm for inverse dynamics and bias forces (RBDA §5.3, Table 5.1),
the articulated-body algorithm for forward dynamics (RBDA §7.3, Table 7.1), a Cholesky solve
of the mass matrix as a second route to the same accelerations (RBDA §6.4), the same solve
reduced to the free joints of a tree with kinematic couplings (q_s = ratio·q_m + offset:
Gᵀ·M·G, Gᵀ·(τ − bias)), and the kinetic and potential energy.

The tree
--------
``n`` joints, numbered so that a parent comes before its children; joint ``i`` moves link
``i`` (its child link) relative to link ``parent[i]`` (``-1``: the fixed base, whose frame is
the world frame). A `TreeModel` holds only numbers:

* ``parent`` (n,) int64 — parent joint of each joint, ``-1`` for the base;
* ``joint_type`` (n,) int64 — `REVOLUTE` or `PRISMATIC`;
* ``axis`` (n, 3) — the joint's unit axis in its joint frame [-];
* ``rotation`` (n, 3, 3), ``translation`` (n, 3) — the fixed placement of joint ``i``'s frame
  in its parent link's frame (a point ``x`` of the joint frame is ``R·x + p`` in the parent
  frame) [-], [m];
* ``mass`` (n,) [kg], ``com`` (n, 3) [m] — each link's mass and centre of mass in its link
  frame;
* ``inertia`` (n, 3, 3) — each link's rotational inertia about its centre of mass, in the
  link frame's axes [kg·m²];
* ``gravity`` (3,) — the acceleration of gravity in the world (base) frame [m/s²];
* ``spatial`` (n, 6, 6) — each link's spatial inertia about its link frame's origin, made
  from ``mass``, ``com`` and ``inertia`` once, when the model is built
  (`spatial_inertias`; the algorithms read it rather than form it at every call).

The link frame of link ``i`` is joint ``i``'s frame after the joint's motion (Pinocchio's
convention): a revolute joint rotates it by ``q`` about the axis through the joint frame's
origin, a prismatic joint translates it by ``q`` along the axis.

Spatial vectors
---------------
6-vectors in Featherstone's order, angular part first (RBDA §2.2): a motion (velocity,
acceleration) is ``(ω, v)`` with ``v`` the velocity of the point at the frame's origin; a force
is ``(n, f)`` with ``n`` the moment about the frame's origin. Every quantity of link ``i`` is
expressed in link ``i``'s own frame (the "body coordinates" of RBDA §5.3). External forces
``fext`` are spatial forces on each link, in its link frame [N·m, N]
(`point_force`).

No function allocates: each writes into the arrays of a `TreeWork` made once by
`make_tree_work` and into an output array, so that an integrator can call it every
stage of every step.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

#: the decorator of the algorithms: compiled, cached, and free of reference counting
#: (numba's ``_nrt=False``; they allocate nothing, `make_tree_work` does). Set here, not
#: left to numba: a function that does not set it takes it from the first caller that
#: compiles it (``_nrt=False`` from the system kernel, reference counting from a compiled
#: loop or from Python) and keeps that version, in its disk cache too, for every caller
#: after: the same algorithm about 3× slower or not by the order things first ran in
#: (benchmarks/mechanism_speed.py)
_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy", "_nrt": False}
kernel = njit(**_OPTIONS)
#: `kernel` compiled into each caller (numba's ``inline="always"``): for the private
#: passes that take the whole model and work (some 230 words, which a call copies; the
#: algorithms call them in turn). Private only: compiled into a caller, a function takes the
#: caller's flags (reference counting in a user's compiled loop); the public functions are
#: `kernel` wrappers of them
inlined = njit(**_OPTIONS, inline="always")

REVOLUTE = 0  # joint type code: rotation about the axis [rad]
PRISMATIC = 1  # joint type code: translation along the axis [m]
STANDARD_GRAVITY = 9.80665  # g₀ [m/s²], along -z of the world frame by default


class TreeModel(NamedTuple):
    """A kinematic tree as plain arrays (see the module docstring for each field)."""

    parent: np.ndarray  # (n,) int64
    joint_type: np.ndarray  # (n,) int64
    axis: np.ndarray  # (n, 3) unit axis in the joint frame
    rotation: np.ndarray  # (n, 3, 3) joint frame in parent link frame
    translation: np.ndarray  # (n, 3) [m]
    mass: np.ndarray  # (n,) [kg]
    com: np.ndarray  # (n, 3) [m], link frame
    inertia: np.ndarray  # (n, 3, 3) [kg m²], about the centre of mass
    gravity: np.ndarray  # (3,) [m/s²], world frame
    spatial: np.ndarray  # (n, 6, 6) [kg m², kg m, kg] spatial_inertias(mass, com, inertia)


class TreeWork(NamedTuple):
    """Work arrays of the algorithms for a tree of ``n`` joints (`make_tree_work`)."""

    R: np.ndarray  # (n, 3, 3) link i in parent link frame, at q
    p: np.ndarray  # (n, 3)
    S: np.ndarray  # (n, 6) motion subspace of each joint, link frame
    v: np.ndarray  # (n, 6) link spatial velocities
    a: np.ndarray  # (n, 6) link spatial accelerations
    f: np.ndarray  # (n, 6) link spatial forces
    c: np.ndarray  # (n, 6) velocity-product accelerations (ABA)
    IA: np.ndarray  # (n, 6, 6) articulated (ABA) or composite (CRBA) inertias
    pA: np.ndarray  # (n, 6) bias forces of the articulated bodies
    U: np.ndarray  # (n, 6)
    D: np.ndarray  # (n,)
    u: np.ndarray  # (n,)
    M: np.ndarray  # (n, n) mass matrix (forward_dynamics_crba)
    armature: np.ndarray  # (n,) inertia added at each joint by its drive [kg·m² or kg] (ABA)
    tmp6: np.ndarray  # (4, 6) scratch vectors
    tmp66: np.ndarray  # (3, 6, 6) scratch matrices


@njit(cache=True, nogil=True, error_model="numpy")
def make_tree_work(n):
    """Work arrays for a tree of ``n`` joints (allocated once, reused by every call; the
    armature zero)."""
    return TreeWork(
        np.zeros((n, 3, 3)),
        np.zeros((n, 3)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6, 6)),
        np.zeros((n, 6)),
        np.zeros((n, 6)),
        np.zeros(n),
        np.zeros(n),
        np.zeros((n, n)),
        np.zeros(n),
        np.zeros((4, 6)),
        np.zeros((3, 6, 6)),
    )


# --- 3-D and spatial helpers --------------------------------------------------------------


@kernel
def axis_rotation(axis, angle, out):
    """Rotation by ``angle`` [rad] about the unit ``axis`` (Rodrigues' formula, RBDA eq. 2.23
    read as an active rotation): R = 1 + sin θ·[a]× + (1 − cos θ)·[a]×², written into
    ``out`` (3, 3)."""
    s = math.sin(angle)
    k = 1.0 - math.cos(angle)
    x, y, z = axis[0], axis[1], axis[2]
    out[0, 0] = 1.0 - k * (y * y + z * z)
    out[0, 1] = k * x * y - s * z
    out[0, 2] = k * x * z + s * y
    out[1, 0] = k * x * y + s * z
    out[1, 1] = 1.0 - k * (x * x + z * z)
    out[1, 2] = k * y * z - s * x
    out[2, 0] = k * x * z - s * y
    out[2, 1] = k * y * z + s * x
    out[2, 2] = 1.0 - k * (x * x + y * y)


@kernel
def motion_to_child(R, p, m, out):
    """A spatial motion ``m`` of the parent frame in the child frame placed at (R, p) in it:
    ω' = Rᵀω, v' = Rᵀ(v − p × ω) (the Plücker transform of RBDA eq. 2.24). ``out`` must not
    alias ``m``."""
    w0, w1, w2 = m[0], m[1], m[2]
    l0 = m[3] - (p[1] * w2 - p[2] * w1)
    l1 = m[4] - (p[2] * w0 - p[0] * w2)
    l2 = m[5] - (p[0] * w1 - p[1] * w0)
    for i in range(3):
        out[i] = R[0, i] * w0 + R[1, i] * w1 + R[2, i] * w2
        out[3 + i] = R[0, i] * l0 + R[1, i] * l1 + R[2, i] * l2


@kernel
def add_force_to_parent(R, p, f, out):
    """Add a spatial force ``f`` of the child frame placed at (R, p) to ``out`` in the parent
    frame: f' = R·f, n' = R·n + p × f' (the dual transform X*, RBDA eq. 2.25)."""
    f0 = R[0, 0] * f[3] + R[0, 1] * f[4] + R[0, 2] * f[5]
    f1 = R[1, 0] * f[3] + R[1, 1] * f[4] + R[1, 2] * f[5]
    f2 = R[2, 0] * f[3] + R[2, 1] * f[4] + R[2, 2] * f[5]
    for i in range(3):
        out[i] += R[i, 0] * f[0] + R[i, 1] * f[1] + R[i, 2] * f[2]
    out[0] += p[1] * f2 - p[2] * f1
    out[1] += p[2] * f0 - p[0] * f2
    out[2] += p[0] * f1 - p[1] * f0
    out[3] += f0
    out[4] += f1
    out[5] += f2


@kernel
def motion_cross(m, x, out):
    """The spatial cross product m × x of two motions (RBDA eq. 2.31): (ω × ω_x, ω × v_x +
    v × ω_x). ``out`` must not alias the inputs."""
    out[0] = m[1] * x[2] - m[2] * x[1]
    out[1] = m[2] * x[0] - m[0] * x[2]
    out[2] = m[0] * x[1] - m[1] * x[0]
    out[3] = m[1] * x[5] - m[2] * x[4] + m[4] * x[2] - m[5] * x[1]
    out[4] = m[2] * x[3] - m[0] * x[5] + m[5] * x[0] - m[3] * x[2]
    out[5] = m[0] * x[4] - m[1] * x[3] + m[3] * x[1] - m[4] * x[0]


@kernel
def add_force_cross(m, f, out):
    """Add the spatial cross product m ×* f of a motion and a force (RBDA eq. 2.32):
    (ω × n + v × f, ω × f) to ``out``."""
    out[0] += m[1] * f[2] - m[2] * f[1] + m[4] * f[5] - m[5] * f[4]
    out[1] += m[2] * f[0] - m[0] * f[2] + m[5] * f[3] - m[3] * f[5]
    out[2] += m[0] * f[1] - m[1] * f[0] + m[3] * f[4] - m[4] * f[3]
    out[3] += m[1] * f[5] - m[2] * f[4]
    out[4] += m[2] * f[3] - m[0] * f[5]
    out[5] += m[0] * f[4] - m[1] * f[3]


@kernel
def spatial_inertia(mass, com, inertia, out):
    """The 6×6 spatial inertia of a rigid body about its frame's origin (RBDA eq. 2.63):
    [[I_c + m·[c]×[c]×ᵀ, m·[c]×], [m·[c]×ᵀ, m·1]] from its mass [kg], centre of mass ``com``
    [m] and rotational inertia about the centre of mass [kg·m²], into ``out`` (6, 6)."""
    cx, cy, cz = com[0], com[1], com[2]
    hx, hy, hz = mass * cx, mass * cy, mass * cz
    cc = cx * cx + cy * cy + cz * cz
    for i in range(3):
        for j in range(3):
            out[i, j] = inertia[i, j] - mass * com[i] * com[j]
            out[3 + i, 3 + j] = 0.0
        out[i, i] += mass * cc
        out[3 + i, 3 + i] = mass
    # m·[c]× (upper right) and its transpose (lower left)
    out[0, 3], out[0, 4], out[0, 5] = 0.0, -hz, hy
    out[1, 3], out[1, 4], out[1, 5] = hz, 0.0, -hx
    out[2, 3], out[2, 4], out[2, 5] = -hy, hx, 0.0
    for i in range(3):
        for j in range(3):
            out[3 + i, j] = out[j, 3 + i]


@njit(cache=True, nogil=True, error_model="numpy")
def spatial_inertias(mass, com, inertia):
    """Each link's spatial inertia (`spatial_inertia`) as an (n, 6, 6) array: the
    `TreeModel`'s ``spatial``, made once when the model is built."""
    n = mass.size
    out = np.zeros((n, 6, 6))
    for i in range(n):
        spatial_inertia(mass[i], com[i], inertia[i], out[i])
    return out


@kernel
def rigid_inertia_times(mass, com, inertia, m, out):
    """The momentum h = I·m [N·m·s, N·s] of a rigid body moving with the spatial velocity
    ``m`` (ω, v), from its mass [kg], centre of mass ``com`` [m] and rotational inertia about
    the centre of mass [kg·m²] without forming the 6×6 inertia (RBDA eq. 2.62–2.63):
    linear L = m·(v + ω × c), angular about the origin N = I_c·ω + c × L. Into ``out``."""
    w0, w1, w2 = m[0], m[1], m[2]
    c0, c1, c2 = com[0], com[1], com[2]
    L0 = mass * (m[3] + w1 * c2 - w2 * c1)
    L1 = mass * (m[4] + w2 * c0 - w0 * c2)
    L2 = mass * (m[5] + w0 * c1 - w1 * c0)
    for k in range(3):
        out[k] = inertia[k, 0] * w0 + inertia[k, 1] * w1 + inertia[k, 2] * w2
    out[0] += c1 * L2 - c2 * L1
    out[1] += c2 * L0 - c0 * L2
    out[2] += c0 * L1 - c1 * L0
    out[3] = L0
    out[4] = L1
    out[5] = L2


@kernel
def add_inertia_to_parent(R, p, Ic, out, tmp):
    """Add a spatial (rigid or articulated) inertia ``Ic`` of the child frame placed at (R, p)
    to ``out`` in the parent frame: X*·Ic·X, with X = [[Rᵀ, 0], [−Rᵀ·[p]×, Rᵀ]] the motion
    transform parent → child and X* = Xᵀ (RBDA eq. 2.66; Table 6.2 line 11, Table 7.1 line 22).

    By blocks (RBDA §2.13's efficient form): with Ic = [[A, B], [Bᵀ, C]] rotated into the
    parent's axes, A' = R·A·Rᵀ, B' = R·B·Rᵀ, C' = R·C·Rᵀ, then moved by P = [p]×:
    [[A' + P·B'ᵀ − B'·P − P·C'·P, B' + P·C'], [·ᵀ, C']]. About 250 flops instead of 864 for two
    6×6 products. ``tmp`` is a (6, 6) scratch matrix."""
    # tmp = blockdiag(R)·Ic·blockdiag(Rᵀ), its blocks A', B', C' (the lower left one, B'ᵀ,
    # is not formed: the sums below read B' in its place): first each block times Rᵀ ...
    for bi in range(2):
        for bj in range(bi, 2):
            for r in range(3):
                for c in range(3):
                    s = 0.0
                    for k in range(3):
                        s += Ic[3 * bi + r, 3 * bj + k] * R[c, k]
                    tmp[3 * bi + r, 3 * bj + c] = s
    # ... then R times it, in place a column of a block at a time
    for bi in range(2):
        for col in range(3 * bi, 6):
            x0 = tmp[3 * bi, col]
            x1 = tmp[3 * bi + 1, col]
            x2 = tmp[3 * bi + 2, col]
            for r in range(3):
                tmp[3 * bi + r, col] = R[r, 0] * x0 + R[r, 1] * x1 + R[r, 2] * x2
    p0, p1, p2 = p[0], p[1], p[2]
    # B'' = B' + P·C': p crossed with each column of C'
    for c in range(3):
        c0 = tmp[3, 3 + c]
        c1 = tmp[4, 3 + c]
        c2 = tmp[5, 3 + c]
        tmp[0, 3 + c] += p1 * c2 - p2 * c1
        tmp[1, 3 + c] += p2 * c0 - p0 * c2
        tmp[2, 3 + c] += p0 * c1 - p1 * c0
    # A'' = A' − B''·P − (B''·P)ᵀ + P·C'·P (the same as above, P being antisymmetric);
    # a row x of a matrix times P is x × p
    for r in range(3):
        b0 = tmp[r, 3]
        b1 = tmp[r, 4]
        b2 = tmp[r, 5]
        w0 = b1 * p2 - b2 * p1
        w1 = b2 * p0 - b0 * p2
        w2 = b0 * p1 - b1 * p0
        out[r, 0] += tmp[r, 0] - w0
        out[r, 1] += tmp[r, 1] - w1
        out[r, 2] += tmp[r, 2] - w2
        out[0, r] -= w0
        out[1, r] -= w1
        out[2, r] -= w2
    for j in range(3):
        # column j of C'·P is C'·(p × e_j); then p × that
        x0 = 0.0 if j == 0 else (-p2 if j == 1 else p1)
        x1 = p2 if j == 0 else (0.0 if j == 1 else -p0)
        x2 = -p1 if j == 0 else (p0 if j == 1 else 0.0)
        y0 = tmp[3, 3] * x0 + tmp[3, 4] * x1 + tmp[3, 5] * x2
        y1 = tmp[4, 3] * x0 + tmp[4, 4] * x1 + tmp[4, 5] * x2
        y2 = tmp[5, 3] * x0 + tmp[5, 4] * x1 + tmp[5, 5] * x2
        out[0, j] += p1 * y2 - p2 * y1
        out[1, j] += p2 * y0 - p0 * y2
        out[2, j] += p0 * y1 - p1 * y0
    for r in range(3):
        for c in range(3):
            out[r, 3 + c] += tmp[r, 3 + c]
            out[3 + c, r] += tmp[r, 3 + c]
            out[3 + r, 3 + c] += tmp[3 + r, 3 + c]


@kernel
def matvec6(A, x, out):
    """out = A·x for a (6, 6) matrix and a 6-vector."""
    for i in range(6):
        s = 0.0
        for j in range(6):
            s += A[i, j] * x[j]
        out[i] = s


@kernel
def dot6(x, y):
    """The scalar product of two 6-vectors (a motion and a force: a power)."""
    s = 0.0
    for i in range(6):
        s += x[i] * y[i]
    return s


# --- kinematics ----------------------------------------------------------------------------


@kernel
def joint_transform(joint_type, axis, q, R, p):
    """The joint's own motion X_J(q) (RBDA Table 4.1): a rotation by ``q`` [rad] about the
    axis (revolute) or a translation by ``q`` [m] along it (prismatic), as (R, p) written into
    ``R`` (3, 3) and ``p`` (3,)."""
    if joint_type == REVOLUTE:
        axis_rotation(axis, q, R)
        p[0] = p[1] = p[2] = 0.0
    else:
        for i in range(3):
            for j in range(3):
                R[i, j] = 1.0 if i == j else 0.0
            p[i] = axis[i] * q


@kernel
def joint_placements(model, q, work):
    """Each link's placement in its parent link's frame at the joint positions ``q``
    (`_placements`)."""
    _placements(model, q, work)


@inlined
def _placements(model, q, work):
    """Each link's placement in its parent link's frame at the joint positions ``q``,
    λ_X_i = X_T(i)·X_J(q_i) (RBDA eq. 4.1, Pinocchio's ``liMi``), into ``work.R``, ``work.p``;
    and each joint's motion subspace S_i in its link frame into ``work.S`` (RBDA Table 4.1:
    (a, 0) revolute, (0, a) prismatic)."""
    n = model.parent.size
    Rj = work.tmp66[0, :3, :3]
    pj = work.tmp6[0, :3]
    for i in range(n):
        joint_transform(model.joint_type[i], model.axis[i], q[i], Rj, pj)
        R0 = model.rotation[i]
        p0 = model.translation[i]
        for r in range(3):
            for c in range(3):
                work.R[i, r, c] = R0[r, 0] * Rj[0, c] + R0[r, 1] * Rj[1, c] + R0[r, 2] * Rj[2, c]
            work.p[i, r] = p0[r] + R0[r, 0] * pj[0] + R0[r, 1] * pj[1] + R0[r, 2] * pj[2]
        off = 0 if model.joint_type[i] == REVOLUTE else 3
        for k in range(6):
            work.S[i, k] = 0.0
        for k in range(3):
            work.S[i, off + k] = model.axis[i, k]


@kernel
def forward_kinematics(model, q, work, R_world, p_world):
    """Each link's placement in the world frame at joint positions ``q`` [rad or m] (RBDA
    §4.2: ⁰X_i = ⁰X_λ(i)·λ(i)X_i), as rotations ``R_world`` (n, 3, 3) and origins ``p_world``
    (n, 3) [m]."""
    _placements(model, q, work)
    n = model.parent.size
    for i in range(n):
        j = model.parent[i]
        if j < 0:
            for r in range(3):  # (not slice copies: they would ask for numba's allocator)
                for c in range(3):
                    R_world[i, r, c] = work.R[i, r, c]
                p_world[i, r] = work.p[i, r]
            continue
        for r in range(3):
            for c in range(3):
                R_world[i, r, c] = (
                    R_world[j, r, 0] * work.R[i, 0, c]
                    + R_world[j, r, 1] * work.R[i, 1, c]
                    + R_world[j, r, 2] * work.R[i, 2, c]
                )
            p_world[i, r] = (
                p_world[j, r]
                + R_world[j, r, 0] * work.p[i, 0]
                + R_world[j, r, 1] * work.p[i, 1]
                + R_world[j, r, 2] * work.p[i, 2]
            )


@inlined
def _velocities(model, q, qd, work):
    """Placements and link velocities v_i = X_i·v_λ + S_i·q̇_i (RBDA eq. 5.7, Table 5.1)."""
    _placements(model, q, work)
    n = model.parent.size
    for i in range(n):
        j = model.parent[i]
        if j < 0:
            for k in range(6):
                work.v[i, k] = work.S[i, k] * qd[i]
        else:
            motion_to_child(work.R[i], work.p[i], work.v[j], work.v[i])
            for k in range(6):
                work.v[i, k] += work.S[i, k] * qd[i]


# --- dynamics ------------------------------------------------------------------------------


@kernel
def inverse_dynamics(model, q, qd, qdd, fext, work, tau):
    """Joint forces τ [N·m or N] that give the accelerations ``qdd`` at (q, q̇) under gravity
    and the external link forces ``fext`` (n, 6) [N·m, N] (recursive Newton–Euler, RBDA
    Table 5.1, with gravity as a base acceleration −g, RBDA §5.3):

        a_i = X_i·a_λ + S_i·q̈_i + v_i × S_i·q̇_i,   a_base = (0, −g)
        f_i = I_i·a_i + v_i ×* I_i·v_i − f_ext,i
        τ_i = S_iᵀ·f_i,    f_λ += X_i*·f_i

    τ = M(q)·q̈ + C(q, q̇)·q̇ + g(q) − Σ J_iᵀ f_ext,i, into ``tau`` (n,)."""
    _velocities(model, q, qd, work)
    _newton_euler(model, qd, qdd, fext, work, tau)


@inlined
def _newton_euler(model, qd, qdd, fext, work, tau):
    """The passes of `inverse_dynamics` after the velocities (the placements and link
    velocities already in ``work``: `_velocities`)."""
    n = model.parent.size
    base = work.tmp6[1]
    base[0] = base[1] = base[2] = 0.0
    for k in range(3):
        base[3 + k] = -model.gravity[k]
    Iv = work.tmp6[2]
    vJ = work.tmp6[3]
    for i in range(n):
        j = model.parent[i]
        if j < 0:
            motion_to_child(work.R[i], work.p[i], base, work.a[i])
        else:
            motion_to_child(work.R[i], work.p[i], work.a[j], work.a[i])
        for k in range(6):
            vJ[k] = work.S[i, k] * qd[i]
        motion_cross(work.v[i], vJ, Iv)  # v_i × S_i q̇_i (c_J = 0: constant S_i)
        for k in range(6):
            work.a[i, k] += work.S[i, k] * qdd[i] + Iv[k]
        rigid_inertia_times(model.mass[i], model.com[i], model.inertia[i], work.a[i], work.f[i])
        rigid_inertia_times(model.mass[i], model.com[i], model.inertia[i], work.v[i], Iv)
        add_force_cross(work.v[i], Iv, work.f[i])
        for k in range(6):
            work.f[i, k] -= fext[i, k]
    for i in range(n - 1, -1, -1):
        tau[i] = dot6(work.S[i], work.f[i])
        j = model.parent[i]
        if j >= 0:
            add_force_to_parent(work.R[i], work.p[i], work.f[i], work.f[j])


@kernel
def bias_forces(model, q, qd, fext, work, out):
    """The bias forces C(q, q̇)·q̇ + g(q) − Σ J_iᵀ f_ext,i [N·m or N]: inverse dynamics at
    q̈ = 0 (RBDA §5.3 and eq. 6.2; Pinocchio's ``nonLinearEffects`` with no external force),
    into ``out`` (n,). Uses ``work.u`` as the zero acceleration."""
    _bias_forces(model, q, qd, fext, work, out)


@inlined
def _bias_forces(model, q, qd, fext, work, out):
    """`bias_forces`, compiled into its callers."""
    n = model.parent.size
    for i in range(n):
        work.u[i] = 0.0
    _velocities(model, q, qd, work)
    _newton_euler(model, qd, work.u, fext, work, out)


@kernel
def mass_matrix(model, q, work, M):
    """The joint-space mass matrix M(q) [kg·m², kg·m or kg] by the composite-rigid-body
    algorithm (RBDA Table 6.2): composite inertias I^c_λ += X_i*·I^c_i·X_i from the leaves in,
    then F = I^c_i·S_i carried towards the root, M_ij = S_jᵀ·F, with each drive's inertia
    ``work.armature`` on the diagonal (as `forward_dynamics`). Into ``M`` (n, n), both
    triangles."""
    _placements(model, q, work)
    _composite_inertia(model, work, M)


@inlined
def _composite_inertia(model, work, M):
    """`mass_matrix` with the placements already in ``work`` (`joint_placements`)."""
    n = model.parent.size
    Ic = work.IA
    for i in range(n):
        for r in range(6):
            for c in range(6):
                Ic[i, r, c] = model.spatial[i, r, c]
        for k in range(n):
            M[i, k] = 0.0  # joints on different branches are not coupled
    for i in range(n - 1, -1, -1):
        j = model.parent[i]
        if j >= 0:
            add_inertia_to_parent(work.R[i], work.p[i], Ic[i], Ic[j], work.tmp66[1])
    F = work.tmp6[1]
    G = work.tmp6[2]
    for i in range(n):
        matvec6(Ic[i], work.S[i], F)
        M[i, i] = dot6(work.S[i], F) + work.armature[i]
        j = i
        while model.parent[j] >= 0:
            for k in range(6):
                G[k] = 0.0
            add_force_to_parent(work.R[j], work.p[j], F, G)
            for k in range(6):  # (not F[:] = G: a slice copy would allocate)
                F[k] = G[k]
            j = model.parent[j]
            M[i, j] = dot6(work.S[j], F)
            M[j, i] = M[i, j]


@kernel
def forward_dynamics(model, q, qd, tau, fext, work, qdd):
    """Joint accelerations q̈ [rad/s² or m/s²] under the joint forces ``tau``, gravity and the
    external link forces ``fext`` by the articulated-body algorithm (RBDA Table 7.1; O(n)):

        pass 1: v_i, c_i = v_i × S_i q̇_i, I^A_i = I_i, p^A_i = v_i ×* I_i v_i − f_ext,i
        pass 2: U_i = I^A_i S_i, D_i = S_iᵀU_i, u_i = τ_i − S_iᵀp^A_i,
                I^a = I^A_i − U_i U_iᵀ/D_i,  p^a = p^A_i + I^a c_i + U_i u_i/D_i,
                I^A_λ += X*·I^a·X,  p^A_λ += X*·p^a
        pass 3: a' = X_i a_λ + c_i (a_base = (0, −g)),  q̈_i = (u_i − U_iᵀa')/D_i,
                a_i = a' + S_i q̈_i

    A drive's inertia at joint i (``work.armature[i]``: a motor's rotor, a cylinder's piston
    seen through its linkage) adds to D_i, as Pinocchio's ``armature`` (RBDA §9.6: a rotor
    on the joint axis). Into ``qdd`` (n,)."""
    _velocities(model, q, qd, work)
    n = model.parent.size
    t = work.tmp6[2]
    vJ = work.tmp6[3]
    for i in range(n):
        for k in range(6):
            vJ[k] = work.S[i, k] * qd[i]
        motion_cross(work.v[i], vJ, work.c[i])
        for r in range(6):
            for c in range(6):
                work.IA[i, r, c] = model.spatial[i, r, c]
        rigid_inertia_times(model.mass[i], model.com[i], model.inertia[i], work.v[i], t)
        for k in range(6):
            work.pA[i, k] = -fext[i, k]
        add_force_cross(work.v[i], t, work.pA[i])
    Ia = work.tmp66[0]
    pa = work.tmp6[1]
    for i in range(n - 1, -1, -1):
        matvec6(work.IA[i], work.S[i], work.U[i])
        D = dot6(work.S[i], work.U[i]) + work.armature[i]
        work.D[i] = D
        work.u[i] = tau[i] - dot6(work.S[i], work.pA[i])
        j = model.parent[i]
        if j < 0:
            continue
        for r in range(6):
            for c in range(6):
                Ia[r, c] = work.IA[i, r, c] - work.U[i, r] * work.U[i, c] / D
        matvec6(Ia, work.c[i], pa)
        for k in range(6):
            pa[k] += work.pA[i, k] + work.U[i, k] * work.u[i] / D
        add_inertia_to_parent(work.R[i], work.p[i], Ia, work.IA[j], work.tmp66[1])
        add_force_to_parent(work.R[i], work.p[i], pa, work.pA[j])
    base = work.tmp6[1]
    base[0] = base[1] = base[2] = 0.0
    for k in range(3):
        base[3 + k] = -model.gravity[k]
    for i in range(n):
        j = model.parent[i]
        if j < 0:
            motion_to_child(work.R[i], work.p[i], base, work.a[i])
        else:
            motion_to_child(work.R[i], work.p[i], work.a[j], work.a[i])
        for k in range(6):
            work.a[i, k] += work.c[i, k]
        qdd[i] = (work.u[i] - dot6(work.U[i], work.a[i])) / work.D[i]
        for k in range(6):
            work.a[i, k] += work.S[i, k] * qdd[i]


@kernel
def cholesky_solve(M, b, x):
    """Solve M·x = b for a symmetric positive-definite ``M`` by its Cholesky factor
    M = L·Lᵀ (RBDA §6.4), in place: ``M``'s lower triangle is overwritten with L."""
    n = b.size
    for j in range(n):
        s = M[j, j]
        for k in range(j):
            s -= M[j, k] * M[j, k]
        d = math.sqrt(s)
        M[j, j] = d
        for i in range(j + 1, n):
            s = M[i, j]
            for k in range(j):
                s -= M[i, k] * M[j, k]
            M[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= M[i, k] * x[k]
        x[i] = s / M[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, n):
            s -= M[k, i] * x[k]
        x[i] = s / M[i, i]


@kernel
def forward_dynamics_crba(model, q, qd, tau, fext, work, qdd):
    """Joint accelerations q̈ = M(q)⁻¹·(τ − C(q, q̇)·q̇ − g(q) + Σ J_iᵀ f_ext,i) by the
    mass matrix (`mass_matrix`) and the bias forces (`bias_forces`) with a
    Cholesky solve (RBDA §6.4; O(n³), the check of `forward_dynamics`). Into ``qdd``."""
    n = model.parent.size
    rhs = work.D  # the bias forces, then τ minus them
    _bias_forces(model, q, qd, fext, work, rhs)
    for i in range(n):
        rhs[i] = tau[i] - rhs[i]
    _composite_inertia(model, work, work.M)  # at the placements _bias_forces made
    cholesky_solve(work.M, rhs, qdd)


@kernel
def reduce_coupled(couplings, laws, M, rhs):
    """Fold the coupled joints into their masters: with q = G·q_f + offset (G constant:
    column of free joint a has 1 at row a and ``ratio`` at each joint coupled to it), the
    free joints' equations are Gᵀ·M·G·q̈_f = Gᵀ·(τ − bias). In place on ``M`` (n, n) and
    ``rhs`` (n,); ``couplings`` (k, 2): each coupled joint and its master (a free joint),
    ``laws`` (k, 2): its ratio and offset. The coupled joints' rows and columns are left as
    those of the identity (and their ``rhs`` zero), so ``M`` stays symmetric positive
    definite and the free joints keep their places."""
    n = rhs.size
    for k in range(couplings.shape[0]):  # rows: Gᵀ·M, Gᵀ·rhs
        s, m, r = couplings[k, 0], couplings[k, 1], laws[k, 0]
        rhs[m] += r * rhs[s]
        rhs[s] = 0.0
        for c in range(n):
            M[m, c] += r * M[s, c]
    for k in range(couplings.shape[0]):  # columns: (Gᵀ·M)·G
        s, m, r = couplings[k, 0], couplings[k, 1], laws[k, 0]
        for c in range(n):
            M[c, m] += r * M[c, s]
    for k in range(couplings.shape[0]):
        s = couplings[k, 0]
        for c in range(n):
            M[s, c] = 0.0
            M[c, s] = 0.0
        M[s, s] = 1.0


@kernel
def forward_dynamics_coupled(model, couplings, laws, q, qd, tau, fext, work, qdd):
    """Joint accelerations q̈ of a tree whose coupled joints follow free ones,
    q_s = ratio·q_m + offset (``couplings``, ``laws``: `reduce_coupled`; q and q̇ of
    the coupled joints must already follow their masters). The reduced equations of the free
    joints (Lagrange's equations in the free coordinates; q̈ = G·q̈_f, G being constant):

        Gᵀ·M(q)·G·q̈_f = Gᵀ·(τ − C(q, q̇)·q̇ − g(q) + Σ J_iᵀ f_ext,i)

    by the mass matrix (`mass_matrix`, armature included) and the bias forces
    (`bias_forces`) with a Cholesky solve; a coupled joint's torque, damping and
    armature act on its master through the coupling (Gᵀ·τ: virtual work). Into ``qdd``, and
    into ``work.D`` each joint's inertia as the projections take it (as the articulated
    inertia D_i of `forward_dynamics`): a free joint's diagonal entry of Gᵀ·M·G (its
    inertia with the other free joints held, its followers moving with it), a coupled
    joint's that over ratio² (infinite at ratio 0: a joint held at its offset)."""
    n = model.parent.size
    rhs = work.D
    _bias_forces(model, q, qd, fext, work, rhs)
    for i in range(n):
        rhs[i] = tau[i] - rhs[i]
    _composite_inertia(model, work, work.M)  # at the placements _bias_forces made
    reduce_coupled(couplings, laws, work.M, rhs)
    diag = work.u  # free after bias_forces
    for i in range(n):
        diag[i] = work.M[i, i]
    cholesky_solve(work.M, rhs, qdd)
    for k in range(couplings.shape[0]):
        s, m, r = couplings[k, 0], couplings[k, 1], laws[k, 0]
        qdd[s] = r * qdd[m]
        diag[s] = diag[m] / (r * r) if r != 0.0 else math.inf
    for i in range(n):
        work.D[i] = diag[i]


@kernel
def kinetic_energy(model, q, qd, work):
    """Kinetic energy T = ½·Σ v_iᵀ·I_i·v_i [J] (RBDA eq. 2.71) of the tree at (q, q̇)."""
    _velocities(model, q, qd, work)
    t = work.tmp6[2]
    T = 0.0
    for i in range(model.parent.size):
        rigid_inertia_times(model.mass[i], model.com[i], model.inertia[i], work.v[i], t)
        T += 0.5 * dot6(work.v[i], t)
    return T


@kernel
def potential_energy(model, q, work, R_world, p_world):
    """Gravitational potential energy V = −Σ m_i·g·c_i [J] of the links' centres of mass
    c_i in the world frame (zero with every centre of mass at the world origin; Pinocchio's
    ``computePotentialEnergy``). ``R_world``, ``p_world`` receive the link placements."""
    forward_kinematics(model, q, work, R_world, p_world)
    g = model.gravity
    V = 0.0
    for i in range(model.parent.size):
        for r in range(3):
            x = p_world[i, r]
            for k in range(3):
                x += R_world[i, r, k] * model.com[i, k]
            V -= model.mass[i] * g[r] * x
    return V


@kernel
def point_force(R_world, point, force, torque, out):
    """The spatial force in a link's frame (n, f) [N·m, N] of a force ``force`` [N] and a
    torque ``torque`` [N·m] (both in world axes) applied at ``point`` [m] of the link (in its
    link frame), the link's world rotation being ``R_world`` (RBDA §2.8): f = Rᵀ·F,
    n = point × f + Rᵀ·τ. Added to ``out`` (6,): several forces on one link sum."""
    f0 = R_world[0, 0] * force[0] + R_world[1, 0] * force[1] + R_world[2, 0] * force[2]
    f1 = R_world[0, 1] * force[0] + R_world[1, 1] * force[1] + R_world[2, 1] * force[2]
    f2 = R_world[0, 2] * force[0] + R_world[1, 2] * force[1] + R_world[2, 2] * force[2]
    for k in range(3):
        out[k] += R_world[0, k] * torque[0] + R_world[1, k] * torque[1] + R_world[2, k] * torque[2]
    out[0] += point[1] * f2 - point[2] * f1
    out[1] += point[2] * f0 - point[0] * f2
    out[2] += point[0] * f1 - point[1] * f0
    out[3] += f0
    out[4] += f1
    out[5] += f2
