"""Tree dynamics (hydroarm.core.tree) and mechanism descriptions (hydroarm.model.mechanism,
hydroarm.io.mechanism), checked against Pinocchio (issue 30; docs/mechanism.md).

Random trees (chains and branched, 1–12 joints, revolute and prismatic, random axes,
placements and inertias) are described once as a :class:`Mechanism`; Pinocchio's model is
built from that same description (``addJoint`` with the unaligned joint models, its own
``rpy`` conversion) and, through a URDF written here, by ``buildModelFromUrdf``. Mass matrix,
bias forces, inverse and forward dynamics and the energies agree to 1e-9 relative.
"""

import dataclasses
import math
import os
import re
import textwrap

import numpy as np
import pytest

from hydroarm.core import tree as T
from hydroarm.errors import HydroarmError
from hydroarm.io.mechanism import load_mechanism, mechanism_from_section
from hydroarm.model.mechanism import (
    Joint,
    Link,
    Mechanism,
    Payload,
    inertia_matrix,
    rpy_matrix,
)

DATA = os.path.join(os.path.dirname(__file__), "data", "mechanism")
RTOL = 1e-9


def rel(a, b) -> float:
    """Largest difference relative to the reference's largest entry."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


# --- random mechanisms -----------------------------------------------------------------------


def random_inertia(rng) -> tuple:
    """A physical inertia about the centre of mass: a random box's, rotated."""
    m = rng.uniform(0.2, 3.0)
    a, b, c = rng.uniform(0.05, 0.5, 3)
    moments = m / 12 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    R = rpy_matrix(rng.uniform(-math.pi, math.pi, 3))
    i3 = R @ np.diag(moments) @ R.T
    return m, (i3[0, 0], i3[1, 1], i3[2, 2], i3[0, 1], i3[0, 2], i3[1, 2])


def random_mechanism(rng, n: int, branched: bool, gravity=None) -> Mechanism:
    links = [Link("base")]
    joints = []
    for i in range(n):
        mass, inertia = random_inertia(rng)
        links.append(Link(f"l{i}", mass, tuple(rng.normal(scale=0.2, size=3)), inertia))
        parent = (
            "base" if i == 0 else f"l{rng.integers(-1, i)}" if branched else f"l{i - 1}"
        ).replace("l-1", "base")
        axis = rng.normal(size=3)
        joints.append(
            Joint(
                name=f"j{i}",
                type=("revolute", "prismatic", "continuous")[rng.integers(0, 3)],
                parent=parent,
                child=f"l{i}",
                axis=tuple(axis / np.linalg.norm(axis) * rng.uniform(0.5, 2)),
                origin=tuple(rng.normal(scale=0.3, size=3)),
                rpy=tuple(rng.uniform(-math.pi, math.pi, 3)),
            )
        )
    kw = {} if gravity is None else {"gravity": gravity}
    return Mechanism(links=tuple(links), joints=tuple(joints), **kw)


CASES = [
    (n, branched, seed)
    for seed, n in enumerate((1, 2, 3, 4, 5, 6, 8, 12))
    for branched in (False, True)
]
CASES += [(12, True, 100 + s) for s in range(4)]


# --- Pinocchio ----------------------------------------------------------------------------------


def pin_model(mech: Mechanism):
    """Pinocchio's model of a mechanism without fixed joints, built from the description
    (not from our compiled arrays), joints in our tree's order."""
    pin = pytest.importorskip("pinocchio")
    compiled = mech.compile()
    joints = {j.name: j for j in mech.joints}
    links = {link.name: link for link in mech.links}
    model = pin.Model()
    model.gravity = pin.Motion(np.r_[mech.gravity, 0.0, 0.0, 0.0])
    ids = {mech.base: 0}
    for name in compiled.joint_names:
        j = joints[name]
        axis = np.asarray(j.axis) / np.linalg.norm(j.axis)
        jm = (
            pin.JointModelPrismaticUnaligned(axis)
            if j.type == "prismatic"
            else pin.JointModelRevoluteUnaligned(axis)
        )
        placement = pin.SE3(pin.rpy.rpyToMatrix(*j.rpy), np.asarray(j.origin))
        jid = model.addJoint(ids[j.parent], jm, placement, name)
        link = links[j.child]
        model.appendBodyToJoint(
            jid,
            pin.Inertia(link.mass, np.asarray(link.com), inertia_matrix(link.inertia)),
            pin.SE3.Identity(),
        )
        ids[j.child] = jid
    return model


