"""The whole arm (issue 5): kinematics, single-joint equivalence, shared pump, the UCL arm's
reported performance, the config file and the command."""

import math
from pathlib import Path

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm import ArmGeometry, ArmJoint, ArmScenario, PowerPack, arm_points, simulate_arm
from hydroarm.arm.config import load_arm, load_arm_text
from hydroarm.arm.expand import RELIEF_OVERRIDE
from hydroarm.cli import main
from hydroarm.core.arm_kinematics import mass_matrix, pose_load, pose_load_fd
from hydroarm.core.params import STANDARD_GRAVITY
from hydroarm.errors import HydroarmError
from hydroarm.io.catalog import paper_load
from hydroarm.paper import arm_validation as AV
from hydroarm.reference.arm_decoupled import simulate_decoupled

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ucl-arm.toml"
G = ArmGeometry()


# ---------------------------------------------------------------- kinematics ---
@pytest.mark.parametrize(
    "q, hand",
    [
        ((0, 0, 0, 0), (0.0, 0.0, -0.51)),  # hanging straight
        ((90, 0, 0, 0), (0.51, 0.0, 0.0)),  # raised forward to horizontal
        # elbow 90° over-extends the shoulder 45°: upper arm 45° forward of down, forearm 45° up
        (
            (90, 0, 90, 0),
            (
                0.25 * math.sqrt(0.5) + 0.26 * math.sqrt(0.5),
                0.0,
                -0.25 * math.sqrt(0.5) + 0.26 * math.sqrt(0.5),
            ),
        ),
        # and humeral rotation 90° swings the forearm across the body (−y)
        ((90, 90, 90, 0), (0.25 * math.sqrt(0.5), -0.26, -0.25 * math.sqrt(0.5))),
        ((90, 90, 90, 77), (0.25 * math.sqrt(0.5), -0.26, -0.25 * math.sqrt(0.5))),  # wrist: none
    ],
)
def test_forward_kinematics_hand_computed(q, hand):
    pts = arm_points(np.radians(np.array(q, float)), G.params())
    assert pts[2] == pytest.approx(hand, abs=1e-12)
    # segment lengths are kept in every pose
    assert np.linalg.norm(pts[0]) == pytest.approx(G.upper_arm_length, abs=1e-12)
    assert np.linalg.norm(pts[1] - pts[0]) == pytest.approx(G.forearm_length, abs=1e-12)


def test_gravity_torque_and_inertia_of_straight_arm():
    # straight arm: W·X·sin(α) about the shoulder, and Σ m·d² for the inertia
    Gv = G.params()
    alpha = math.radians(70)
    torque, inertia = pose_load(np.array([alpha, 0, 0, 0.0]), 0, Gv)
    wx = STANDARD_GRAVITY * (
        G.upper_arm_mass * G.upper_arm_com + G.forearm_mass * (G.upper_arm_length + G.forearm_com)
    )
    assert torque == pytest.approx(wx * math.sin(alpha), rel=1e-8)  # central differences
    md2 = (
        G.upper_arm_mass * G.upper_arm_com**2
        + G.forearm_mass * (G.upper_arm_length + G.forearm_com) ** 2
    )
    assert inertia == pytest.approx(md2, rel=1e-8)


def test_rotation_of_hanging_arm_has_no_gravity_load():
    assert pose_load(np.radians([0.0, 30.0, 0.0, 0.0]), 1, G.params())[0] == pytest.approx(
        0.0, abs=1e-9
    )


def _example_geometry():
    return load_arm(EXAMPLE).geometry.params()  # a hand payload: all three point masses


def test_closed_form_pose_load_equals_finite_differences():
    # central differences with d = 1e-6 rad: truncation d²/6·|U'''| ≈ 1e-12 N m, round-off
    # ε·|U|/d ≈ 2e-16·4 J/1e-6 ≈ 1e-9 N m (observed ≤ 1.1e-9); the inertia's round-off is
    # ε·|r|/d ≈ 1e-10 m per unit of |∂r/∂q| ≈ 0.5 m: ≈ 1e-10 kg m² (observed ≤ 6e-11)
    Gv = _example_geometry()
    rng = np.random.default_rng(21)
    for _ in range(200):
        q = rng.uniform(-math.pi, math.pi, 4)
        for j in range(4):
            t, i = pose_load(q, j, Gv)
            t_fd, i_fd = pose_load_fd(q, j, Gv)
            assert t == pytest.approx(t_fd, abs=1e-8)
            assert i == pytest.approx(i_fd, abs=1e-9)


