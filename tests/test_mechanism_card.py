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


def test_the_ucl_arm_mechanism_card_leaves_its_paper_joints_out():
    # the paper joints are lumped servo_jacks (the UCL arm's own card measures them); the
    # elbow's valve_4_3 and cylinder are on the card
    joints, skipped = mc.check_card(load_circuit(EXAMPLES / "ucl-arm-mechanism.toml"))
    assert [j.name for j in joints] == ["elbow_reach"]
    assert [s.split(" ")[0] for s in skipped] == [
        "shoulder_elevation",
        "humeral_rotation",
        "wrist_rotation",
    ]


def test_card_on_the_arm_model_is_refused(tmp_path, capsys):
    argv = ["arm", "--config", str(EXAMPLES / "ucl-arm.toml"), "--card", "--out", str(tmp_path)]
    assert main(argv) == 2
    assert "hydroarm: error: --card: " in capsys.readouterr().err
