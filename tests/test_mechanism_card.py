"""The evaluation card of any mechanism file (``hydroarm arm --config FILE --card``;
hydroarm/analysis/mechanism_card.py, docs/evaluate.md "Any mechanism file"): the excavator's
and the leg's cards, their numbers checked against the physics by hand (the pump's flow
over the piston area and the linkage's moment arm; the blocked actuator's force against the
supply's no-flow pressure times the areas; the stall payload's torque balance against the
gravity torque taken from the potential energy), and the refusals."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.analysis import mechanism_card as mc
from hydroarm.cli import main
from hydroarm.core import tree as T
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import load_circuit

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
BAR = 1e5
P_TANK = 1.0 * BAR  # both examples' tank


def _card_csv(path: Path) -> dict[tuple[str, str, str], float]:
    with open(path) as fh:
        return {
            (r["joint"], r["direction"], r["quantity"]): float(r["value"])
            for r in csv.DictReader(fh)
        }


@pytest.fixture(scope="module")
def excavator(tmp_path_factory):
    out = tmp_path_factory.mktemp("excavator-card")
    argv = ["arm", "--config", str(EXAMPLES / "excavator.toml"), "--card", "--no-animation"]
    assert main(argv + ["--out", str(out)]) == 0
    for name in ("card.csv", "card.md", "card.png", "joints.csv"):
        assert (out / name).stat().st_size > 0
    return _card_csv(out / "card.csv"), (out / "card.md").read_text()


@pytest.fixture(scope="module")
def leg():
    return mc.mechanism_card(load_circuit(EXAMPLES / "hydraulic_leg.toml"))


def _pivot(a: float, b: float, phi_deg: float):
    """A pivot linkage's pin-to-pin length and moment arm dL/dq by the law of cosines."""
    phi = math.radians(phi_deg)

    def length(q):
        return math.sqrt(a * a + b * b - 2 * a * b * math.cos(q + phi))

    def arm(q):
        return a * b * math.sin(q + phi) / length(q)

    return length, arm


def _gravity_by_energy(path: Path, joint: str, q: float, point_link: str, point):
    """(the joint's gravity torque at rest, its rise per kg at the point) at the file's
    [initial] pose with the joint at q, from the potential energy (tree.potential_energy)
    and the point's height (tree.forward_kinematics) by central differences: not the bias
    forces (RNEA) the card uses."""
    circuit = load_circuit(path)
    mech = circuit.mechanism.compile()
    n = mech.n
    j = mech.joint_names.index(joint)
    link = mech.link_names.index(point_link)
    q0 = np.array([circuit.initial_joints.get(name, 0.0) for name in mech.joint_names])
    q0[j] = q
    work = T.make_tree_work(n)
    R, p = np.zeros((n, 3, 3)), np.zeros((n, 3))
    gvec = np.asarray(mech.tree.gravity, float)

    def energy(x):
        qq = q0.copy()
        qq[j] = x
        V = T.potential_energy(mech.tree, qq, work, R, p)
        r = p[link] + R[link] @ np.asarray(point, float)
        return V, -float(gvec @ r)  # the mechanism's V; a kilogram's at the point

    h = 1e-6  # central differences: error O(h²) ≈ 1e-12 of the torque
    (v1, w1), (v2, w2) = energy(q + h), energy(q - h)
    return (v1 - v2) / (2 * h), (w1 - w2) / (2 * h)


# ---------------------------------------------------------------------- the excavator ---
@pytest.mark.slow
def test_excavator_boom_raising_speed_is_the_pump_flow_over_the_area_and_arm(excavator):
    card, _ = excavator
    # raising the boom with its valve fully open draws the whole pump: the supply sags far
    # below the compensator's 290 bar (the sag row), so the pump is on full stroke and its
    # 279 cm³/rev at 1900 rpm fills the cap side: v = Q/A_a. Over the middle 80 % of the
    # travel the joint sweeps 0.8·Δq while the rod moves L(q90) − L(q10) (law of cosines
    # with the file's pivots): speed = v·0.8·Δq/ΔL.
    q_pump = 279e-6 * 1900 / 60
    length, _ = _pivot(1.2, 2.8, 95.0)
    lo, hi = math.radians(-45.0), math.radians(50.0)
    d_rod = length(lo + 0.9 * (hi - lo)) - length(lo + 0.1 * (hi - lo))
    expected = q_pump / 306.6e-4 * 0.8 * (hi - lo) / d_rod
    assert card[("boom", "", "stall payload")] > 1980.0
    assert card[("boom", "increasing", "supply sag")] > 150.0
    # 2 %: the chambers' and the 5 L supply line's compression while the pressures fall,
    # and the first 10 % of travel not quite covering the acceleration (measured −1.1 %)
    assert card[("boom", "increasing", "speed")] == pytest.approx(expected, rel=0.02)