def pin_forces(pin, model, fext, order):
    """Our link forces (n, f) in link frames as Pinocchio's (f, n) per joint id."""
    forces = pin.StdVec_Force()
    for _ in range(model.njoints):
        forces.append(pin.Force.Zero())
    for i, jid in enumerate(order):
        forces[jid] = pin.Force(np.r_[fext[i, 3:], fext[i, :3]])
    return forces


def compare_with_pinocchio(compiled, model, rng, q_of=None, states=3):
    """Largest relative errors of our kernels against Pinocchio's on random states."""
    pin = pytest.importorskip("pinocchio")
    data = model.createData()
    tree = compiled.tree
    n = compiled.n
    order = [model.getJointId(name) for name in compiled.joint_names]
    # our joint i is Pinocchio's velocity index idx_v of its joint
    vidx = np.array([model.joints[jid].idx_v for jid in order])
    P = np.zeros((n, n))
    P[np.arange(n), vidx] = 1.0  # ours = P @ Pinocchio's
    work = T.make_tree_work(n)
    out = np.zeros(n)
    M = np.zeros((n, n))
    worst = dict.fromkeys(("M", "nle", "rnea", "aba", "crba_fd", "kinetic", "potential"), 0.0)
    for _ in range(states):
        q = rng.uniform(-math.pi, math.pi, n)
        qd, qdd, tau = (rng.normal(scale=2.0, size=n) for _ in range(3))
        fext = rng.normal(size=(n, 6))
        qp = q_of(q) if q_of else P.T @ q
        qdp, qddp, taup = P.T @ qd, P.T @ qdd, P.T @ tau
        fp = pin_forces(pin, model, fext, order)

        T.mass_matrix(tree, q, work, M)
        Mp = pin.crba(model, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        worst["M"] = max(worst["M"], rel(M, P @ Mp @ P.T))
        T.bias_forces(tree, q, qd, np.zeros((n, 6)), work, out)
        worst["nle"] = max(worst["nle"], rel(out, P @ pin.nonLinearEffects(model, data, qp, qdp)))
        T.inverse_dynamics(tree, q, qd, qdd, fext, work, out)
        worst["rnea"] = max(worst["rnea"], rel(out, P @ pin.rnea(model, data, qp, qdp, qddp, fp)))
        T.forward_dynamics(tree, q, qd, tau, fext, work, out)
        ref = P @ pin.aba(model, data, qp, qdp, taup, fp)
        worst["aba"] = max(worst["aba"], rel(out, ref))
        T.forward_dynamics_crba(tree, q, qd, tau, fext, work, out)
        worst["crba_fd"] = max(worst["crba_fd"], rel(out, ref))
        ke = T.kinetic_energy(tree, q, qd, work)
        worst["kinetic"] = max(
            worst["kinetic"], rel(ke, pin.computeKineticEnergy(model, data, qp, qdp))
        )
        Rw, pw = np.zeros((n, 3, 3)), np.zeros((n, 3))
        pe = T.potential_energy(tree, q, work, Rw, pw)
        # (neither counts the base link: it does not move)
        pe_ref = pin.computePotentialEnergy(model, data, qp)
        worst["potential"] = max(worst["potential"], abs(pe - pe_ref) / max(abs(pe_ref), 1.0))
        # link placements
        pin.forwardKinematics(model, data, qp)
        for i, jid in enumerate(order):
            assert rel(Rw[i], data.oMi[jid].rotation) < RTOL
            assert rel(pw[i], data.oMi[jid].translation) < RTOL
    return worst


@pytest.mark.parametrize(
    "n,branched,seed", CASES, ids=[f"{n}{'b' if b else 'c'}{s}" for n, b, s in CASES]
)
def test_random_trees_match_pinocchio(n, branched, seed):
    rng = np.random.default_rng(seed)
    gravity = tuple(rng.normal(scale=5.0, size=3)) if seed % 3 == 0 else None
    mech = random_mechanism(rng, n, branched, gravity)
    worst = compare_with_pinocchio(mech.compile(), pin_model(mech), rng)
    assert max(worst.values()) < RTOL, worst


def coordinate_axis_mechanism(rng, n: int, branched: bool, rpy: bool) -> Mechanism:
    """A random tree whose joints turn about or slide along ±x, ±y or ±z of their joint frames
    (the motion subspace one entry ±1: :func:`hydroarm.core.tree.subspace_index`), the joint
    frames rotated (``rpy``) or not (URDF files' usual joints)."""
    mech = random_mechanism(rng, n, branched)
    joints = []
    for j in mech.joints:
        axis = [0.0, 0.0, 0.0]
        axis[int(rng.integers(0, 3))] = float(rng.choice((-1.0, 1.0)))
        joints.append(
            dataclasses.replace(j, axis=tuple(axis), rpy=j.rpy if rpy else (0.0, 0.0, 0.0))
        )
    return Mechanism(links=mech.links, joints=tuple(joints))


@pytest.mark.parametrize("n,branched,seed", [(1, False, 30), (5, False, 31), (8, True, 32)])
@pytest.mark.parametrize("rpy", [False, True])
def test_coordinate_axis_trees_match_pinocchio(n, branched, seed, rpy):
    """Joints about coordinate axes take the one-entry products of the motion subspace."""
    rng = np.random.default_rng(seed)
    mech = coordinate_axis_mechanism(rng, n, branched, rpy)
    compiled = mech.compile()
    work = T.make_tree_work(n)
    T.joint_placements(compiled.tree, np.zeros(n), work)
    assert (work.Sk >= 0).all()
    assert ((work.Rk >= 0) != rpy).all()
    worst = compare_with_pinocchio(compiled, pin_model(mech), rng)
    assert max(worst.values()) < RTOL, worst


def test_massless_links_match_pinocchio():
    """Links with neither mass nor inertia between joints (frames, as the UCL arm's shoulder):
    the Newton–Euler pass skips their zero products."""
    rng = np.random.default_rng(40)
    mech = coordinate_axis_mechanism(rng, 5, False, False)
    links = tuple(Link(link.name) if link.name in ("l1", "l2") else link for link in mech.links)
    mech = Mechanism(links=links, joints=mech.joints)
    assert T.massless(0.0, np.zeros((3, 3))) and not T.massless(0.0, np.eye(3) * 1e-9)
    worst = compare_with_pinocchio(mech.compile(), pin_model(mech), rng)
    assert max(worst.values()) < RTOL, worst


def test_subspace_index():
    """The one non-zero entry of S for ±x, ±y, ±z (revolute: 0–2, prismatic: 3–5), −1 for
    any other axis."""
    for k in range(3):
        for sign in (1.0, -1.0):
            axis = np.zeros(3)
            axis[k] = sign
            assert T.subspace_index(T.REVOLUTE, axis) == k
            assert T.subspace_index(T.PRISMATIC, axis) == 3 + k
    for axis in ((0.6, 0.8, 0.0), (0.0, 0.0, 0.0), (0.0, 0.5, 0.0), (1.0, 1e-300, 0.0)):
        assert T.subspace_index(T.REVOLUTE, np.array(axis)) == -1


def test_subspace_products_are_the_full_ones_bit_for_bit():
    """Sᵀ·x and A·S by one entry and one column are the six-term sums exactly (the sums add
    only zeros); a force carried to the parent in place is add_force_to_parent's."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        A = rng.normal(size=(6, 6))
        x = rng.normal(size=6)
        for k in range(6):
            S = np.zeros(6)
            S[k] = rng.choice((-1.0, 1.0))
            got, ref = np.zeros(6), np.zeros(6)
            T.subspace_column(A, S, k, got)
            T.matvec6(A, S, ref)
            assert np.array_equal(got, ref)
            assert T.subspace_dot(S, k, x) == T.dot6(S, x)
        S = rng.normal(size=6)
        got, ref = np.zeros(6), np.zeros(6)
        T.subspace_column(A, S, -1, got)
        T.matvec6(A, S, ref)
        assert np.array_equal(got, ref) and T.subspace_dot(S, -1, x) == T.dot6(S, x)
        R, p, f = rpy_matrix(rng.uniform(-3, 3, 3)), rng.normal(size=3), rng.normal(size=6)
        ref = np.zeros(6)
        T.add_force_to_parent(R, p, f, ref)
        T.force_to_parent(R, p, f)
        assert np.array_equal(f, ref)


def test_transforms_about_a_coordinate_axis_are_the_full_ones_bit_for_bit():
    """A link turning about ±x, ±y or ±z of its parent (or not turning: prismatic), its
    joint's fixed rotation the identity: the transforms that skip R's zeros give the full
    ones' numbers exactly; any other placement has no axis (−1) and takes the full ones."""
    rng = np.random.default_rng(8)
    for jtype in (T.REVOLUTE, T.PRISMATIC):
        for k in range(3):
            for sign in (1.0, -1.0):
                axis = np.zeros(3)
                axis[k] = sign
                sk = T.subspace_index(jtype, axis)
                assert T.rotation_axis(jtype, np.eye(3), sk) == (k if jtype == T.REVOLUTE else 0)
                assert T.rotation_axis(jtype, rpy_matrix((0.0, 0.2, 0.0)), sk) == -1
                R, p = np.zeros((3, 3)), rng.normal(size=3)
                T.joint_transform(jtype, axis, rng.uniform(-4, 4), R, np.zeros(3))
                kr = T.rotation_axis(jtype, np.eye(3), sk)
                for _ in range(5):
                    m, f = rng.normal(size=6), rng.normal(size=6)
                    got, ref = np.zeros(6), np.zeros(6)
                    T.motion_to_child_about(R, kr, p, m, got)
                    T.motion_to_child(R, p, m, ref)
                    assert np.array_equal(got, ref)
                    got, ref = m.copy(), m.copy()
                    T.add_force_to_parent_about(R, kr, p, f, got)
                    T.add_force_to_parent(R, p, f, ref)
                    assert np.array_equal(got, ref)
                    got, ref = f.copy(), f.copy()
                    T.force_to_parent_about(R, kr, p, got)
                    T.force_to_parent(R, p, ref)
                    assert np.array_equal(got, ref)
    assert T.rotation_axis(T.REVOLUTE, np.eye(3), -1) == -1  # a tilted axis


def test_rigid_inertia_moves_to_the_parent_as_the_whole_matrix():
    """The ten-number transform of a rigid (or composite) inertia is X*·I·X of the whole 6×6
    (add_inertia_to_parent) to round-off, and keeps the rigid structure exactly."""
    rng = np.random.default_rng(11)
    for trial in range(20):
        I = np.zeros((6, 6))
        for _ in range(1 + trial % 3):  # a composite of rigid bodies is rigid
            m, i6 = random_inertia(rng)
            T.spatial_inertia(m * (trial % 4 != 0), rng.normal(size=3), inertia_matrix(i6), I)
        R, p = rpy_matrix(rng.uniform(-3, 3, 3)), rng.normal(size=3)
        base = rng.normal(size=(6, 6))
        base = base + base.T
        T.spatial_inertia(1.0, rng.normal(size=3), np.eye(3), base)
        got, ref = base.copy(), base.copy()
        T.add_rigid_inertia_to_parent(R, p, I, got)
        T.add_inertia_to_parent(R, p, I, ref, np.zeros((6, 6)))
        assert rel(got, ref) < 1e-14
        assert np.array_equal(got, got.T)
        for k in range(3):  # the off-diagonal blocks' diagonals, m·1's off-diagonal entries
            assert got[k, 3 + k] == got[3 + k, k] == 0.0
        assert got[3, 4] == got[3, 5] == got[4, 5] == 0.0


def test_payload_is_a_point_mass_under_gravity():
    """A payload of mass m at a point weighs as a force m·g applied at that point."""
    rng = np.random.default_rng(7)
    mech = random_mechanism(rng, 5, True)
    point = (0.1, -0.2, 0.3)
    loaded = Mechanism(mech.links, mech.joints, payloads=(Payload("box", "l3", 1.7, point),))
    a, b = mech.compile(), loaded.compile()
    n = a.n
    work = T.make_tree_work(n)
    q = rng.normal(size=n)
    Rw, pw = np.zeros((n, 3, 3)), np.zeros((n, 3))
    T.forward_kinematics(a.tree, q, work, Rw, pw)
    fext = np.zeros((n, 6))
    k = a.link_names.index("l3")
    T.point_force(Rw[k], np.array(point), 1.7 * a.tree.gravity, np.zeros(3), fext[k])
    with_force, with_payload = np.zeros(n), np.zeros(n)
    T.bias_forces(a.tree, q, np.zeros(n), fext, work, with_force)
    T.bias_forces(b.tree, q, np.zeros(n), np.zeros((n, 6)), work, with_payload)
    assert rel(with_force, with_payload) < 1e-12


# --- URDF -------------------------------------------------------------------------------------


def to_urdf(mech: Mechanism) -> str:
    """A URDF document of a mechanism (links' inertias about their centres, link axes)."""
    out = [f'<robot name="{mech.name}">']
    for link in mech.links:
        out.append(f'<link name="{link.name}">')
        if link.mass > 0:
            ixx, iyy, izz, ixy, ixz, iyz = link.inertia
            out.append(
                f'<inertial><origin xyz="{" ".join(map(repr, link.com))}" rpy="0 0 0"/>'
                f'<mass value="{link.mass!r}"/><inertia ixx="{ixx!r}" iyy="{iyy!r}" '
                f'izz="{izz!r}" ixy="{ixy!r}" ixz="{ixz!r}" iyz="{iyz!r}"/></inertial>'
            )
        out.append("</link>")
    for j in mech.joints:
        limit = ""
        if j.type in ("revolute", "prismatic"):
            limit = '<limit lower="-3" upper="3" effort="100" velocity="10"/>'
        out.append(
            f'<joint name="{j.name}" type="{j.type}"><parent link="{j.parent}"/>'
            f'<child link="{j.child}"/><origin xyz="{" ".join(map(repr, j.origin))}" '
            f'rpy="{" ".join(map(repr, j.rpy))}"/><axis xyz="{" ".join(map(repr, j.axis))}"/>'
            f"{limit}</joint>"
        )
    out.append("</robot>")
    return "\n".join(out)


def pin_q(model, compiled):
    """Our q as Pinocchio's configuration: an unbounded revolute joint's q is (cos, sin)."""

    def convert(q):
        qp = np.zeros(model.nq)
        for i, name in enumerate(compiled.joint_names):
            jm = model.joints[model.getJointId(name)]
            if jm.nq == 2:
                qp[jm.idx_q : jm.idx_q + 2] = math.cos(q[i]), math.sin(q[i])
            else:
                qp[jm.idx_q] = q[i]
        return qp

    return convert


@pytest.mark.parametrize("seed", [3, 11])
def test_urdf_written_here_matches_pinocchio(tmp_path, seed):
    """A random mechanism written as URDF: read by our reader (from a [mechanism] section)
    and by Pinocchio's buildModelFromUrdf, the dynamics agree."""
    pin = pytest.importorskip("pinocchio")
    rng = np.random.default_rng(seed)
    mech = random_mechanism(rng, 7, True)
    (tmp_path / "robot.urdf").write_text(to_urdf(mech))
    (tmp_path / "robot.toml").write_text('[mechanism]\nurdf = "robot.urdf"\n')
    ours = load_mechanism(tmp_path / "robot.toml").compile()
    direct = mech.compile()
    assert ours.joint_names == direct.joint_names
    for field in ("axis", "rotation", "translation", "mass", "com", "inertia"):
        assert rel(getattr(ours.tree, field), getattr(direct.tree, field)) < 1e-12, field
    model = pin.buildModelFromUrdf(str(tmp_path / "robot.urdf"))
    model.gravity = pin.Motion(np.r_[mech.gravity, 0.0, 0.0, 0.0])  # Pinocchio's is 9.81
    worst = compare_with_pinocchio(ours, model, rng, q_of=pin_q(model, ours))
    assert max(worst.values()) < RTOL, worst


def test_urdf_fixture_with_fixed_joint_matches_pinocchio():
    """tests/data/mechanism/leg.urdf: a fixed joint merged into its parent link (inertias
    combined, as Pinocchio does), an unaligned hip axis, an inertial frame rotated by rpy, a
    prismatic foot and a continuous joint."""
    pin = pytest.importorskip("pinocchio")
    path = os.path.join(DATA, "leg.urdf")
    compiled = load_mechanism(path).compile()
    assert compiled.joint_names == ("hip", "knee", "foot_slide", "tail_spin")
    assert compiled.link_names == ("thigh", "shank", "foot", "tail")
    assert compiled.tree.mass[0] == pytest.approx(2.8)  # thigh + sensor plate
    assert compiled.lower[1] == -2.4 and math.isinf(compiled.upper[3])
    assert compiled.damping[0] == 0.5 and compiled.friction[1] == 0.8
    model = pin.buildModelFromUrdf(path)
    model.gravity = pin.Motion(np.r_[compiled.tree.gravity, 0.0, 0.0, 0.0])  # its g is 9.81
    worst = compare_with_pinocchio(
        compiled, model, np.random.default_rng(5), q_of=pin_q(model, compiled)
    )
    assert max(worst.values()) < RTOL, worst


# --- physics without Pinocchio ----------------------------------------------------------------


def rk4_step(tree, work, q, qd, h, acc):
    n = q.size
    zero, fext = np.zeros(n), np.zeros((n, 6))

    def f(q, qd):
        T.forward_dynamics(tree, q, qd, zero, fext, work, acc)
        return qd.copy(), acc.copy()

    k1 = f(q, qd)
    k2 = f(q + h / 2 * k1[0], qd + h / 2 * k1[1])
    k3 = f(q + h / 2 * k2[0], qd + h / 2 * k2[1])
    k4 = f(q + h * k3[0], qd + h * k3[1])
    return (
        q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]),
        qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]),
    )