def test_mass_matrix_equals_finite_differences():
    # M_ij = Σ m·(∂r/∂q_i · ∂r/∂q_j) from central differences of the points
    Gv = _example_geometry()
    masses = np.array([Gv.hand_mass, Gv.upper_arm_mass, Gv.forearm_mass])
    rng = np.random.default_rng(5)
    d = 1e-6
    for _ in range(20):
        q = rng.uniform(-math.pi, math.pi, 4)
        jac = np.empty((4, 3, 3))
        for j in range(4):
            qp, qm = q.copy(), q.copy()
            qp[j] += d
            qm[j] -= d
            jac[j] = ((arm_points(qp, Gv) - arm_points(qm, Gv)) / (2 * d))[[2, 3, 4]]
        m_fd = np.einsum("k,ikc,jkc->ij", masses, jac, jac)
        m = mass_matrix(q, Gv)
        assert np.allclose(m, m_fd, rtol=0, atol=1e-9)
        assert np.allclose(m, m.T)
        assert np.all(np.diag(m) == [pose_load(q, j, Gv)[1] for j in range(4)])
        assert np.all(np.linalg.eigvalsh(m[:3, :3]) > -1e-12)  # positive semidefinite


# -------------------------------------------------------- single-joint equivalence ---
def _shoulder_alone(joint, sc1, method="euler", fixed_load=None):
    """The shoulder elevation alone in the arm, its pose load that of the straight arm
    (the arm runs as its mechanism: a joint's load is its pose's), or on a test bench
    driving ``fixed_load``."""
    aj = ArmJoint("shoulder_elevation", joint, angle_offset=math.radians(60), fixed_load=fixed_load)
    return ArmScenario(
        joints=(aj,),
        inputs={"shoulder_elevation": sc1.lever},
        initial_angles={"shoulder_elevation": sc1.initial_angle + math.radians(60)},
        duration=sc1.duration,
        record_every=1,
        method=method,
        step=sc1.step,
        power_pack=PowerPack(supply_pressure=joint.supply_pressure),
    )


def _straight_arm_load():
    """The straight arm's pose load about the shoulder as a W, X, I load."""
    wx = G.upper_arm_mass * G.upper_arm_com + G.forearm_mass * (G.upper_arm_length + G.forearm_com)
    m = G.upper_arm_mass + G.forearm_mass
    inertia = (
        G.upper_arm_mass * G.upper_arm_com**2
        + G.forearm_mass * (G.upper_arm_length + G.forearm_com) ** 2
    )
    return ha.Load(weight=m * STANDARD_GRAVITY, arm=wx / m, inertia=inertia)


@pytest.mark.parametrize("set_name", ["paper-calibrated", "ucl-arm-measured"])
def test_shoulder_in_arm_pose_load_equals_single_joint(set_name):
    # the straight arm's pose load is a W, X, I load: the mechanism's tree gives its gravity
    # torque and inertia (round-off of the tree's sums), the servo jack and crank linkage
    # are the single joint's laws on an unlimited supply: equal to 1e-9
    j = ha.parameter_set(set_name)
    sc1 = ha.saturation_test(j, _straight_arm_load(), "raise")
    r1 = ha.simulate(sc1)
    ra = simulate_arm(_shoulder_alone(j, sc1))
    assert np.ptp(r1.theta) > 1.0  # it moves over the range
    assert np.max(np.abs(ra.theta[:, 0] - r1.theta)) / np.max(np.abs(r1.theta)) <= 1e-9
    assert np.max(np.abs(ra.p[:, 0] - r1.p)) / np.max(np.abs(r1.p)) <= 1e-9


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("set_name", ["paper-calibrated", "ucl-arm-measured"])
def test_shoulder_on_a_bench_equals_single_joint_and_decoupled_arm(set_name, method):
    """A joint with a fixed load (on a test bench) drives its own load, an inertia off the
    arm's tree (hydroarm/arm/expand.py): its servo jack, crank linkage and load are the
    single joint's circuit (hydroarm.io.joint_circuit) on the arm's supply, unlimited here,
    so it is the single-joint run and the decoupled arm's to round-off, as a pose-loaded
    joint alone is (test above, tests/test_ucl_mechanism.py: 1e-9 of the range). Measured
    3e-14 in the angle, 5e-13 in the pressure, for both sets and both methods."""
    j = ha.parameter_set(set_name)
    load = paper_load(5)
    sc1 = ha.saturation_test(j, load, "raise", method=method)
    r1 = ha.simulate(sc1)
    sc = _shoulder_alone(j, sc1, method, fixed_load=load)
    ra, rd = simulate_arm(sc), simulate_decoupled(sc)
    assert np.ptp(r1.theta) > 1.0  # it moves over the range
    assert ra.circuit.compiled.mechanism.joint_names == ()  # nothing of the arm moves
    for other in (r1, rd):
        theta = other.theta if other is r1 else other.theta[:, 0]
        p = other.p if other is r1 else other.p[:, 0]
        assert np.max(np.abs(ra.theta[:, 0] - theta)) <= 1e-9 * np.max(np.abs(theta))
        assert np.max(np.abs(ra.p[:, 0] - p)) <= 1e-9 * np.max(np.abs(p))


