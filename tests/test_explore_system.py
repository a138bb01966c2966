"""``hydroarm explore --config`` on any system file (issue 29): the system page's state
without a browser (hydroarm/explore/system.py). The page itself in headless Chromium is
tests/test_explore_system_browser.py; bad input, tests/test_bad_input.py (``explore-system-*``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hydroarm.arm import ArmScenario
from hydroarm.errors import HydroarmError
from hydroarm.explore.launch import explore_target
from hydroarm.explore.system import (
    DEFAULT_SLIDERS,
    MAX_POINTS,
    POSE_FRAMES,
    SystemExplorer,
    SystemModel,
    load_system_model,
)
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

ROOT = Path(__file__).parents[1]
SERVO_CIRCUIT = ROOT / "examples" / "circuit_position_servo.toml"
BOOM = ROOT / "tests" / "data" / "mechanism" / "boom.toml"
# the example's 3 s at 10 µs is 0.3 M steps a run; the tests run 0.6 s of it (the step at
# 1 s is not reached: the first step, 0.2 m, at t = 0 is)
SHORT = '\n[explore]\nduration = "0.6 s"\n'


def _copy(tmp_path: Path, src: Path, extra: str = SHORT) -> Path:
    p = tmp_path / src.name
    p.write_text(src.read_text() + extra)
    return p


@pytest.fixture(scope="module")
def servo(tmp_path_factory) -> SystemModel:
    path = _copy(
        tmp_path_factory.mktemp("servo"),
        SERVO_CIRCUIT,
        SHORT + '[explore.parameters]\n"payload.mass" = ["20 kg", "400 kg"]\n'
        '"controller.proportional_gain" = []\n',
    )
    return load_system_model(path)


def test_the_page_runs_the_system_kernel(servo, tmp_path):
    """The file's run is ``simulate``'s (the same kernel: equal to the last bit), with the
    [explore] duration; the section does not stop the other commands reading the file."""
    circuit = load_circuit(_copy(tmp_path, SERVO_CIRCUIT))  # [explore] left alone
    ref = simulate(circuit.replace(duration=0.6)).columns()
    assert set(servo.columns) == set(ref)
    for k, v in ref.items():
        np.testing.assert_array_equal(servo.columns[k], v, err_msg=k)
    assert servo.columns["t_s"][-1] == pytest.approx(0.6)


def test_sliders_show_absolute_values_with_units(servo):
    mass, gain = servo.sliders
    assert (mass.name, mass.unit, mass.value) == ("payload.mass", "kg", 100.0)
    assert (mass.low, mass.high) == (20.0, 400.0)
    assert mass.heading == "payload.mass [kg]"
    # [] : the default range, the file's value ÷ 4 to × 4
    assert gain.low == pytest.approx(0.0264249 / 4) and gain.high == pytest.approx(0.0264249 * 4)
    # a gain declared in any unit: its value in SI base units
    assert gain.heading == "controller.proportional_gain [SI]" and gain.value == 0.0264249


def test_a_slider_change_changes_the_curves(servo):
    state = SystemExplorer(servo)
    before = state.columns["load_position_m"].copy()
    assert state.update("payload.mass", 400.0)
    after = state.columns["load_position_m"]
    assert state.error == ""
    # the same run as simulate with the value set
    ref = simulate(servo.circuit.with_values({"payload.mass": 400.0})).columns()
    np.testing.assert_array_equal(after, ref["load_position_m"])
    # four times the mass: a slower rise towards the first step's 0.2 m (the positions
    # differ by more than 1 mm somewhere: the runs are not the same curve)
    assert np.max(np.abs(after - before)) > 1e-3
    assert servo.columns["load_position_m"] is not after  # the shared run is untouched


def test_refused_values_keep_the_setting(servo):
    state = SystemExplorer(servo)
    with pytest.raises(HydroarmError, match="payload.mass"):
        state.set("payload.mass", -5.0)
    with pytest.raises(HydroarmError, match="finite"):
        state.set("payload.mass", float("nan"))
    with pytest.raises(HydroarmError, match="outside the slider's range 20 to 400 kg"):
        state.set("payload.mass", 500.0)  # a typed value; the rule allows it
    with pytest.raises(HydroarmError, match="no slider"):
        state.set("payload.volume", 1.0)
    assert state.values["payload.mass"] == 100.0


def test_a_failed_run_says_why_and_keeps_the_curves(tmp_path):
    """A value the run cannot take (the explicit step above the valve's stable limit: the
    run leaves finite numbers) gives the run's one-line message; the last curves stay."""
    path = _copy(
        tmp_path,
        SERVO_CIRCUIT,
        SHORT + '[explore.parameters]\n"valve.natural_frequency" = ["100 rad/s", "1e6 rad/s"]\n',
    )
    state = SystemExplorer(load_system_model(path))
    before = state.columns
    assert not state.update("valve.natural_frequency", 1e6)
    assert state.error.startswith("the run failed: system.step: the run left finite numbers")
    assert "\n" not in state.error
    assert state.columns is before
    assert state.update("valve.natural_frequency", 200.0)  # back to a value that runs
    assert state.error == ""