def energy(tree, work, q, qd):
    n = q.size
    return T.kinetic_energy(tree, q, qd, work) + T.potential_energy(
        tree, q, work, np.zeros((n, 3, 3)), np.zeros((n, 3))
    )


def energy_drift(tree, q0, qd0, h, duration):
    work = T.make_tree_work(q0.size)
    acc = np.zeros(q0.size)
    q, qd = q0.copy(), qd0.copy()
    e0 = energy(tree, work, q, qd)
    worst = 0.0
    for _ in range(int(round(duration / h))):
        q, qd = rk4_step(tree, work, q, qd, h, acc)
        worst = max(worst, abs(energy(tree, work, q, qd) - e0))
    return worst, e0


def test_unactuated_chain_conserves_energy():
    """A free 4-joint chain (3 revolute, 1 prismatic) under gravity, RK4 for 1 s. RK4's
    global error is O(h⁴), so is the energy error: it is small at h = 1 ms and falls by about
    2⁴ = 16 when h halves (≥ 10 allowed for the pre-asymptotic part); no damping exists, so
    a drift that does not shrink with h would be a modelling error, not the integrator's."""
    links = [Link("base")]
    joints = []
    for i, jtype in enumerate(("revolute", "revolute", "prismatic", "revolute")):
        links.append(
            Link(f"l{i}", 1.0 + 0.3 * i, (0.0, 0.02, -0.15), (0.02, 0.021, 0.003, 0, 0, 0))
        )
        joints.append(
            Joint(
                f"j{i}",
                jtype,
                "base" if i == 0 else f"l{i - 1}",
                f"l{i}",
                axis=(0.0, 1.0, 0.1 * i) if jtype == "revolute" else (0.0, 0.0, 1.0),
                origin=(0.0, 0.0, -0.3 if i else 0.0),
            )  # fmt: skip
        )
    tree = Mechanism(tuple(links), tuple(joints)).compile().tree
    q0 = np.array([0.8, -0.5, 0.05, 0.3])
    qd0 = np.array([0.5, -1.0, 0.2, 2.0])
    coarse, e0 = energy_drift(tree, q0, qd0, 1e-3, 1.0)
    fine, _ = energy_drift(tree, q0, qd0, 5e-4, 1.0)
    scale = abs(e0) + 10.0
    assert coarse / scale < 1e-8, (coarse, e0)
    assert coarse / fine > 10.0, (coarse, fine)