@pytest.mark.parametrize("direction", ["raise", "lower"])
def test_shoulder_in_arm_rk4_dry_friction_equals_single_joint(direction):
    # rk4 with the measured arm's dry friction (piston stiction and Coulomb, gearbox torque
    # and load-dependent loss): the arm's mechanism takes the smooth RK4 stages of the
    # system kernel and the same projection after the step (stick or slide) as the single
    # joint: equal to the round-off of the tree's sums, 1e-9 of the range
    j = ha.parameter_set("ucl-arm-measured")
    assert j.has_dry_friction
    sc1 = ha.saturation_test(j, _straight_arm_load(), direction, method="rk4", duration=0.8)
    r1 = ha.simulate(sc1)
    assert np.ptp(r1.theta) > 1.0  # it moves over the range
    assert r1.omega[0] == 0.0 and np.any(r1.omega[1:] != 0.0)  # breaks away from rest
    ra = simulate_arm(_shoulder_alone(j, sc1, "rk4"))
    scale = np.max(np.abs(r1.theta))
    np.testing.assert_allclose(ra.theta[:, 0], r1.theta, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(
        ra.omega[:, 0], r1.omega, rtol=0, atol=1e-9 * np.max(np.abs(r1.omega))
    )
    np.testing.assert_allclose(ra.p[:, 0], r1.p, rtol=0, atol=1e-9 * np.max(np.abs(r1.p)))


# --------------------------------------------------------------- shared pump ---
def _two_rotations(pump_flow):
    # no gravity load: p ≈ 0 in steady motion, so the leakage 2L·p draws no flow (the hand
    # on the wrist's axis: the mechanism's wrist turns its own inertia alone)
    base = ha.parameter_set("paper-calibrated")
    rot = ArmJoint("humeral_rotation", base, own_inertia=0.01)
    # the same servo on both, the same travel: they move together from start to end
    wr = ArmJoint("wrist_rotation", base, own_inertia=0.01)
    inputs = {
        "humeral_rotation": ha.step(rot.lever_for_angle(-0.8), rot.lever_for_angle(0.8)),
        "wrist_rotation": ha.step(wr.lever_for_angle(-0.8), wr.lever_for_angle(0.8)),
    }
    init = {"humeral_rotation": -0.8, "wrist_rotation": -0.8}
    return ArmScenario(
        joints=(rot, wr),
        inputs=inputs,
        initial_angles=init,
        duration=1.2,
        power_pack=PowerPack(31e5, pump_flow),
        geometry=ArmGeometry(hand_mass=0.1),
    )


def _alone(sc, name):
    j = sc.joint(name)
    return sc.replace(
        joints=(j,), inputs={name: sc.inputs[name]}, initial_angles={name: sc.initial_angles[name]}
    )


def _velocity(res, name):
    return abs(res.joint_metrics(name)["saturation_velocity_rad_s"])


def test_limited_pump_flow_balance():
    base = ha.parameter_set("paper-calibrated")
    demand = base.flow_gain * base.valve_saturation  # each valve wide open at p_s
    q_p = 1.3 * demand  # each alone fits, both together do not
    sc = _two_rotations(q_p)
    both = simulate_arm(sc)
    for name in ("humeral_rotation", "wrist_rotation"):
        alone = simulate_arm(_alone(sc, name))
        # alone: never pump-limited, the relief valve passing the rest of the pump's flow
        # within its override (RELIEF_OVERRIDE below the supply pressure it opens fully at)
        assert np.all(alone.supply_pressure >= 31e5 - RELIEF_OVERRIDE)
        p_alone = np.min(alone.supply_pressure)  # in the saturated motion (the most drawn)
        # flow balance: K·√(p*/2)·e_o per valve, 2 valves share Q_p ⇒ √(p*/p_s) = Q_p/(2·demand)
        # with p_s = 31 bar; alone each runs at √p_alone
        predicted = q_p / (2 * demand) * math.sqrt(31e5 / p_alone)
        ratio = _velocity(both, name) / _velocity(alone, name)
        assert ratio == pytest.approx(predicted, rel=0.01)  # transients: 1 %
        assert ratio < 1


def test_unlimited_pump_matches_fixed_supply():
    sc = _two_rotations(math.inf)
    both = simulate_arm(sc)
    for i, name in enumerate(("humeral_rotation", "wrist_rotation")):
        alone = simulate_arm(_alone(sc, name))
        # the two axes are one line in the hanging straight arm, every point mass on it: the
        # coupled mass matrix has no off-diagonal term, so the joints do not see each other
        # (round-off of the tree's sums)
        scale = np.max(np.abs(alone.theta[:, 0]))
        np.testing.assert_allclose(both.theta[:, i], alone.theta[:, 0], rtol=0, atol=1e-12 * scale)


# ------------------------------------------------------------- the UCL arm ---
@pytest.fixture(scope="module")
def ucl():
    return load_arm(EXAMPLE)


@pytest.mark.parametrize("direction", [1, -1])
def test_shoulder_rotation_100_deg_in_0_6_s(ucl, direction):
    # the paper: 100° in 0.6 s both ways (±10 %, issue 5)
    assert AV.rotation_time(ucl, direction) == pytest.approx(0.6, rel=0.10)


def test_elbow_reach_velocities(ucl):
    # the paper: 2.4 rad/s raising, 2.8 rad/s lowering (±10 %, issue 5)
    assert AV.reach_velocity(ucl, "raise") == pytest.approx(2.4, rel=0.10)
    assert AV.reach_velocity(ucl, "lower") == pytest.approx(2.8, rel=0.10)


@pytest.mark.slow
def test_elbow_stall_mass(ucl):
    # the paper: 0.9 kg at the end of the arm stalls the elbow (±10 %, issue 5)
    assert AV.elbow_stall_mass(ucl, tol=0.01) == pytest.approx(0.9, rel=0.10)


# ---------------------------------------------------------- config and command ---
SMALL = """
name = "two joints"
[power_pack]
pump_flow = "0.4 l/min"
[joints.shoulder_elevation]
angle_offset = "60 deg"
[joints.elbow_reach]
piston_area = "141.9 mm**2"
crank_radius = "10 mm"
gear_ratio = 1.2222
angle_offset = "55 deg"
[initial]
shoulder_elevation = "0 deg"
elbow_reach = "0 deg"
[inputs.shoulder_elevation]
type = "step"
to = "40 deg"
[inputs.elbow_reach]
type = "ramp"
to = "90 deg"
start = "0.1 s"
end = "0.6 s"
[solver]
duration = "0.8 s"
record_every = 1000
"""


def test_config_parsed():
    sc = load_arm_text(SMALL)
    assert [j.name for j in sc.joints] == ["shoulder_elevation", "elbow_reach"]
    assert sc.power_pack.pump_flow == pytest.approx(0.4e-3 / 60)
    assert sc.joint("elbow_reach").servo.valve_model == "orifice"  # ucl-arm-measured default
    r = simulate_arm(sc)
    assert r.angle("shoulder_elevation")[-1] == pytest.approx(math.radians(40), abs=0.02)


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("[joints.elbow_reach]", "[joints.elbow]", "joints.elbow"),
        ('to = "40 deg"', 'to = "40 mm"', "inputs.shoulder_elevation.to"),
        ('to = "40 deg"', 'to = "300 deg"', "inputs.shoulder_elevation"),
        ('pump_flow = "0.4 l/min"', 'pump_flow = "-1 l/min"', "power_pack.pump_flow"),
        ("record_every = 1000", "record_every = 0", "solver.record_every"),
        ('type = "ramp"', 'type = "spline"', "inputs.elbow_reach.type"),
    ],
)
def test_config_errors(old, new, field):
    with pytest.raises(HydroarmError, match=field.replace(".", r"\.")):
        load_arm_text(SMALL.replace(old, new))


