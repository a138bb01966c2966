"""``hydroarm explore``'s state without a browser: the single joint, the live arm, the
block-stacking task, the recording and the checks made before the server starts.

The page itself (NiceGUI) is tested in a real browser (tests/test_explore_browser.py): the
state classes here are what its callbacks call."""

from __future__ import annotations

import math
import socket
import sys
from pathlib import Path

import numpy as np
import pytest

from hydroarm.arm import load_arm, load_arm_text, simulate_arm
from hydroarm.arm.stepper import ArmStepper
from hydroarm.errors import HydroarmError
from hydroarm.explore import JointExplorer, LiveArm, StackingTask, check, default_arm
from hydroarm.explore.blocks import BLOCK_SIZE, GRASP_RADIUS, PAD
from hydroarm.explore.joint import JointSettings, build_joint, hand_load
from hydroarm.explore.launch import check_port
from hydroarm.explore.live import LEVER_RATE, MAX_TICK
from hydroarm.io.catalog import paper_load
from hydroarm.model.lever import step as lever_step
from hydroarm.model.scenario import saturation_test, simulate

EXAMPLES = Path(__file__).parents[1] / "examples"


@pytest.fixture(scope="module")
def joint():
    return JointExplorer()


@pytest.fixture(scope="module")
def arm():
    return default_arm()


# ------------------------------------------------------------------ single joint ---
def test_hand_load_is_load_1_plus_the_hand():
    base, load = paper_load(1), hand_load(0.0)
    # no mass in the hand: Appendix I's load 1 (the same floats through W·X/W)
    assert load.weight == base.weight
    assert load.gravity_torque == pytest.approx(base.gravity_torque, rel=1e-15)
    assert load.inertia == base.inertia
    heavier = hand_load(0.45)
    assert heavier.gravity_torque > load.gravity_torque and heavier.inertia > load.inertia


def test_joint_runs_are_simulate(joint):
    """One physics: the view's numbers are simulate()'s of the paper's saturation test."""
    s = joint.settings
    res = simulate(saturation_test(build_joint(s), hand_load(s.hand_mass), "raise"))
    assert joint.saturation_velocity("raise") == res.metrics()["saturation_velocity_m_s"]
    assert joint.run.error == ""
    assert set(joint.traces()) == {"t", "theta", "x", "p", "xdot"}


def test_heavier_hand_raises_slower_and_lowers_faster():
    """Table I's trend: load 5 (0.45 kg in the hand) raises at 20.8 mm/s against load 1's
    24.4 and lowers at 36.6 against 32.8."""
    e = JointExplorer()
    up0, down0 = e.saturation_velocity("raise"), e.saturation_velocity("lower")
    e.set("hand_mass", 0.45)
    assert e.saturation_velocity("raise") < up0
    assert e.saturation_velocity("lower") > down0
    rows = e.paper_rows()
    assert rows[0]["source"].startswith("model") and rows[0]["raise"] == pytest.approx(
        e.saturation_velocity("raise") * 1e3, rel=1e-12
    )
    assert {r["load"] for r in rows[1:]} == {"load 1", "load 5", "load 6", "load 10"}


def test_sliders_and_choices(joint):
    assert joint.display_value("supply_pressure") == pytest.approx(31.0)  # bar, the set's
    with pytest.raises(HydroarmError, match="hand_mass: must be between 0 and 0.6 kg"):
        joint.set("hand_mass", 2.0)
    with pytest.raises(HydroarmError, match="valve_model: must be one of"):
        joint.set("valve_model", "spool")
    with pytest.raises(HydroarmError, match="nothing: is not a control"):
        joint.set("nothing", 1)
    assert joint.test("lower") is joint.run and joint.direction == "lower"
    joint.test("raise")


def test_choices_default_to_the_sets_own():
    e = JointExplorer(JointSettings(parameter_set="ucl-arm-measured"))
    # the measured arm's set: orifice valve, kinematic torque arm, 96.5 % loss at stall
    assert (e.option("valve_model"), e.option("torque_arm")) == ("orifice", "kinematic")
    assert e.display_value("gearbox_loss_at_stall") == pytest.approx(0.96486)
    e.set("valve_model", "linear")
    assert e.option("valve_model") == "linear" and e.option("torque_arm") == "kinematic"


def test_a_setting_that_cannot_run_is_reported():
    # a tenth of the leakage, four times the flow gain and the volume: the loop is unstable
    # (simulate's own error text, shown on the page; no results, no numbers)
    e = JointExplorer(JointSettings(leakage_gain=0.1, volume_gain=4.0, flow_gain=4.0))
    assert e.run.error.startswith("joint: the servo loop is unstable")
    assert e.result is None and e.traces() == {} and math.isnan(e.saturation_velocity())
    assert e.linear()["error"] == e.run.error


def test_linear_view(joint):
    lin = joint.linear()
    assert lin["error"] == ""
    m = lin["margins"]
    assert math.isfinite(m["phase_margin_deg"]) and m["phase_margin_deg"] > 0
    assert lin["bandwidth"] > 0