def test_pendulum_closed_form():
    """One revolute joint: a rod of mass m, centre of mass at l, inertia I_c about it.
    M = I_c + m·l², bias = m·g·l·sin θ, q̈ = (τ − m·g·l·sin θ)/(I_c + m·l²); and the period of
    a large swing is 4·√(I_o/(m·g·l))·K(sin(θ₀/2)) (complete elliptic integral)."""
    scipy_special = pytest.importorskip("scipy.special")
    m, l, ic = 1.3, 0.4, 0.02
    mech = Mechanism(
        (Link("base"), Link("rod", m, (0.0, 0.0, -l), (ic, ic, 0.001, 0, 0, 0))),
        (Joint("pivot", "revolute", "base", "rod", axis=(1.0, 0.0, 0.0)),),
    )
    tree = mech.compile().tree
    work = T.make_tree_work(1)
    g = T.STANDARD_GRAVITY
    io = ic + m * l * l
    M, out = np.zeros((1, 1)), np.zeros(1)
    for theta in (-2.0, 0.3, 1.1):
        q = np.array([theta])
        T.mass_matrix(tree, q, work, M)
        assert M[0, 0] == pytest.approx(io, rel=1e-14)
        T.bias_forces(tree, q, np.array([3.0]), np.zeros((1, 6)), work, out)
        assert out[0] == pytest.approx(m * g * l * math.sin(theta), rel=1e-13)
        T.forward_dynamics(tree, q, np.array([3.0]), np.array([0.7]), np.zeros((1, 6)), work, out)
        assert out[0] == pytest.approx((0.7 - m * g * l * math.sin(theta)) / io, rel=1e-13)
    theta0 = 2.0
    period = 4 * math.sqrt(io / (m * g * l)) * scipy_special.ellipk(math.sin(theta0 / 2) ** 2)
    # integrate a quarter swing from rest at θ₀ to the bottom (θ = 0) with RK4
    h = 1e-4
    q, qd = np.array([theta0]), np.array([0.0])
    acc = np.zeros(1)
    t = 0.0
    while True:
        qn, qdn = rk4_step(tree, work, q, qd, h, acc)
        if qn[0] <= 0.0:
            t += h * q[0] / (q[0] - qn[0])  # linear interpolation of the crossing
            break
        q, qd, t = qn, qdn, t + h
    assert 4 * t == pytest.approx(period, rel=1e-6)