def test_chart_is_data_only_per_unit(servo):
    state = SystemExplorer(servo)
    opts = state.chart()
    names = [s["name"] for s in opts["series"]]
    assert names == state.shown
    # one panel per unit, in the order of the outputs: m, then bar
    assert [y["name"] for y in opts["yAxis"]] == ["m", "bar"]
    s = next(s for s in opts["series"] if s["name"] == "load_position_m")
    assert len(s["data"]) <= MAX_POINTS
    t, x = np.array(s["data"]).T
    # the points are the run's records (6 significant digits)
    np.testing.assert_allclose(
        x, np.interp(t, state.columns["t_s"], state.columns["load_position_m"]), rtol=1e-5
    )
    rows = state.summary_rows()
    assert [r["output"] for r in rows] == state.shown
    state.choose(["pump_flow_lpm"])
    assert [y["name"] for y in state.chart()["yAxis"]] == ["L/min"]
    with pytest.raises(HydroarmError, match="no such output"):
        state.choose(["pump_flow"])


def test_defaults_without_an_explore_section():
    model = load_system_model(SERVO_CIRCUIT)
    names = [s.name for s in model.sliders]
    assert len(names) == DEFAULT_SLIDERS
    # PREFERRED first: the mass, the gains, then pressures
    assert names[:3] == ["payload.mass", "controller.proportional_gain", "controller.integral_gain"]
    assert all(s.low < s.value < s.high for s in model.sliders)
    assert "tank.pressure" not in names  # the return line's tank
    assert names[3:] == ["relief.cracking_pressure", "valve.spool_diameter", "pump.displacement"]
    # the positions, then the node pressures that move (not the tank's 1 bar), at most 6
    assert model.shown == [
        "load_position_m", "supply_pressure_bar", "A_pressure_bar", "B_pressure_bar",
    ]  # fmt: skip
    assert np.ptp(model.columns["T_pressure_bar"]) == 0.0
    assert model.defaults == {"parameters": True, "outputs": True}


def test_a_mechanism_and_its_pose(tmp_path):
    model = load_system_model(_copy(tmp_path, BOOM, '\n[explore]\nduration = "0.3 s"\n'))
    assert model.kind == "mechanism"
    assert "lift_angle_deg" in model.shown
    pose = SystemExplorer(model).pose()
    assert pose is not None and len(pose["series"]) == POSE_FRAMES
    # each frame: the base to the joint to the boom's centre of mass
    assert all(len(s["data"]) == 2 for s in pose["series"])
    assert SystemExplorer(load_system_model(SERVO_CIRCUIT)).pose() is None


def test_a_component_servo_is_shown_as_its_circuit(tmp_path):
    model = load_system_model(_copy(tmp_path, ROOT / "examples" / "position_servo.toml"))
    assert model.kind.startswith("component servo")
    assert any(k.endswith("_position_m") for k in model.shown)
    # the arm file keeps its page; a system file gets the system page
    assert isinstance(explore_target(ROOT / "examples" / "ucl-arm.toml"), ArmScenario)


def test_a_reference_file_through_the_file_it_names(tmp_path):
    """A reference file (as ``hydroarm fit`` writes): the values beside ``file`` set, its
    own [explore] read; one naming a component servo is shown as that servo's circuit."""
    (tmp_path / "c.toml").write_text(SERVO_CIRCUIT.read_text())
    ref = tmp_path / "fitted.toml"
    ref.write_text(
        '[system]\nfile = "c.toml"\n"payload.mass" = "200 kg"\nduration = "0.3 s"\n'
        '[explore.parameters]\n"payload.mass" = []\n'
    )
    model = load_system_model(ref)
    assert model.kind == "reference to c.toml"
    (mass,) = model.sliders
    assert (mass.value, mass.low, mass.high) == (200.0, 50.0, 800.0)
    ref_servo = simulate(load_circuit(tmp_path / "c.toml").replace(duration=0.3))
    assert model.columns["t_s"][-1] == ref_servo.t[-1]
    (tmp_path / "s.toml").write_text((ROOT / "examples" / "position_servo.toml").read_text())
    ref.write_text('[system]\nfile = "s.toml"\nduration = "0.3 s"\n')
    model = load_system_model(ref)
    assert model.kind == "reference to the component servo s.toml"
    assert model.columns["t_s"][-1] == pytest.approx(0.3)


def test_a_study_opens_the_system_it_names():
    """A study file (here a design study's) opens the system its ``[system] file`` names,
    with the values beside ``file`` (boom_servo.toml run for 3 s, not its 4.5 s)."""
    model = load_system_model(ROOT / "examples" / "design_boom_servo.toml")
    assert model.kind == "the system of a study: the component servo boom_servo.toml"
    assert model.circuit.duration == 3.0
    assert model.columns["t_s"][-1] == pytest.approx(3.0)