def test_csv_input(tmp_path):
    (tmp_path / "lev.csv").write_text(
        "t_s,shoulder_elevation_deg,elbow_reach_deg\n0,0,0\n0.2,30,60\n"
    )
    text = (
        SMALL.split("[inputs.shoulder_elevation]")[0]
        + '[inputs]\ncsv = "lev.csv"\n'
        + '[solver]\nduration = "0.6 s"\nrecord_every = 1000\n'
    )
    sc = load_arm_text(text, tmp_path)
    assert sc.inputs["elbow_reach"].description == "csv:lev.csv"
    (tmp_path / "lev.csv").write_text("t_s,shoulder_elevation_deg,knee_deg\n0,0,0\n")
    with pytest.raises(HydroarmError, match="knee_deg"):
        load_arm_text(text, tmp_path)


@pytest.mark.slow
def test_arm_command(tmp_path, capsys):
    cfg = tmp_path / "arm.toml"
    cfg.write_text(SMALL)
    out = tmp_path / "run"
    assert main(["arm", "--config", str(cfg), "--out", str(out)]) == 0
    for f in (
        "joints.csv",
        "hand_trajectory.csv",
        "joints.png",
        "frames.png",
        "arm.gif",
        "power.csv",
        "energy.png",
        "arm_validation.csv",
    ):
        assert (out / f).stat().st_size > 0, f
    printed = capsys.readouterr().out
    assert "hydraulic energy (pump)" in printed
    assert "electric energy                  not reported" in printed  # no efficiencies
    assert (out / "arm.gif").read_bytes()[:3] == b"GIF"
    head = (out / "arm_validation.csv").read_text().splitlines()[0]
    assert head == "quantity,measured,model,rel_error"
    joints = (out / "joints.csv").read_text().splitlines()
    assert joints[0].startswith("t_s,supply_pressure_bar,shoulder_elevation_deg")
    assert not list(tmp_path.glob(".hydroarm-arm-*"))