def test_forward_dynamics_does_not_allocate_per_call():
    """The hot functions write into the work arrays: calling them does not change the
    output array's identity and leaves no state behind (same answer twice)."""
    rng = np.random.default_rng(2)
    tree = random_mechanism(rng, 6, True).compile().tree
    work = T.make_tree_work(6)
    q, qd, tau = (rng.normal(size=6) for _ in range(3))
    a, b = np.zeros(6), np.zeros(6)
    T.forward_dynamics(tree, q, qd, tau, np.zeros((6, 6)), work, a)
    T.mass_matrix(tree, rng.normal(size=6), work, np.zeros((6, 6)))
    T.forward_dynamics(tree, q, qd, tau, np.zeros((6, 6)), work, b)
    assert np.array_equal(a, b)


# --- mechanism files --------------------------------------------------------------------------

GOOD = """
[mechanism]
name = "two links"
[[mechanism.link]]
name = "base"
[[mechanism.link]]
name = "upper"
mass = "1.2 kg"
com = ["0 m", "0 m", "-15 cm"]
ixx = "0.01 kg*m**2"
iyy = "0.01 kg*m**2"
izz = "0.001 kg*m**2"
[[mechanism.link]]
name = "lower"
mass = "800 g"
com = ["0 m", "0 m", "-0.1 m"]
ixx = "0.005 kg*m**2"
iyy = "0.005 kg*m**2"
izz = "0.0005 kg*m**2"
[[mechanism.joint]]
name = "shoulder"
type = "revolute"
parent = "base"
child = "upper"
origin = ["0 m", "0 m", "0.3 m"]
rpy = ["0 deg", "0 deg", "90 deg"]
axis = [0, 1, 0]
lower = "-30 deg"
upper = "120 deg"
damping = "0.1 N*m*s/rad"
friction = "0.2 N*m"
[[mechanism.joint]]
name = "elbow"
type = "revolute"
parent = "upper"
child = "lower"
origin = ["0 m", "0 m", "-0.3 m"]
axis = [0, 1, 0]
[[mechanism.payload]]
name = "tool"
link = "lower"
mass = "0.5 kg"
point = ["0 m", "0 m", "-0.25 m"]
"""