@pytest.mark.slow
def test_excavator_blocked_boom_force_is_the_deadhead_pressure_times_the_areas(excavator):
    card, _ = excavator
    # at its upper stop with the valve fully open, the cap side sits at the pump's deadhead
    # p_c + Δp_r (290 + 12.5 bar: the compensator's band; the pump has no leakage) and the
    # rod side at the tank's 1 bar
    expected = (290e5 + 12.5e5) * 306.6e-4 - P_TANK * 144.4e-4
    # 0.1 %: the tail's mean over the oil column's ring at the stop (measured 4e-5)
    assert card[("boom", "increasing", "blocked force")] == pytest.approx(expected, rel=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize(
    "joint, pivot, point_link, point",
    [
        ("boom", (1.2, 2.8, 95.0), "bucket", (0.7, 0.0, 0.0)),
        ("stick", (2.6, 0.7, 15.0), "bucket", (0.7, 0.0, 0.0)),
        ("bucket", (1.9, 0.5, 0.0), "bucket", (0.7, 0.0, 0.0)),
    ],
)
def test_excavator_stall_payload_balances_gravity_at_the_worst_pose(
    excavator, joint, pivot, point_link, point
):
    card, _ = excavator
    # the file's soil payload (1980 kg at 0.7 m along the bucket) is the payload point
    m_stall = card[(joint, "", "stall payload")]
    q = math.radians(card[(joint, "", "stall worst pose")])
    _, arm = _pivot(*pivot)
    held = [card[(joint, d, "blocked force")] * arm(q) for d in ("increasing", "decreasing")]
    g0, per_kg = _gravity_by_energy(EXAMPLES / "excavator.toml", joint, q, point_link, point)
    bound = max(held) if per_kg > 0 else min(held)
    # at stall the blocked actuator's torque holds the mechanism and the extra soil:
    # bound = g0 + (m − 1980 kg)·per_kg; 2e-5: card.csv's 6 significant digits of the
    # force, the pose and the mass (5e-6 each; the central differences add 1e-12)
    assert bound == pytest.approx(g0 + (m_stall - 1980.0) * per_kg, rel=2e-5)


@pytest.mark.slow
def test_excavator_card_has_every_joint_and_the_task(excavator):
    card, md = excavator
    for joint in ("boom", "stick", "bucket"):
        for d in ("increasing", "decreasing"):
            assert card[(joint, d, "speed")] > 0.0
            assert 0.0 < card[(joint, d, "time constant (63 %)")] < 1000.0
            assert card[(joint, d, "peak pressure a")] <= 400.0
            assert card[(joint, d, "energy")] > 0.0
        assert ("task", joint, "tracking error (RMS)") in card
    assert card[("task", "", "cycle time")] == pytest.approx(19.0)
    # the task's energy is the pump's (docs/mechanism.md: 1.76 MJ over the cycle)
    assert card[("task", "", "energy")] == pytest.approx(1.76e6, rel=0.01)
    assert "| boom | increasing | speed |" in md


# ---------------------------------------------------------------------------- the leg ---
@pytest.mark.slow
def test_leg_blocked_force_is_the_relief_pressure_times_the_areas(leg):
    # at each stop with its valve fully open a cylinder's pushing chamber sits at the
    # supply (the relief's 160 bar, absolute) and the other at the tank's 1 bar
    push = 160e5 * 2.011e-4 - P_TANK * 1.225e-4
    pull = -(160e5 * 1.225e-4 - P_TANK * 2.011e-4)
    for joint in ("hip", "knee"):
        forces = sorted(leg.value(joint, "blocked force", d) for d in ("increasing", "decreasing"))
        # 0.5 %: the relief's override at the pump's 10 L/min (0.1 bar) and the servo
        # valves' underlap, which feeds the tank side a little from the supply
        assert forces[1] == pytest.approx(push, rel=5e-3)
        assert forces[0] == pytest.approx(pull, rel=5e-3)


@pytest.mark.slow
@pytest.mark.parametrize(
    "joint, pivot", [("hip", (0.20, 0.045, 80.0)), ("knee", (0.25, 0.045, -10.0))]
)
def test_leg_stall_payload_balances_gravity_at_the_worst_pose(leg, joint, pivot):
    # no payload in the file: the point is the lower leg's centre of mass (the last link
    # both joints move)
    m_stall = leg.value(joint, "stall payload")
    q = math.radians(leg.value(joint, "stall worst pose"))
    _, arm = _pivot(*pivot)
    held = [leg.value(joint, "blocked force", d) * arm(q) for d in ("increasing", "decreasing")]
    com = (0.1254, 0.0001, 0.00004)
    g0, per_kg = _gravity_by_energy(EXAMPLES / "hydraulic_leg.toml", joint, q, "lower_leg", com)
    bound = max(held) if per_kg > 0 else min(held)
    assert m_stall > 0.0
    # 1e-6: the central differences and round-off
    assert bound == pytest.approx(g0 + m_stall * per_kg, rel=1e-6)


@pytest.mark.slow
def test_leg_card_files_and_rows(leg, tmp_path):
    names = leg.write(tmp_path)
    assert names == ["card.csv", "card.md", "card.png"]
    rows = _card_csv(tmp_path / "card.csv")
    for joint in ("hip", "knee"):
        up, down = rows[(joint, "increasing", "speed")], rows[(joint, "decreasing", "speed")]
        assert up > 0.0 and down > 0.0
        # 1e-5: card.csv's 6 significant digits, each number rounded on its own
        deg = rows[(joint, "increasing", "speed [deg/s]")]
        assert deg == pytest.approx(math.degrees(up), rel=1e-5)
    joints, skipped = mc.check_card(load_circuit(EXAMPLES / "hydraulic_leg.toml"))
    assert [j.name for j in joints] == ["hip", "knee"] and skipped == []
    assert leg.runs <= mc.runs_needed(joints)


# ---------------------------------------------------------------------- the UCL arm ---
@pytest.fixture(scope="module")
def ucl(tmp_path_factory):
    out = tmp_path_factory.mktemp("ucl-card")
    argv = ["arm", "--config", str(EXAMPLES / "ucl-arm-mechanism.toml"), "--card"]
    assert main(argv + ["--no-animation", "--out", str(out)]) == 0
    return _card_csv(out / "card.csv"), (out / "card.md").read_text()


@pytest.mark.slow
def test_ucl_arm_mechanism_card_is_complete(ucl):
    card, md = ucl
    assert "Not on this card" not in md
    for joint in ("shoulder_elevation", "humeral_rotation", "elbow_reach", "wrist_rotation"):
        for d in ("increasing", "decreasing"):
            assert card[(joint, d, "speed")] > 0.0
            assert card[(joint, d, "energy")] > 0.0
            assert (joint, d, "blocked force") in card
    for joint in ("shoulder_elevation", "humeral_rotation", "wrist_rotation"):
        for d in ("increasing", "decreasing"):
            # the paper: the transients' time constant "not measured at more than 40 ms,
            # even for the heaviest loads"
            assert 0.0 < card[(joint, d, "time constant, start (63 % of e_o)")] < 40.0
            assert card[(joint, d, "jack speed")] > 0.0
    # the humeral rotation: 100° in 0.6 s each way (2.91 rad/s), within the arm
    # validation's ±10 %; the card's travel is ±60° about the crank's centre
    for d in ("increasing", "decreasing"):
        assert card[("humeral_rotation", d, "speed")] == pytest.approx(2.909, rel=0.1)


@pytest.mark.slow
def test_ucl_arm_blocked_jack_force_is_the_supply_pressure_times_the_area(ucl):
    card, _ = ucl
    # the jack's A·p with p where the valve's flow K·e_o·√((p_s − p)/2) meets the jack's
    # leakage 2·L·p, p_s = 31 bar (the relief's no-flow pressure less the tank): p a
    # little under p_s (0.09 bar for the big jacks, 0.46 bar for the wrist's smaller
    # valve); 0.6 %: at rest the supply sits 0.07 to 0.13 bar (0.23 to 0.43 %) under its
    # no-flow pressure, the held joints' leakage (0.7 to 1.3 cm³/s) taken from the relief's
    # flow along its slope (1e-10 m³/s/Pa)
    p_s, leak, e_o = 31e5, 8.022e-14, 7.5e-4
    for joint, area, k in (
        ("shoulder_elevation", 3.03e-4, 9.943513487062e-06),
        ("humeral_rotation", 3.03e-4, 9.943513487062e-06),
        ("wrist_rotation", 1.419e-4, 4.382070349803556e-06),
    ):
        p = p_s
        for _ in range(60):
            p = p_s - 2.0 * (2.0 * leak * p / (k * e_o)) ** 2
        up = card[(joint, "increasing", "blocked force")]
        down = card[(joint, "decreasing", "blocked force")]
        assert up == pytest.approx(area * p, rel=6e-3)
        assert down == pytest.approx(-area * p, rel=6e-3)


@pytest.mark.slow
def test_ucl_arm_raised_shoulder_folds_the_elbow_through_the_reach_coupling(ucl):
    # docs/mechanism.md: raised to 120°, the shoulder's upper arm loads the elbow's jack
    # through the reach coupling (half the shoulder extension's torque) and the elbow
    # gives way to its stop (165°, from its start at 0°); a rotation barely moves it
    card, _ = ucl
    assert card[("shoulder_elevation", "increasing", "held joints' largest excursion")] > 150.0
    assert card[("humeral_rotation", "increasing", "held joints' largest excursion")] < 5.0


# ------------------------------------------------------------------------ refusals ---
def test_a_passive_mechanism_is_refused_in_one_line(tmp_path, capsys):
    path = ROOT / "tests" / "data" / "mechanism" / "double_pendulum.toml"
    code = main(["arm", "--config", str(path), "--card", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err == [
        "hydroarm: error: card: no joint of the mechanism is driven by a valve-fed actuator, "
        "so the card's protocol (each joint's valve stepped to full opening) has nothing to "
        "drive"
    ]
    assert not (tmp_path / "o").exists()


def test_a_card_over_the_budget_is_refused_before_any_run():
    circuit = load_circuit(EXAMPLES / "excavator.toml")
    with pytest.raises(HydroarmError) as e:
        mc.mechanism_card(circuit, max_runs=10)
    assert str(e.value) == (
        "card: the protocol needs up to 18 runs for 3 driven joints, more than the budget of 10"
    )


def test_the_ucl_arm_mechanism_card_has_every_joint():
    # the paper joints are servo_jacks driven by their levers, the elbow a valve_4_3 and a
    # cylinder: all four on the card, none left out
    joints, skipped = mc.check_card(load_circuit(EXAMPLES / "ucl-arm-mechanism.toml"))
    assert [j.name for j in joints] == [
        "shoulder_elevation",
        "humeral_rotation",
        "elbow_reach",
        "wrist_rotation",
    ]
    assert skipped == []
    assert [j.servo for j in joints] == [True, True, False, True]
    assert {j.command for j in joints if j.servo} == {"lever"}


def test_the_ucl_arm_card_over_the_budget_is_refused_before_any_run():
    # four driven joints, the servo jacks' among them: 24 runs at most, checked before the
    # first (nothing reported to the progress)
    circuit = load_circuit(EXAMPLES / "ucl-arm-mechanism.toml")
    ticks: list[str] = []
    with pytest.raises(HydroarmError) as e:
        mc.mechanism_card(circuit, max_runs=23, progress=ticks.append)
    assert str(e.value) == (
        "card: the protocol needs up to 24 runs for 4 driven joints, more than the budget of 23"
    )
    assert ticks == []
    assert mc.mechanism_card(circuit, check_only=True) == 24


# ------------------------------------------------------------ a servo jack by hand ---
SERVO = ROOT / "tests" / "data" / "mechanism" / "servo_crank.toml"
# the fixture's jack and crank (tests/data/mechanism/servo_crank.toml)
AREA, K, E_O, LEAK, DAMPER = 3.03e-4, 9.943513487062e-06, 7.5e-4, 8.022e-14, 2000.0
P_S = 3201325.0 - 101325.0  # its supply tank less its return tank
CRANK = 0.02  # crank radius; gear ratio 1, no angle offset: x = r·sin q


def _saturated_jack_speed() -> float:
    """The rod's speed with the valve fully open [m/s]: the orifice's flow
    K·e_o·√((p_s − p)/2) fills the jack, A·v + 2·L·p, with the load pressure p = b·v/A
    that the damper's force b·v needs (the joint's inertia needs none at a steady rod
    speed bar the crank's slow change, 0.2 kPa); a fixed point."""
    v = K * E_O * math.sqrt(P_S / 2.0) / AREA
    for _ in range(60):
        p = DAMPER * v / AREA
        v = (K * E_O * math.sqrt((P_S - p) / 2.0) - 2.0 * LEAK * p) / AREA
    return v


@pytest.fixture(scope="module")
def servo():
    return mc.mechanism_card(load_circuit(SERVO))


def test_servo_jack_joint_speed_is_the_jack_flow_through_the_crank(servo):
    v = _saturated_jack_speed()
    # the protocol's travel: where the crank's moment arm r·cos q is at least cos 30° of
    # its largest (the limits are ±90°, its dead centres): ±30°
    for (_, x), direction in zip(servo.traces["turn"], ("increasing", "decreasing"), strict=True):
        assert abs(x[0]) == pytest.approx(30.0, abs=0.3)  # 0.25°: the pose grid
        assert x[-1] == pytest.approx(-x[0], abs=0.05)  # the servo brings it to rest there
        a, b = math.radians(x[0]), math.radians(x[-1])
        q10, q90 = a + 0.1 * (b - a), a + 0.9 * (b - a)
        chord = abs(CRANK * (math.sin(q90) - math.sin(q10)))
        speed = servo.value("turn", "speed", direction)
        # exact through the crank: the rod runs at v over the middle 80 % (the valve is
        # saturated until the rod is e_o = 0.75 mm from its end, 3.75 % of its 20 mm),
        # while the joint sweeps 0.8·Δq; 0.2 %: the damper's and the inertia's pressure
        # change along the crank (a few kPa of 31 bar), the 10 % point's transient
        assert speed == pytest.approx(v * 0.8 * abs(b - a) / chord, rel=2e-3)
        # the hand calculation: K_q·e_o/A through the crank ratio at mid-travel
        # (r·cos 0 = r), within the crank's variation over the middle 80 %: the mean of
        # 1/cos q over ±24° lies between 1 (mid-travel) and 1/cos 24° (its ends)
        assert v / CRANK <= speed <= v / (CRANK * math.cos(q90 if b > a else q10))
        assert servo.value("turn", "jack speed", direction) == pytest.approx(1e3 * v, rel=2e-3)


def test_servo_jack_time_constants_are_the_servo_s_own(servo):
    v = _saturated_jack_speed()
    v0 = K * E_O * math.sqrt(P_S / 2.0) / AREA  # the unloaded flow over the area
    for direction in ("increasing", "decreasing"):
        start = servo.value("turn", "time constant, start (63 % of e_o)", direction)
        end = servo.value("turn", "time constant, end (63 % of e_o)", direction)
        # at the start the rod cannot move 0.63·e_o faster than at its saturated speed;
        # it lags by the oil's compression and the inertia's acceleration,
        # (V/β)·p/q + m_eq·v/(A·p_s) ≈ 0.2 + 0.5 ms: at most 1.5 ms
        lower = 1e3 * 0.63 * E_O / v
        assert lower <= start <= lower + 1.5
        # at the end the mechanical feedback makes a first-order servo, ė = −(K_q/A)·e with
        # K_q = K·√(p_s/2): e_o to 0.37·e_o in ln(1/0.37)·A/K_q; the damper's load pressure
        # (b·v/A, 1.95 bar at e = e_o, falling with the speed) slows the orifice's flow by
        # at most √(1 − p/p_s)
        tau = 1e3 * math.log(1.0 / 0.37) * E_O / v0
        assert tau <= end <= tau / math.sqrt(1.0 - DAMPER * v / AREA / P_S)


def test_servo_jack_blocked_force_is_its_stall_pressure_times_the_area(servo):
    # the rod still, the valve fully open: K·e_o·√((p_s − p)/2) = 2·L·p, p a little under
    # p_s (a fixed point); 1e-6: the root's tolerance and the orifice's regularisation
    # (its 100 Pa against the 8.9 kPa drop: 3e-5 of √Δp, 2e-7 of p)
    p = P_S
    for _ in range(60):
        p = P_S - 2.0 * (2.0 * LEAK * p / (K * E_O)) ** 2
    assert servo.value("turn", "blocked force", "increasing") == pytest.approx(AREA * p, rel=1e-6)
    assert servo.value("turn", "blocked force", "decreasing") == pytest.approx(-AREA * p, rel=1e-6)
    # a vertical axis: no gravity moment, no stall payload
    assert math.isnan(servo.value("turn", "stall payload"))
    assert servo.runs <= mc.runs_needed(mc.check_card(load_circuit(SERVO))[0])