# ------------------------------------------------------------------ the live arm ---
def test_default_arm_is_the_example_arm(arm):
    ex = load_arm(EXAMPLES / "ucl-arm.toml")
    assert arm.joints == ex.joints
    assert arm.geometry == ex.geometry and arm.power_pack == ex.power_pack
    assert (arm.method, arm.step) == (ex.method, ex.step)
    assert arm.initial_angles == ex.initial_angles


def test_held_lever_is_the_arm_run(arm):
    """One physics: levers set at t = 0 and held give the run of the same step levers on the
    system kernel (the arm's mechanism, `simulate_arm`; the stepper's own bit-for-bit
    test is tests/test_stepper.py; here through the live arm's lever mapping and clock;
    equal to rounding, 1e-12 rad: the run's angles go through degrees)."""
    live = LiveArm(arm)
    target = {"shoulder_elevation": math.radians(30.0), "elbow_reach": math.radians(60.0)}
    for n, a in target.items():
        live.set_lever(n, a)
    for _ in range(20):
        live.tick(MAX_TICK)  # 2 s
    assert live.t == pytest.approx(2.0, abs=1e-9)
    inputs = dict(arm.inputs)
    for n, a in target.items():
        j = arm.joint(n)
        inputs[n] = lever_step(j.lever_for_angle(0.0), j.lever_for_angle(a), 0.0)
    # at the live arm's step (below the file's 1 ms: tests/test_explore_live_run.py)
    res = simulate_arm(arm.replace(inputs=inputs, duration=2.0, record_every=1, step=live.step))
    got = live.angles()
    for n in target:
        assert got[n] == pytest.approx(
            float(res.articulation_angles()[-1, res.index(n)]), abs=1e-12
        )


def test_keys_move_levers_at_their_rate(arm):
    live = LiveArm(arm)
    live.key("Q", True)
    live.key("e", True)
    live.tick(0.05)
    live.key("q", False)
    live.tick(0.05)
    live.key("e", False)
    live.tick(0.05)
    lv = live.levers
    # 0.05 s of the shoulder key, 0.1 s of the elbow key at LEVER_RATE (exact arithmetic)
    assert lv["shoulder_elevation"] == pytest.approx(0.05 * LEVER_RATE, rel=1e-12)
    assert lv["elbow_reach"] == pytest.approx(0.1 * LEVER_RATE, rel=1e-12)
    assert live.angles()["shoulder_elevation"] > 0.0
    # the recording: a row per tick in which a lever moved, after the start
    assert [round(t, 9) for t, _ in live.recording] == [0.0, 0.05, 0.1]
    # a lever stops at its range
    live.key("a", True)
    live.tick(MAX_TICK)
    assert live.levers["shoulder_elevation"] == 0.0


def test_speed_pause_and_reset(arm):
    live = LiveArm(arm)
    live.set_speed(0.25)
    assert live.tick(0.04) == pytest.approx(0.01)
    assert live.tick(5.0) == pytest.approx(0.25 * MAX_TICK)  # a long stall is capped
    live.paused = True
    t = live.t
    assert live.tick(0.04) == 0.0 and live.t == t
    with pytest.raises(HydroarmError, match="speed"):
        live.set_speed(2.0)
    live.reset()
    assert live.t == 0.0 and not live.paused and len(live.recording) == 1


def test_gauges(arm):
    live = LiveArm(arm)
    live.set_lever("elbow_reach", math.radians(90.0))
    live.tick(0.05)
    g = live.gauges()
    assert set(g["pressures"]) == set(live.names)
    # the elbow moving at full speed draws flow; the pump's 0.6 l/min is the file's
    assert g["valve_flow"] > 0 and g["pump_capacity"] == pytest.approx(0.6e-3 / 60)
    assert 0 < g["supply_pressure"] <= g["relief_pressure"] * (1 + 1e-9)


def test_recording_replays_in_the_arm_command(arm, tmp_path):
    """The saved attempt is the arm command's lever CSV: read by the arm file reader and run,
    it ends where the live arm ended (to 0.5°: the live levers are held over each tick, the
    replay interpolates linearly between the rows, up to LEVER_RATE × one tick ≈ 1.5° of
    lever apart while a key is held, the arm's lag then closing the gap)."""
    live = LiveArm(arm)
    for k, ticks in (("q", 15), ("e", 30), ("s", 10)):
        live.key(k, True)
        for _ in range(ticks):
            live.tick(1 / 30)
        live.key(k, False)
    for _ in range(30):
        live.tick(1 / 30)
    (tmp_path / "attempt.csv").write_text(live.recording_csv())
    text = (EXAMPLES / "ucl-arm.toml").read_text()
    text = text.replace('csv = "block_stacking.csv"', 'csv = "attempt.csv"')
    text = text.replace('duration = "9 s"', f'duration = "{live.t:.6f} s"')
    sc = load_arm_text(text, tmp_path)
    res = simulate_arm(sc)
    got = live.angles()
    for n in live.names:
        replay = math.degrees(float(res.articulation_angles()[-1, res.index(n)]))
        assert replay == pytest.approx(math.degrees(got[n]), abs=0.5), n