def load_text(tmp_path, text, name="mech.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return load_mechanism(path)


def test_toml_mechanism_in_si(tmp_path):
    mech = load_text(tmp_path, GOOD)
    c = mech.compile()
    assert c.joint_names == ("shoulder", "elbow")
    assert c.lower[0] == pytest.approx(math.radians(-30)) and c.upper[0] == pytest.approx(
        math.radians(120)
    )
    assert c.damping[0] == pytest.approx(0.1) and c.friction[0] == pytest.approx(0.2)
    assert c.tree.mass[1] == pytest.approx(1.3)  # the link and its payload
    assert c.tree.com[1, 2] == pytest.approx((0.8 * -0.1 + 0.5 * -0.25) / 1.3)
    assert c.tree.rotation[0] == pytest.approx(rpy_matrix((0, 0, math.pi / 2)))
    assert mech.gravity == (0.0, 0.0, -9.80665)


def edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


BAD = [
    # (edit, field, words in the problem)
    (('parent = "upper"', 'parent = "lower"'), "mechanism.joint.elbow.child", "own parent"),
    (
        ('parent = "upper"', 'parent = "uper"'),
        "mechanism.joint.elbow.parent",
        "did you mean 'upper'",
    ),
    (
        ('name = "base"', 'name = "base"\n[[mechanism.link]]\nname = "spare"\nmass = "1 kg"'),
        "mechanism.link",
        "2 roots",
    ),
    (
        ('ixx = "0.01 kg*m**2"', 'ixx = "-0.01 kg*m**2"'),
        "mechanism.link.upper.inertia",
        "not positive definite",
    ),
    (
        ('izz = "0.001 kg*m**2"', 'izz = "0.03 kg*m**2"'),
        "mechanism.link.upper.inertia",
        "triangle inequality",
    ),
    (('mass = "1.2 kg"', 'mass = "-1.2 kg"'), "mechanism.link.upper.mass", "negative"),
    (
        ('mass = "800 g"', 'mass = "0 g"', 'link = "lower"', 'link = "upper"'),
        "mechanism.link.lower.mass",
        "must be positive",
    ),
    (
        ("axis = [0, 1, 0]\nlower", "axis = [0, 0, 0]\nlower"),
        "mechanism.joint.shoulder.axis",
        "is zero",
    ),
    (
        ('type = "revolute"', 'type = "revolut"'),
        "mechanism.joint.shoulder.type",
        "did you mean 'revolute'",
    ),
    (('type = "revolute"', 'type = "ball"'), "mechanism.joint.shoulder.type", "unknown joint type"),
    (
        ('upper = "120 deg"', 'upper = "-40 deg"'),
        "mechanism.joint.shoulder.upper",
        "below the lower",
    ),
    (('mass = "1.2 kg"', 'mass = "1.2 m"'), "mechanism.link.upper.mass", "not in units of kg"),
    (('link = "lower"', 'link = "hand"'), "mechanism.payload.tool.link", "no link named 'hand'"),
    (('child = "lower"', 'child = "upper"'), "mechanism.joint.elbow.child", "own parent"),
    (
        ('damping = "0.1 N*m*s/rad"', 'damping = "-0.1 N*m*s/rad"'),
        "mechanism.joint.shoulder.damping",
        "negative",
    ),
]


@pytest.mark.parametrize("change,field,words", BAD, ids=[b[2] for b in BAD])
def test_bad_mechanism_is_one_line(tmp_path, change, field, words):
    text = GOOD
    for k in range(0, len(change), 2):
        text = edit(text, change[k], change[k + 1])
    with pytest.raises(HydroarmError) as err:
        load_text(tmp_path, text)
    message = str(err.value)
    assert "\n" not in message
    assert err.value.field.startswith(field), message
    assert words in err.value.problem, message


def test_cycle_off_the_base(tmp_path):
    """Two links each the other's parent, beside a tree with a base: a cycle."""
    text = GOOD + textwrap.dedent(
        """
        [[mechanism.link]]
        name = "a"
        mass = "1 kg"
        [[mechanism.link]]
        name = "b"
        mass = "1 kg"
        [[mechanism.joint]]
        name = "ab"
        type = "revolute"
        parent = "a"
        child = "b"
        [[mechanism.joint]]
        name = "ba"
        type = "revolute"
        parent = "b"
        child = "a"
        """
    )
    with pytest.raises(
        HydroarmError, match=r"mechanism\.joint\.ab: is part of a cycle .*b <- a <- b"
    ):
        load_text(tmp_path, text)


def test_every_link_a_child_is_a_cycle():
    links = (Link("a", 1.0), Link("b", 1.0))
    joints = (Joint("ab", "revolute", "a", "b"), Joint("ba", "revolute", "b", "a"))
    with pytest.raises(HydroarmError, match=r"mechanism\.joint\.ab: is part of a cycle"):
        Mechanism(links, joints)


def test_bad_urdf_is_one_line(tmp_path):
    (tmp_path / "m.toml").write_text('[mechanism]\nurdf = "leg.urdf"\n')
    with pytest.raises(HydroarmError, match=r"^mechanism\.urdf: .*leg\.urdf: file not found$"):
        load_mechanism(tmp_path / "m.toml")
    (tmp_path / "leg.urdf").write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(HydroarmError) as err:
        load_mechanism(tmp_path / "m.toml")
    assert err.value.field == "mechanism.urdf" and "not a readable URDF" in err.value.problem
    assert "\n" not in str(err.value)
    text = open(os.path.join(DATA, "leg.urdf")).read()
    (tmp_path / "leg.urdf").write_text(re.sub(r'<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>', text))
    with pytest.raises(
        HydroarmError, match=r"^mechanism\.urdf: leg\.urdf: joint\.knee\.axis: is zero"
    ):
        load_mechanism(tmp_path / "m.toml")
    (tmp_path / "leg.urdf").write_text(text.replace('type="continuous"', 'type="floating"'))
    with pytest.raises(HydroarmError, match=r"tail_spin.*'floating' is not supported"):
        load_mechanism(tmp_path / "m.toml")


def test_urdf_with_links_and_joints_too(tmp_path):
    with pytest.raises(HydroarmError, match=r"mechanism\.link: give links and joints"):
        mechanism_from_section({"urdf": "x.urdf", "link": []}, tmp_path)
