"""Kinematic couplings between joints (issue 30; docs/mechanism.md "Kinematic couplings").

A coupled joint follows another, q_s = ratio·q_m + offset (URDF's ``<mimic>``). The reduced
equations of the free joints, Gᵀ·M·G·q̈_f = Gᵀ·(τ − bias)
(:func:`hydroarm.core.tree.forward_dynamics_coupled`), are checked against an independent
formulation — the constrained system solved with Lagrange multipliers on Pinocchio's mass
matrix and bias forces — and, in the system kernel, by energy conservation, by a joint held
at its offset against the same joint welded, by two descriptions of one coupled boom, and by
the energy account; then the files (TOML and URDF) and every bad input.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import pytest
from test_tree import pin_model, random_mechanism, rel

from hydroarm.core import tree as T
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import circuit_from_doc
from hydroarm.io.mechanism import load_mechanism
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import build, simulate
from hydroarm.model.mechanism import Coupling, Mechanism

DATA = Path(__file__).parent / "data" / "mechanism"
RTOL = 1e-9


def _doc(name: str) -> dict:
    return parse_toml((DATA / name).read_text(), name)


# --- the reduced equations against Lagrange multipliers on Pinocchio's M and bias --------------


def _with_couplings(rng, mech: Mechanism, chain: bool) -> Mechanism:
    """The mechanism with one to three joints coupled to others (one of them, if ``chain``,
    following a coupled joint), random ratios and offsets."""
    names = [j.name for j in mech.joints]
    k = min(len(names) - 1, int(rng.integers(1, 4)))
    coupled = list(rng.choice(names, size=k, replace=False))
    free = [x for x in names if x not in coupled]
    couplings = []
    for i, name in enumerate(coupled):
        follows = coupled[0] if chain and i > 0 else str(rng.choice(free))
        couplings.append(
            Coupling(name, follows, float(rng.uniform(-2.0, 2.0)), float(rng.uniform(-1, 1)))
        )
    return Mechanism(mech.links, mech.joints, mech.gravity, couplings=tuple(couplings))


def _kkt_accelerations(M, bias, tau, C):
    """q̈ of M·q̈ + bias = τ + Cᵀ·λ with C·q̈ = 0 (C constant: −Ċ·q̇ = 0), by one solve of
    the saddle-point system [[M, Cᵀ], [C, 0]]·[q̈; λ] = [τ − bias; 0]."""
    n, k = M.shape[0], C.shape[0]
    K = np.zeros((n + k, n + k))
    K[:n, :n] = M
    K[:n, n:] = C.T
    K[n:, :n] = C
    return np.linalg.solve(K, np.concatenate([tau - bias, np.zeros(k)]))[:n]


CASES = [(n, branched, seed) for seed, n in enumerate((2, 3, 4, 6, 8, 12)) for branched in
         (False, True)]  # fmt: skip


@pytest.mark.parametrize(
    "n,branched,seed", CASES, ids=[f"{n}{'b' if b else 'c'}{s}" for n, b, s in CASES]
)
def test_reduced_dynamics_match_lagrange_multipliers_on_pinocchio(n, branched, seed):
    """On random trees with couplings (chains of couplings among them), random states,
    torques, armatures and external forces: the kernel's q̈ equals the constrained
    system's, solved with Lagrange multipliers, the constraints written from the couplings
    as given (q_s − ratio·q_m − offset = 0, a chain's links one by one), M and the bias from
    Pinocchio (pin.crba, pin.rnea at q̈ = 0 with the external forces)."""
    pin = pytest.importorskip("pinocchio")
    rng = np.random.default_rng(300 + seed)
    gravity = tuple(rng.normal(scale=5.0, size=3)) if seed % 2 else None
    mech = _with_couplings(rng, random_mechanism(rng, n, branched, gravity), chain=seed % 3 == 1)
    compiled = mech.compile()
    model = pin_model(mech)
    data = model.createData()
    order = [model.getJointId(name) for name in compiled.joint_names]
    vidx = np.array([model.joints[jid].idx_v for jid in order])
    P = np.zeros((n, n))
    P[np.arange(n), vidx] = 1.0  # ours = P @ Pinocchio's
    index = {name: i for i, name in enumerate(compiled.joint_names)}
    C = np.zeros((len(mech.couplings), n))
    for r, c in enumerate(mech.couplings):
        C[r, index[c.joint]] = 1.0
        C[r, index[c.follows]] = -c.ratio
    work = T.make_tree_work(n)
    qdd = np.zeros(n)
    worst = 0.0
    for _ in range(3):
        # free joints random, the coupled ones from the couplings as given (a chain's
        # follower after its master: n sweeps settle any order)
        q = rng.uniform(-math.pi, math.pi, n)
        qd = rng.normal(scale=2.0, size=n)
        for _ in range(n):
            for c in mech.couplings:
                q[index[c.joint]] = c.ratio * q[index[c.follows]] + c.offset
                qd[index[c.joint]] = c.ratio * qd[index[c.follows]]
        tau = rng.normal(scale=2.0, size=n)
        fext = rng.normal(size=(n, 6))
        armature = rng.uniform(0.0, 0.1, n)
        work.armature[:] = armature
        fp = pin.StdVec_Force()
        for _ in range(model.njoints):
            fp.append(pin.Force.Zero())
        for i, jid in enumerate(order):
            fp[jid] = pin.Force(np.r_[fext[i, 3:], fext[i, :3]])
        qp, qdp = P.T @ q, P.T @ qd
        Mp = pin.crba(model, data, qp)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        M = P @ Mp @ P.T + np.diag(armature)
        bias = P @ pin.rnea(model, data, qp, qdp, np.zeros(n), fp)
        ref = _kkt_accelerations(M, bias, tau, C)
        T.forward_dynamics_coupled(
            compiled.tree, compiled.couplings, compiled.coupling_laws, q, qd, tau, fext, work,
            qdd,
        )  # fmt: skip
        worst = max(worst, rel(qdd, ref))
        assert np.abs(C @ qdd).max() <= 1e-12 * np.abs(qdd).max()  # q̈ keeps the couplings
    # both sides solve a small well-conditioned system in double precision: the differences
    # are round-off (measured ≤ 4.5e-14), far under 1e-9
    assert worst < RTOL, worst


def test_couplings_of_a_chain_resolve_to_its_free_joint():
    rng = np.random.default_rng(5)
    mech = random_mechanism(rng, 4, False)
    chained = Mechanism(
        mech.links, mech.joints,
        couplings=(Coupling("j3", "j2", 2.0, 0.1), Coupling("j2", "j0", -0.5, 0.3)),
    )  # fmt: skip
    c = chained.compile()
    i = {name: k for k, name in enumerate(c.joint_names)}
    assert c.master[i["j3"]] == c.master[i["j2"]] == i["j0"]
    assert c.ratio[i["j3"]] == pytest.approx(-1.0)  # 2·(−0.5)
    assert c.offset[i["j3"]] == pytest.approx(2.0 * 0.3 + 0.1)
    assert c.master[i["j1"]] == i["j1"] and c.ratio[i["j1"]] == 1.0


# --- in the system kernel ------------------------------------------------------------------------


def _coupled_pendulum(doc, ratio=-0.5, offset="10 deg"):
    """The double pendulum with its elbow following its shoulder."""
    doc["mechanism"]["coupling"] = [
        {"joint": "elbow", "follows": "shoulder", "ratio": ratio, "offset": offset}
    ]
    del doc["initial"]["elbow"]
    return doc


def _energy(cc, states):
    tree = cc.mechanism.tree
    work = T.make_tree_work(2)
    R, p = np.zeros((2, 3, 3)), np.zeros((2, 3))
    e = []
    for row in states:
        q, qd = row[:2].copy(), row[2:4].copy()
        e.append(T.kinetic_energy(tree, q, qd, work) + T.potential_energy(tree, q, work, R, p))
    return np.array(e)


def test_passive_coupled_chain_conserves_energy():
    """No damping, no friction: the coupled double pendulum's T + V (of the whole tree, the
    coupled joint moving with its master) is constant to RK4's error, which falls about
    16-fold when the step halves (fourth order: the drift is the integrator's truncation,
    not a modelling error). The elbow keeps its coupling at every record."""
    drift = []
    for step in ("2 ms", "1 ms"):
        doc = _coupled_pendulum(_doc("double_pendulum.toml"))
        doc["solver"]["step"] = step
        doc["solver"]["record_every"] = 1
        cc = build(circuit_from_doc(doc, "coupled", DATA))
        r = simulate(cc)
        assert r.bad_step == -1
        q = r.states[:, :2]
        np.testing.assert_allclose(q[:, 1], -0.5 * q[:, 0] + math.radians(10), atol=1e-14)
        e = _energy(cc, r.states)
        drift.append(np.ptp(e))
    scale = 2.5 * T.STANDARD_GRAVITY * 0.5  # m·g·(a length of the chain) ≈ 12 J
    # at h = 1 ms the swing (6 rad/s at most) has ωh = 6e-3, RK4's local energy error
    # ~ (ωh)⁵ ≈ 8e-12 of the energy a step: measured 1.6e-11 J of T + V over the second
    # (2.6e-10 J at 2 ms); at smaller steps round-off (~1e-13 J) takes over and the ratio
    # below would not show the order
    assert drift[1] < 1e-9 * scale, drift
    assert 12.0 < drift[0] / drift[1] < 20.0, drift  # 2⁴ = 16: measured 16.3


def test_the_batch_engine_runs_a_coupled_mechanism_as_simulate_does():
    """A row of the batch engine is the same coupled run as :func:`simulate`, to the bit."""
    from hydroarm.model.circuit import simulate_many

    cc = build(circuit_from_doc(_coupled_pendulum(_doc("double_pendulum.toml")), "c", DATA))
    alone = simulate(cc)
    table = np.repeat(cc.P[None, :], 2, axis=0)
    _, states, bad = simulate_many(cc, table, cc.initial_states(table))
    assert list(bad) == [-1, -1]
    np.testing.assert_array_equal(states[1], alone.states)


def test_ratio_zero_holds_the_joint_as_a_fixed_one():
    """A coupling of ratio 0 holds the elbow at its offset: the shoulder moves as with the
    elbow welded at that angle (a fixed joint, its link merged into the upper arm), though
    by another route (CRBA and the reduced solve, not the ABA on the merged link)."""
    held = simulate(
        circuit_from_doc(
            _coupled_pendulum(_doc("double_pendulum.toml"), 0.0, "-40 deg"), "held", DATA
        )  # fmt: skip
    )
    doc = _doc("double_pendulum.toml")
    doc["mechanism"]["joint"][1]["type"] = "fixed"
    doc["mechanism"]["joint"][1]["rpy"] = ["0 deg", "-40 deg", "0 deg"]
    del doc["initial"]["elbow"]
    welded = simulate(circuit_from_doc(doc, "welded", DATA))
    np.testing.assert_allclose(held.output("elbow_angle_deg"), -40.0, rtol=0, atol=1e-12)
    # two routes to the same q̈ differ by round-off (1e-15 relative), which RK4 carries over
    # 10000 steps of a regular (not chaotic) swing: measured 1.1e-13 deg
    np.testing.assert_allclose(
        held.output("shoulder_angle_deg"), welded.output("shoulder_angle_deg"), rtol=0,
        atol=1e-9,
    )  # fmt: skip


def _folding_boom(doc, swap: bool):
    """The boom with a tip link on a joint ``fold`` that keeps the tip level (fold = −lift):
    ``fold`` follows ``lift``, or (``swap``) ``lift`` follows ``fold`` — then the cylinder's
    linkage drives the coupled joint."""
    doc["mechanism"]["link"].append(
        {"name": "tip", "mass": "20 kg", "com": ["0.3 m", "0 m", "0 m"], "ixx": "0.1 kg*m**2",
         "iyy": "0.5 kg*m**2", "izz": "0.5 kg*m**2"}
    )  # fmt: skip
    doc["mechanism"]["joint"].append(
        {"name": "fold", "type": "revolute", "parent": "boom", "child": "tip",
         "origin": ["1.6 m", "0 m", "0 m"], "axis": [0, -1, 0], "damping": "5 N*m*s/rad"}
    )  # fmt: skip
    joint, follows = ("lift", "fold") if swap else ("fold", "lift")
    doc["mechanism"]["coupling"] = [{"joint": joint, "follows": follows, "ratio": -1.0}]
    if swap:
        doc["initial"]["fold"] = doc["initial"].pop("lift")
    doc["solver"]["duration"] = "1 s"
    return doc


@pytest.mark.slow
def test_a_coupled_boom_is_the_same_whichever_joint_is_free():
    """One physical system written two ways — the tip's joint following the lift joint, or
    the lift joint (the one the cylinder drives, through its linkage) following the tip's —
    runs the same from the same equilibrium start: the coupled joint's actuator torque and
    damping act through the coupling. The energy account closes in both."""
    runs = []
    for swap in (False, True):
        r = simulate(circuit_from_doc(_folding_boom(_doc("boom.toml"), swap), "fold", DATA))
        assert r.bad_step == -1
        np.testing.assert_allclose(
            r.output("fold_angle_deg"), -r.output("lift_angle_deg"), rtol=0, atol=1e-12
        )
        e = r.energy()
        # the powers sum to zero at every record, so the closure is round-off only
        # (measured 4e-12 J of 3.1 kJ)
        assert abs(e["closure_energy_j"]) < 1e-9 * max(abs(v) for v in e.values()), e
        runs.append(r)
    a, b = runs
    assert np.ptp(a.output("lift_angle_deg")) > 5.0  # it moves
    # the same equations by two reductions (G's column on either joint): their round-off
    # may differ and RK4 at 20 µs would carry it (measured: none, ratio −1 making the two
    # reductions the same arithmetic)
    np.testing.assert_allclose(a.output("lift_angle_deg"), b.output("lift_angle_deg"),
                               rtol=0, atol=1e-7)  # fmt: skip
    np.testing.assert_allclose(a.output("A_pressure_bar"), b.output("A_pressure_bar"),
                               rtol=1e-8)  # fmt: skip


def test_a_coupled_joint_pinned_in_a_static_solve_pins_its_master():
    """The static solve (an equilibrium start, the linear view's operating point) pins a
    coupled joint through its master: fold = −lift, so fold at −5° holds lift at 5°."""
    from hydroarm.model.circuit_steady import steady_state

    cc = build(circuit_from_doc(_folding_boom(_doc("boom.toml"), swap=False), "fold", DATA))
    point = steady_state(cc, 0.0, {"fold": math.radians(-5.0)})
    nh = len(cc.hydraulic)
    lift, fold = (cc.mechanical[k] for k in ("lift", "fold"))
    assert point.state[nh + lift] == pytest.approx(math.radians(5.0), abs=1e-12)
    assert point.state[nh + fold] == pytest.approx(math.radians(-5.0), abs=1e-12)


def test_the_linear_view_holds_a_coupled_joint():
    """``hydroarm linearize`` on the coupled boom: the coupled joint is set by the kernel, so
    it is no state (as many poles as the boom without the tip), and the poles are the same
    whichever joint is free and whichever joint's angle is the output."""
    from hydroarm.analysis.circuit_linear import linearize_circuit

    plain = linearize_circuit(
        build(circuit_from_doc(_doc("boom.toml"), "boom", DATA)), "lever", "lift_angle_deg",
        math.radians(10),
    )  # fmt: skip
    poles = []
    for swap in (False, True):
        cc = build(circuit_from_doc(_folding_boom(_doc("boom.toml"), swap), "fold", DATA))
        for out, pos in (("lift_angle_deg", 10.0), ("fold_angle_deg", -10.0)):
            p = np.sort_complex(linearize_circuit(cc, "lever", out, math.radians(pos)).poles)
            assert p.size == plain.poles.size
            poles.append(p)
    # the Jacobians are central differences of the same right-hand side at the same state:
    # measured equal to 4e-16 1/s; 1e-6 leaves the differences' truncation room
    for p in poles[1:]:
        np.testing.assert_allclose(p, poles[0], rtol=1e-6, atol=1e-6)
    # the oil column's pair, 133 1/s with the tip where the boom alone has 207 1/s
    assert np.abs(poles[0].imag).max() > 100.0


def test_limits_and_friction_of_a_coupled_joint_act_through_its_master():
    """The elbow's limits stop the shoulder where the elbow reaches them; the elbow's dry
    friction (acting through the coupling as |ratio|·F on the shoulder) holds the pendulum
    that it is strong enough to hold."""
    doc = _coupled_pendulum(_doc("double_pendulum.toml"), -0.5, "0 deg")
    doc["mechanism"]["joint"][1].update(type="revolute", lower="-30 deg", upper="30 deg")
    r = simulate(circuit_from_doc(doc, "limited", DATA))
    elbow = r.output("elbow_angle_deg")
    shoulder = r.output("shoulder_angle_deg")
    assert elbow.min() >= -30.0 - 1e-9 and elbow.max() <= 30.0 + 1e-9
    assert shoulder.max() == pytest.approx(60.0, abs=1e-9)  # the elbow at −30°: a stop
    cc = build(circuit_from_doc(doc, "limited", DATA))
    np.testing.assert_allclose(cc.joint_limits[0, 2:], np.radians([-60.0, 60.0]))
    assert np.all(np.isinf(cc.joint_limits[1, 2:]))  # the elbow's own: through the shoulder
    # gravity's moment at the shoulder at 20° is below 12 N·m (2.5 kg, centre of mass ≤ 0.5 m);
    # 30 N·m at the elbow is 15 N·m at the shoulder through ratio 0.5: it sticks
    doc["mechanism"]["joint"][1]["friction"] = "30 N*m"
    stuck = simulate(circuit_from_doc(doc, "stuck", DATA))
    np.testing.assert_allclose(stuck.output("shoulder_angle_deg"), 20.0, rtol=0, atol=1e-12)
    assert build(circuit_from_doc(doc, "stuck", DATA)).joint_limits[0, 1] == pytest.approx(15.0)


def test_hydroarm_arm_writes_the_coupled_joints_columns(tmp_path):
    import pandas as pd

    from hydroarm.cli import main

    text = (DATA / "double_pendulum.toml").read_text().replace('elbow = "-40 deg"\n', "")
    text += textwrap.dedent(
        """
        [[mechanism.coupling]]
        joint = "elbow"
        follows = "shoulder"
        ratio = -0.5
        offset = "10 deg"
        """
    )
    path = tmp_path / "coupled.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["arm", "--config", str(path), "--out", str(out), "--no-animation"]) == 0
    df = pd.read_csv(out / "joints.csv")
    for col in ("elbow_angle_deg", "elbow_angular_velocity_rad_s", "elbow_torque_n_m"):
        assert col in df, col
    assert df["elbow_angle_deg"].iloc[0] == pytest.approx(0.0)  # −0.5·20° + 10°
    # the CSV's 10 significant digits
    np.testing.assert_allclose(
        df["elbow_angle_deg"], -0.5 * df["shoulder_angle_deg"] + 10.0, rtol=0, atol=1e-7
    )


# --- files ---------------------------------------------------------------------------------------

URDF = """<?xml version="1.0"?>
<robot name="gripper">
  <link name="base"/>
  <link name="arm">
    <inertial><mass value="1.0"/><origin xyz="0.2 0 0"/>
      <inertia ixx="1e-3" iyy="1e-2" izz="1e-2" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="finger_a">
    <inertial><mass value="0.1"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>
  <link name="finger_b">
    <inertial><mass value="0.1"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>
  <joint name="swing" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
  </joint>
  <joint name="grip" type="prismatic">
    <parent link="arm"/><child link="finger_a"/><origin xyz="0.4 0 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.04" effort="10" velocity="1"/>
  </joint>
  <joint name="grip_mirror" type="prismatic">
    <parent link="arm"/><child link="finger_b"/><origin xyz="0.4 0 0"/><axis xyz="0 0 -1"/>
    <limit lower="0" upper="0.04" effort="10" velocity="1"/>
    <mimic joint="grip" multiplier="1.0" offset="0.001"/>
  </joint>
  <joint name="wrist_follow" type="revolute">
    <parent link="finger_b"/><child link="tip"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/>
    <mimic joint="swing"/>
  </joint>
  <link name="tip">
    <inertial><mass value="0.05"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>
</robot>
"""


def test_urdf_mimic_is_a_coupling(tmp_path):
    (tmp_path / "gripper.urdf").write_text(URDF)
    mech = load_mechanism(tmp_path / "gripper.urdf")
    assert set(mech.couplings) == {
        Coupling("grip_mirror", "grip", 1.0, 0.001),
        Coupling("wrist_follow", "swing", 1.0, 0.0),  # URDF's defaults
    }
    c = mech.compile()
    i = {name: k for k, name in enumerate(c.joint_names)}
    assert c.master[i["grip_mirror"]] == i["grip"] and c.offset[i["grip_mirror"]] == 0.001
    # grip_mirror's limits [0, 0.04] need grip in [−0.001, 0.039]: grip's range narrows
    np.testing.assert_allclose(c.kernel_limits()[i["grip"], 2:], [0.0, 0.039])
    # from a TOML file naming the URDF, with a coupling of its own beside the mimics
    (tmp_path / "m.toml").write_text(
        textwrap.dedent(
            """
            [mechanism]
            urdf = "gripper.urdf"
            [[mechanism.coupling]]
            joint = "grip"
            follows = "swing"
            ratio = "0.01 m/rad"
            """
        )
    )
    mech = load_mechanism(tmp_path / "m.toml")
    c = mech.compile()
    assert c.master[i["grip_mirror"]] == i["swing"]  # a chain: grip_mirror -> grip -> swing
    assert c.ratio[i["grip_mirror"]] == pytest.approx(0.01)


GOOD = """
[mechanism]
[[mechanism.link]]
name = "base"
[[mechanism.link]]
name = "upper"
mass = "1 kg"
com = ["0.2 m", "0 m", "0 m"]
ixx = "0.001 kg*m**2"
iyy = "0.01 kg*m**2"
izz = "0.01 kg*m**2"
[[mechanism.link]]
name = "lower"
mass = "1 kg"
com = ["0.2 m", "0 m", "0 m"]
ixx = "0.001 kg*m**2"
iyy = "0.01 kg*m**2"
izz = "0.01 kg*m**2"
[[mechanism.link]]
name = "slider"
mass = "1 kg"
[[mechanism.joint]]
name = "shoulder"
type = "revolute"
parent = "base"
child = "upper"
axis = [0, 1, 0]
lower = "-90 deg"
upper = "90 deg"
[[mechanism.joint]]
name = "elbow"
type = "revolute"
parent = "upper"
child = "lower"
origin = ["0.4 m", "0 m", "0 m"]
axis = [0, 1, 0]
lower = "-30 deg"
upper = "30 deg"
[[mechanism.joint]]
name = "slide"
type = "prismatic"
parent = "lower"
child = "slider"
axis = [1, 0, 0]
[[mechanism.joint]]
name = "weld"
type = "fixed"
parent = "slider"
child = "tool"
[[mechanism.link]]
name = "tool"
mass = "0.1 kg"
[[mechanism.coupling]]
joint = "elbow"
follows = "shoulder"
ratio = -0.5
offset = "0 deg"
"""

BAD = [
    # (old, new, field, words)
    ('follows = "shoulder"', 'follows = "elbow"', "mechanism.coupling.elbow.follows",
     "cannot follow itself"),
    ('follows = "shoulder"', 'follows = "shouldr"', "mechanism.coupling.elbow.follows",
     "did you mean 'shoulder'"),
    ('joint = "elbow"', 'joint = "elbw"', "mechanism.coupling[0].joint",
     "no joint named 'elbw'"),
    ('follows = "shoulder"', 'follows = "weld"', "mechanism.coupling.elbow.follows",
     "is a fixed joint"),
    ('ratio = -0.5', 'ratio = "0.5 m"', "mechanism.coupling.elbow.ratio", "expected dimensionless"),
    ('offset = "0 deg"', 'offset = "0 m"', "mechanism.coupling.elbow.offset", "not in units"),
    ('offset = "0 deg"', 'offset = "0 deg"\nbias = 1', "mechanism.coupling.elbow.bias",
     "unknown key"),
    # the elbow's limits need the shoulder in [−60°, 60°] + 200°: outside its ±90°
    ('offset = "0 deg"', 'offset = "100 deg"', "mechanism.coupling.elbow",
     "outside the range"),
    ('ratio = -0.5', 'ratio = 0', "mechanism.coupling.elbow.offset", None),
    ('ratio = -0.5\noffset = "0 deg"', 'ratio = 0\noffset = "40 deg"',
     "mechanism.coupling.elbow.offset", "outside its limits"),
]  # fmt: skip


@pytest.mark.parametrize("old,new,field,words", BAD, ids=[b[2] + str(i) for i, b in
                                                         enumerate(BAD)])  # fmt: skip
def test_bad_coupling_is_one_line(tmp_path, old, new, field, words):
    assert old in GOOD
    path = tmp_path / "m.toml"
    path.write_text(GOOD.replace(old, new, 1))
    if words is None:  # a good variant: ratio 0 at an offset inside the limits
        load_mechanism(path).compile()
        return
    with pytest.raises(HydroarmError) as err:
        load_mechanism(path)
    assert "\n" not in str(err.value)
    assert err.value.field == field, str(err.value)
    assert words in err.value.problem, str(err.value)


@pytest.mark.parametrize(
    "extra,field,words",
    [
        ('[[mechanism.coupling]]\njoint = "elbow"\nfollows = "slide"\nratio = "1 rad/m"',
         "mechanism.coupling.elbow.joint", "already follows 'shoulder'"),
        ('[[mechanism.coupling]]\njoint = "shoulder"\nfollows = "elbow"',
         "mechanism.coupling.elbow", "loop (elbow -> shoulder -> elbow)"),
        ('[[mechanism.coupling]]\njoint = "slide"\nfollows = "elbow"\nratio = 0.1',
         "mechanism.coupling.slide.ratio", "has no unit"),
        ('[[mechanism.coupling]]\njoint = "weld"\nfollows = "elbow"',
         "mechanism.coupling.weld.joint", "is a fixed joint"),
        ('[[mechanism.coupling]]\nfollows = "elbow"', "mechanism.coupling[1].joint",
         "is missing"),
    ],
)  # fmt: skip
def test_bad_couplings_together_are_one_line(tmp_path, extra, field, words):
    path = tmp_path / "m.toml"
    path.write_text(GOOD + extra + "\n")
    with pytest.raises(HydroarmError) as err:
        load_mechanism(path)
    assert err.value.field == field, str(err.value)
    assert words in err.value.problem, str(err.value)


def test_a_prismatic_joint_may_follow_a_revolute_one_with_units(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(GOOD + '[[mechanism.coupling]]\njoint = "slide"\nfollows = "elbow"\n'
                    'ratio = "2 cm/deg"\noffset = "1 cm"\n')  # fmt: skip
    c = load_mechanism(path).compile()
    i = c.joint_names.index("slide")
    assert c.master[i] == c.joint_names.index("shoulder")  # slide -> elbow -> shoulder
    assert c.ratio[i] == pytest.approx(0.02 / math.radians(1) * -0.5)
    assert c.offset[i] == pytest.approx(0.01)


def test_bad_coupled_circuits_are_one_line(tmp_path, capsys):
    """An [initial] angle for a coupled joint; two actuators on one coupled group; and the
    CLI's one line with exit status 2, before any work."""
    doc = _coupled_pendulum(_doc("double_pendulum.toml"))
    doc["initial"]["elbow"] = "5 deg"
    with pytest.raises(HydroarmError) as err:
        build(circuit_from_doc(doc, "bad", DATA))
    assert err.value.field == "initial.elbow" and "follows 'shoulder'" in err.value.problem
    doc = _coupled_pendulum(_doc("double_pendulum.toml"), -0.5, "0 deg")
    doc["mechanism"]["joint"][1].update(type="revolute", lower="-30 deg", upper="30 deg")
    doc["initial"]["shoulder"] = "70 deg"  # the elbow at −35°: past its stop
    with pytest.raises(HydroarmError) as err:
        build(circuit_from_doc(doc, "bad", DATA))
    assert err.value.field == "initial.shoulder", str(err.value)
    assert "narrowed by the joints coupled to it" in err.value.problem
    doc = _coupled_pendulum(_doc("double_pendulum.toml"))
    doc["component"] = [
        {"type": "inertia", "name": "rotor", "ports": {"body": "elbow"},
         "inertia": "1e-4 kg*m**2", "initial_angle": "5 deg"}
    ]  # fmt: skip
    with pytest.raises(HydroarmError) as err:
        build(circuit_from_doc(doc, "bad", DATA))
    assert err.value.field == "component.rotor.initial_angle", str(err.value)
    del doc["component"][0]["initial_angle"]  # a rotor on the coupled joint is allowed
    assert build(circuit_from_doc(doc, "rotor", DATA)).s0[1] == pytest.approx(0.0)
    doc = _folding_boom(_doc("boom.toml"), swap=False)
    doc["component"].append(
        {"type": "rotary_actuator", "name": "tip_motor", "ports": {"a": "A", "b": "B",
         "shaft": "fold"}, "displacement_a": "1e-5 m**3/rad",
         "displacement_b": "1e-5 m**3/rad", "travel": "3 rad", "angle_at_a_end": "-1.5 rad"}
    )  # fmt: skip
    with pytest.raises(HydroarmError) as err:
        build(circuit_from_doc(doc, "bad", DATA))
    assert err.value.field == "component.tip_motor", str(err.value)
    assert "'fold' follows 'lift'" in err.value.problem
    from hydroarm.cli import main

    text = (DATA / "double_pendulum.toml").read_text()
    text += '\n[[mechanism.coupling]]\njoint = "elbow"\nfollows = "elbow"\n'
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    try:
        rc = main(["arm", "--config", str(bad), "--out", str(tmp_path / "o")])
    except SystemExit as e:
        rc = e.code
    err_lines = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err_lines == [
        "hydroarm: error: mechanism.coupling.elbow.follows: a joint cannot follow itself"
    ], err_lines
    assert not (tmp_path / "o").exists()


def test_a_coupled_mechanism_fmu_is_hydroarm_simulate(tmp_path):
    """The FMU of a coupled mechanism file equals `hydroarm simulate` to the last bit, the
    coupled joint's angle included."""
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    from test_fmu import run_fmu

    import hydroarm as ha
    from hydroarm.io.circuit import load_circuit

    text = (DATA / "double_pendulum.toml").read_text().replace('elbow = "-40 deg"\n', "")
    text += '\n[[mechanism.coupling]]\njoint = "elbow"\nfollows = "shoulder"\nratio = -0.5\n'
    path = tmp_path / "coupled.toml"
    path.write_text(text)
    fmu = ha.export_fmu(path, tmp_path / "coupled.fmu")["path"]
    names = ["shoulder_angle_deg", "elbow_angle_deg", "elbow_torque_n_m"]
    kwargs = {"stop_time": 0.5, "output_interval": 1e-3, "output": names}
    runs, _ = run_fmu(tmp_path / "run", fmu, [{"name": "c", "kwargs": kwargs}])
    ref = simulate(load_circuit(path)).columns()
    for name in names:
        assert np.array_equal(runs["c"][name], ref[name][:501]), name
    assert np.ptp(ref["elbow_angle_deg"]) > 5.0  # it moved [deg]