def test_live_arm_needs_all_four_joints():
    text = (EXAMPLES / "ucl-arm.toml").read_text()
    sc = load_arm_text(text, EXAMPLES)
    three = sc.replace(joints=sc.joints[:3])
    with pytest.raises(HydroarmError, match="joints: the live arm needs all four"):
        LiveArm(three, stepper_factory=ArmStepper)


# ------------------------------------------------------------------ the blocks ---
def test_grasp_stack_and_score():
    task = StackingTask()
    first = task.blocks[0].centre.copy()
    far = first + np.array([0.0, 0.0, 2 * GRASP_RADIUS])
    assert task.toggle(far, 0.5) == "nothing in reach"
    task.start(0.2)
    assert task.toggle(first + [0.0, 0.0, 0.01], 1.0) == "grasped 1"
    pad = np.array([PAD[0] + 0.004, PAD[1] - 0.003, first[2] + 0.05])
    task.follow(pad)
    assert task.toggle(pad, 2.0) == "released 1"
    s = task.score(2.5)
    assert s["stacked"] == 1 and not s["done"]
    assert s["placement_error"] == pytest.approx(0.005, rel=1e-9)  # the 3-4-5 mm offset
    assert s["time"] == pytest.approx(2.3)  # running from the first lever movement
    # the second block onto the first: it rests one block higher
    assert task.toggle(task.blocks[1].centre, 3.0) == "grasped 2"
    above = task.blocks[0].centre + [0.006, 0.0, 3 * BLOCK_SIZE]
    task.toggle(above, 4.0)
    assert task.blocks[1].centre[2] == pytest.approx(task.blocks[0].centre[2] + BLOCK_SIZE)
    assert task.stacked() == 2
    # the first, now under the second, cannot be taken
    assert task.toggle(task.blocks[0].centre, 4.5) in ("grasped 2", "nothing in reach")
    task.reset()
    assert task.stacked() == 0 and task.score(9.0)["time"] == 0.0


def test_all_stacked_stops_the_clock():
    task = StackingTask(starts=((0.2, 0.0),))
    task.start(1.0)
    task.toggle(task.blocks[0].centre, 1.5)
    task.toggle(np.array([*PAD, -0.2]), 3.0)
    s = task.score(10.0)
    assert s["done"] and s["time"] == pytest.approx(2.0)


def test_block_off_the_pad_is_not_stacked():
    task = StackingTask()
    task.toggle(task.blocks[0].centre, 0.0)
    task.toggle(task.blocks[0].centre + [0.0, 0.1, 0.0], 1.0)
    assert task.stacked() == 0 and math.isnan(task.score(1.0)["placement_error"])


# ------------------------------------------------------------------ start checks ---
def test_port_in_use_is_refused():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        with pytest.raises(HydroarmError, match=rf"--port: 127.0.0.1:{port} is in use"):
            check_port(port)


def test_check_before_serving(arm, tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert check(arm, port, tmp_path / "attempts") == tmp_path / "attempts"
    assert not (tmp_path / "attempts").exists()  # made when an attempt is saved


def test_missing_nicegui_is_one_line(arm, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "nicegui", None)  # import nicegui raises ImportError
    with pytest.raises(HydroarmError, match=r"explore: needs NiceGUI.*hydroarm\[explore\]"):
        check(arm, 1, tmp_path)


def test_the_shown_test_first_then_the_other():
    """The page's first answer runs the shown test only (its curves), then the other (the
    tables): the same numbers as both at once."""
    e = JointExplorer()
    e.set("hand_mass", 0.2, shown_only=True)
    assert not e.complete and math.isnan(e.saturation_velocity("lower"))
    assert math.isfinite(e.saturation_velocity("raise"))
    e.run_rest()
    assert e.complete
    both = JointExplorer()
    both.set("hand_mass", 0.2)
    for d in ("raise", "lower"):
        assert e.saturation_velocity(d) == both.saturation_velocity(d)


def test_the_bode_plot_is_the_linear_models(joint):
    """The linear view's curves (ECharts data) are LinearModel.bode_figure's: the same
    responses at the grid's ends (the two grids share them; 1e-5: the 6 significant digits
    sent to the browser)."""
    options = joint.bode()
    fig = joint.linear()["model"].bode_figure()
    mag, phase = fig.axes[0].get_lines(), fig.axes[1].get_lines()
    sent = options["series"]  # open loop: magnitude, phase; closed loop: magnitude, phase
    for k, (m_line, p_line) in enumerate(((mag[0], phase[0]), (mag[1], phase[1]))):
        for line, s in ((m_line, sent[2 * k]), (p_line, sent[2 * k + 1])):
            x, y = line.get_data()
            for i in (0, -1):
                assert s["data"][i][0] == pytest.approx(x[i], rel=1e-5)
                assert s["data"][i][1] == pytest.approx(y[i], rel=1e-5, abs=1e-4)
    assert options["title"]["text"].startswith("gain margin")