def test_arm_command_bad_config_one_line(tmp_path, capsys):
    cfg = tmp_path / "arm.toml"
    cfg.write_text(SMALL.replace("[joints.elbow_reach]", "[joints.knee]"))
    assert main(["arm", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "joints.knee" in err[0]
    assert not (tmp_path / "o").exists()


# ------------------------------------------------- power pack energy (issue 14) ---
BATTERY = """pump_efficiency = 0.6
motor_efficiency = 0.7
battery_capacity = "1.2 A*h"
battery_voltage = "12 V"
usable_fraction = 0.8
"""
SMALL_BATTERY = SMALL.replace('pump_flow = "0.4 l/min"\n', 'pump_flow = "0.4 l/min"\n' + BATTERY)


@pytest.fixture(scope="module")
def small_energy():
    """SMALL recorded at every step: the pump limits the two joints for a while (the supply
    sags), the relief valve passes the rest; the measured set's leakage, leakage at null and
    orifice valves; gravity loads."""
    res = simulate_arm(load_arm_text(SMALL_BATTERY).replace(record_every=1))
    return res, res.energy()


def test_energy_balance_closes(small_energy):
    res, e = small_energy
    assert res.supply_pressure.min() < 0.5 * 31e5  # pump-limited for a while
    assert e["relief_loss_j"] > 0.3 * e["pump_hydraulic_j"]  # and relieving for a while
    # pump = relief + supply compression + valves: the circuit's energy account, every
    # component's absorbed power integrated by the run's own method (Σ P = 0 at every
    # evaluation): round-off but for a chamber held at a cavitation floor
    assert abs(e["supply_residual_j"]) <= 1e-9 * e["pump_hydraulic_j"]
    # the pump's account against its recorded supply pressure: ∫p_s·Q_p by the trapezoid
    # over the Euler steps, O(h) apart (h = 10 µs against ~25 ms transients)
    pump = np.trapezoid(res.supply_pressure * 0.4e-3 / 60, res.t)
    assert e["pump_hydraulic_j"] == pytest.approx(pump, rel=1e-3)
    # the joints lose part of what they draw (metering, leakage, oil) and hand the rest on
    assert 0 < e["joint_losses_j"] < e["valves_j"]
    # the jacks lift the arm (potential gained) and lose the rest to friction and gearbox
    assert 0 < e["potential_j"] < e["jack_work_j"]
    assert e["mechanical_losses_j"] > 0


def test_cycles_per_charge_is_the_formula(small_energy):
    res, e = small_energy
    usable = 1.2 * 3600 * 12 * 0.8  # A·h → C, × V, × usable fraction [J]
    electric = e["pump_hydraulic_j"] / (0.6 * 0.7)
    assert e["battery_usable_energy_j"] == pytest.approx(usable, rel=1e-12)
    assert e["electric_energy_j"] == pytest.approx(electric, rel=1e-12)
    assert e["energy_per_cycle_j"] == pytest.approx(electric, rel=1e-12)  # the run is one cycle
    assert e["cycles_per_charge"] == pytest.approx(usable / electric, rel=1e-12)
    assert e["run_time_per_charge_s"] == pytest.approx(usable / (electric / 0.8), rel=1e-12)
    two = res.energy(cycles=2)
    assert two["energy_per_cycle_j"] == pytest.approx(electric / 2, rel=1e-12)
    assert two["cycles_per_charge"] == pytest.approx(2 * usable / electric, rel=1e-12)


def test_power_traces_integrate_to_the_summary(small_energy):
    res, e = small_energy
    tr = res.power_traces()
    # the traces' trapezoid over the records against the account integrated by the
    # method (Euler at 10 µs, every step recorded): O(h)
    summary = {
        "pump": "pump_hydraulic_j",
        "electric": "electric_energy_j",
        "valves": "valves_j",
        "relief": "relief_loss_j",
        "jacks": "jack_work_j",
    }
    for k, key in summary.items():
        assert tr[f"cumulative_{k}_j"][-1] == pytest.approx(e[key], rel=1e-4), k
    # the pump gives Q_p at p_s throughout: p_s·Q_p, 31 bar × 0.4 l/min = 20.7 W at relief
    assert tr["pump_w"][0] == pytest.approx(31e5 * 0.4e-3 / 60, rel=1e-12)


def test_battery_as_energy_or_charge():
    a = load_arm_text(SMALL_BATTERY).power_pack
    b = load_arm_text(
        SMALL_BATTERY.replace('"1.2 A*h"', '"14.4 W*h"').replace('battery_voltage = "12 V"\n', "")
    ).power_pack
    c = load_arm_text(SMALL_BATTERY.replace('"1.2 A*h"', '"1200 mA*h"')).power_pack
    assert a.battery_charge == pytest.approx(4320.0) and a.battery_voltage == 12.0
    assert b.battery_energy == pytest.approx(14.4 * 3600) and b.battery_voltage is None
    assert a.usable_battery_energy == pytest.approx(b.usable_battery_energy, rel=1e-12)
    assert c.usable_battery_energy == pytest.approx(a.usable_battery_energy, rel=1e-12)
    assert load_arm_text(SMALL).power_pack.electric is False  # no efficiencies: hydraulic only


def test_unlimited_pump_delivers_what_the_valves_draw():
    res = simulate_arm(load_arm_text(SMALL.replace('"0.4 l/min"', '"unlimited"')))
    e = res.energy()
    assert e["relief_loss_j"] == 0.0
    assert e["pump_hydraulic_j"] == pytest.approx(e["valves_j"], rel=1e-9)
    assert "electric_energy_j" not in e


@pytest.mark.slow
def test_block_stacking_battery_reported(tmp_path, capsys):
    # issue 14: `hydroarm arm` reports the energy per block-stacking cycle and the cycles per
    # charge (the example's estimated pump, motor and battery; docs/arm.md)
    out = tmp_path / "run"
    assert main(["arm", "--config", str(EXAMPLE), "--out", str(out), "--no-animation"]) == 0
    text = capsys.readouterr().out
    lines = {ln.split("  ")[0]: ln for ln in text.splitlines()}
    assert "energy per cycle" in lines and "battery: cycles per charge" in lines
    assert "battery: run time per charge" in lines and "electric energy" in lines
    rows = {r.split(",")[0]: r.split(",") for r in (out / "power.csv").read_text().splitlines()}
    assert rows["quantity"] == ["quantity", "value", "unit", "description"]
    per_cycle = float(rows["energy_per_cycle"][1])
    cycles = float(rows["cycles_per_charge"][1])
    usable = float(rows["battery_usable_energy"][1]) * 3600  # W*h → J
    assert usable == pytest.approx(1.2 * 3600 * 12 * 0.8)
    assert cycles == pytest.approx(usable / per_cycle, rel=1e-5)  # 6 printed digits
    assert float(lines["energy per cycle"].split()[3]) == pytest.approx(per_cycle, rel=1e-3)
    assert float(lines["battery: cycles per charge"].split()[4]) == pytest.approx(cycles, rel=1e-3)
    # the pump runs throughout at (mostly) its relief pressure: 31 bar × 0.6 l/min × 9 s
    pump = float(rows["pump_hydraulic"][1])
    assert 0.95 * 31e5 * 1e-5 * 9 < pump <= 31e5 * 1e-5 * 9
    assert (out / "energy.png").stat().st_size > 0
    # issue 17: the arm's card; the reach's speeds and stall are the validation's numbers,
    # the block score the arithmetic of hydroarm.arm.blocks on the card's speeds
    import csv

    from hydroarm.arm.blocks import DEFAULT_TASK, block_score

    card = list(csv.DictReader(open(out / "arm_card.csv")))
    val = {r["quantity"]: r["model"] for r in csv.DictReader(open(out / "arm_validation.csv"))}
    got = {(r["joint"], r["quantity"], r["unit"]): r["value"] for r in card}
    assert got[("elbow_reach", "speed increasing", "rad/s")] == val["elbow_reach_raise_rad_s"]
    assert got[("elbow_reach", "speed decreasing", "rad/s")] == val["elbow_reach_lower_rad_s"]
    assert got[("elbow_reach", "stall mass at the hand", "kg")] == val["elbow_stall_mass_kg"]
    speeds = {
        j: (
            float(got[(j, "speed increasing", "rad/s")]),
            float(got[(j, "speed decreasing", "rad/s")]),
        )
        for j in DEFAULT_TASK.pick
    }
    bpm = float(got[("arm", "block transfer score", "blocks/min")])
    # the CSV's 6 significant digits of the speeds and of the score
    assert bpm == pytest.approx(block_score(DEFAULT_TASK, speeds)["blocks_per_minute"], rel=2e-5)
    assert "block transfer score" in text and (out / "arm_card.png").stat().st_size > 0


# ------------------------------------------------- joints built from components ---
def _component_arm(component, load, method, step, servo=None, duration=0.4):
    from hydroarm.arm.config import component_values

    servo = servo or ha.parameter_set("ucl-arm-measured").replace(gearbox_loss_at_stall=0.3)
    comp = component_values("joints.elbow_reach", servo, component, None)
    servo = servo.replace(piston_area=comp["area_a"])
    j = ArmJoint("elbow_reach", servo, fixed_load=load, component=comp)
    y0, y1 = j.lever_for_angle(0.0), j.lever_for_angle(0.6)
    return ArmScenario(
        joints=(j,),
        inputs={"elbow_reach": ha.step(y0, y1, 0.05)},
        initial_angles={"elbow_reach": 0.0},
        duration=duration,
        step=step,
        method=method,
        record_every=10,
    )


@pytest.mark.parametrize("method, step", [("euler", 1e-5), ("rk4", 1e-4)])
def test_component_joint_on_a_bench_is_the_decoupled_arms(method, step):
    """The single-rod elbow on a test bench with a constant load: the valve, cylinder,
    crank with its dry friction and lever feedback of a component joint driving an inertia
    off the tree, against the decoupled arm (the servo kernel's step on the same W·X and
    inertia): to round-off in the angle, 1e-9 of its range, as a component joint alone in
    the arm (tests/test_ucl_mechanism.py); the chamber pressures, through the oil's
    stiffness, to 1e-8 of their largest. Measured: angle 1.5e-12 (euler) and 9.9e-11 (rk4),
    pressure 3.9e-11 and 2.7e-9."""
    load = ha.Load(weight=5.0, arm=0.2, inertia=0.02)
    act = {"type": "single_rod", "piston_diameter": "13.443 mm", "rod_diameter": "10 mm"}
    sc = _component_arm(act, load, method, step)
    ra, rd = simulate_arm(sc), simulate_decoupled(sc)
    span = np.ptp(rd.theta)
    assert span > 0.5  # it moves (0.6 rad commanded)
    assert np.max(np.abs(ra.theta - rd.theta)) <= 1e-9 * span
    assert np.max(np.abs(ra.p - rd.p)) <= 1e-8 * np.max(np.abs(rd.p))


@pytest.mark.parametrize("method, step", [("euler", 1e-5), ("rk4", 1e-4)])
def test_symmetric_component_joint_tracks_lumped_joint_in_arm(method, step):
    """A symmetric two-chamber jack with the linearised valve, chambers of 2V at mid-stroke
    and internal leakage C_i = 2L is the lumped joint (test_components.py): in the arm, with
    the reach's pose loads, the two runs differ in ε² only, ε = A·x/(2V) the stroke's share
    of the chamber. V is 1000× the paper's (ε ≤ 3.9e-4, ε² ≤ 1.5e-7), the cavitation floor
    is off (the lumped linear valve has none): tolerance 1e-6 of the angle, velocity and
    pressure scales (≈ 7·ε²; measured 1.2e-7 for both methods)."""
    base = ha.parameter_set("paper-calibrated")
    V = 1000 * base.trapped_volume
    joint = base.replace(trapped_volume=V, crank_radius=0.01, gear_ratio=1.2222)
    A = joint.piston_area
    r = joint.crank_radius
    comp = {
        "area_a": A,
        "area_b": A,
        "stroke_min": -r,
        "stroke_max": r,
        "dead_volume_a": 2 * V - A * r,
        "dead_volume_b": 2 * V - A * r,
        "bulk_modulus": joint.bulk_modulus,
        "internal_leakage": 2 * joint.leakage_coefficient,
        "valve_kind": 1.0,  # VALVE_LINEARISED
        "flow_gain": joint.flow_gain,
        "cavitation_pressure": -1e12,
    }
    runs = []
    for c in (None, comp):
        j = ArmJoint("elbow_reach", joint, angle_offset=math.radians(55), component=c)
        lever = ha.step(j.lever_for_angle(0.0), j.lever_for_angle(math.radians(60)), 0.02)
        sc = ArmScenario(
            joints=(j,),
            inputs={"elbow_reach": lever},
            initial_angles={"elbow_reach": 0.0},
            duration=0.6,
            step=step,
            method=method,
            record_every=10,
        )
        runs.append(simulate_arm(sc))
    lumped, compo = runs
    assert np.ptp(lumped.theta) > 0.5  # it moves
    eps = np.max(np.abs(A * r * np.sin(lumped.theta / 1.2222) / (2 * V)))
    assert eps < 4e-4
    for a, b in ((lumped.theta, compo.theta), (lumped.omega, compo.omega), (lumped.p, compo.p)):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-6 * np.max(np.abs(a)))


def test_elbow_is_a_single_rod_jack_whose_bore_lifts(ucl):
    j = ucl.joint("elbow_reach")
    assert j.component is not None
    a_a, a_b = j.component["area_a"], j.component["area_b"]
    assert a_b < a_a  # single rod, the full bore (chamber A) lifts
    assert a_a * 31e5 == pytest.approx(440, rel=0.01)  # 0.44 kN available at 31 bar
    # a plausible gearbox: the paper's "loss of nearly 30 %" at stall, not the lumped 96 %
    assert 0.2 <= j.servo.gearbox_loss_at_stall <= 0.4


def test_elbow_force_needed_at_stall(ucl):
    # the paper: 0.32 kN needed at the actuator in the stall configuration (±10 %)
    assert AV.force_needed_at_stall(ucl) == pytest.approx(320.0, rel=0.10)


def test_component_arm_energy_balance(ucl):
    # the reach built from components in the energy account: it closes as the lumped does
    sc = AV._single(ucl, "elbow_reach", 0.0, math.radians(100), duration=0.8)
    sc = sc.replace(method="rk4", step=1e-4)
    e = simulate_arm(sc).energy()
    assert e["jack_work_j"] > 0.1
    assert 0 < e["joint_losses_j"] < e["valves_j"]
    # the account closes but for the chambers held at the cavitation floor (the lowering
    # jack's annulus): at most 1 % of what the joint drew
    assert abs(e["supply_residual_j"]) <= 0.01 * e["valves_j"]
