"""The paper's joint as a circuit on the system kernel (issue 28: the paper's lumped joint
is a preset of the system; the paper's own kernel is its fast path, held here to it).

Every run of a joint file is made twice: by the paper's kernel (``simulate``,
:mod:`hydroarm.integrators.fixed`) and by the system kernel on the circuit the file stands
for (:func:`hydroarm.io.joint_circuit.joint_circuit`: tanks, ``servo_jack``,
``crank_linkage``, ``inertia``, ``signal_source``). The two evaluate the same laws
(:func:`hydroarm.core.equations.load_flow`, ``load_pressure_rate``, ``friction_capacity``,
``stick_or_slide``) in the same order of steps, so they agree to round-off; the tolerance,
1e-9 of each trace's range, is far above that (measured ≤ 6e-14 of the angle's range with
friction, ≤ 3e-16 without, over 60 000 steps) and far below any term of the model (the
leakage alone moves the angle by ~1e-3 of its range, a gearbox loss by ~1e-2).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import load_circuit
from hydroarm.io.joint_circuit import joint_circuit
from hydroarm.io.schema import load_scenario
from hydroarm.model.circuit import build
from hydroarm.model.circuit import simulate as simulate_circuit
from hydroarm.model.scenario import simulate

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "load6_raise.toml"
TOLERANCE = 1e-9  # of each trace's range (module doc)


def _scenario(parameter_set: str, method: str, direction: str, **joint) -> ha.Scenario:
    base = load_scenario(EXAMPLE)
    j = ha.parameter_set(parameter_set).replace(supply_pressure=base.joint.supply_pressure)
    sc = ha.saturation_test(j.replace(**joint), base.load, direction)
    return sc.replace(method=method, duration=0.5, step=1e-5)


def _both(sc: ha.Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r = simulate(sc)
    df = simulate_circuit(joint_circuit(sc)).to_pandas()
    theta = np.radians(df["joint_angle_deg"].to_numpy())
    p = df["jack_load_pressure_bar"].to_numpy() * 1e5
    assert df["t_s"].to_numpy() == pytest.approx(r.t, abs=1e-12)
    return r.theta, theta, r.p, p


def _assert_same(sc: ha.Scenario) -> tuple[np.ndarray, np.ndarray]:
    th_j, th_c, p_j, p_c = _both(sc)
    assert np.max(np.abs(th_c - th_j)) <= TOLERANCE * np.ptp(th_j)
    assert np.max(np.abs(p_c - p_j)) <= TOLERANCE * np.ptp(p_j)
    return th_j, p_j


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("direction", ["raise", "lower"])
@pytest.mark.parametrize(
    "parameter_set",
    [
        "paper-calibrated",  # linear valve, the printed torque arm r/n
        "ucl-arm-measured",  # orifice valve, leakage at null, piston and gearbox friction
    ],
)
def test_paper_joint_equals_its_circuit(parameter_set, direction, method):
    theta, _ = _assert_same(_scenario(parameter_set, method, direction))
    assert np.ptp(theta) > 0.5  # the joint moved by more than 30° in the half second


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_joint_held_by_stiction_sticks_in_both(method):
    # breakaway friction above what the valve's half-opening can produce: the joint stays
    # where it is (ω = 0 exactly, the stick branch), in both kernels
    sc = _scenario(
        "ucl-arm-measured",
        method,
        "raise",
        static_friction=5000.0,
        coulomb_friction=4000.0,
    )
    theta, _ = _assert_same(sc)
    assert np.ptp(theta) == 0.0


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_end_stop_and_viscous_friction(method):
    # from −30° toward +60° against stops at ±45°: the joint arrives at the stop and rests
    base = load_scenario(EXAMPLE)
    j = ha.parameter_set("paper-calibrated").replace(
        end_stop_angle=np.radians(45.0), viscous_friction=100.0
    )
    sc = ha.saturation_test(j, base.load, "raise", low_angle=np.radians(-30.0))
    theta, _ = _assert_same(sc.replace(method=method, duration=0.8))
    assert theta.max() == pytest.approx(np.radians(45.0), abs=1e-15)


def test_sine_lever_input():
    base = load_scenario(EXAMPLE)
    lever = ha.sine(0.0, 0.004, 3.0)
    sc = base.replace(lever=lever, initial_angle=0.0, duration=0.5, method="rk4")
    _assert_same(sc)


def test_backlash_is_refused():
    sc = load_scenario(EXAMPLE)
    with pytest.raises(HydroarmError, match="backlash"):
        joint_circuit(sc.replace(joint=sc.joint.replace(backlash=0.01)))


def test_expand_writes_a_circuit_file_that_runs_the_joint(tmp_path):
    out = tmp_path / "joint_circuit.toml"
    r = subprocess.run(
        [sys.executable, "-m", "hydroarm", "expand", "--config", str(EXAMPLE), "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    assert "paper joint" in out.read_text()
    circuit = load_circuit(out).replace(duration=0.2)
    sc = load_scenario(EXAMPLE).replace(duration=0.2)
    df = simulate_circuit(circuit).to_pandas()
    j = simulate(sc)
    theta = np.radians(df["joint_angle_deg"].to_numpy())
    # the file holds every value with repr digits: the same run as the object's
    assert np.max(np.abs(theta - j.theta)) <= TOLERANCE * np.ptp(j.theta)


def test_a_crank_whose_range_passes_its_dead_centre_is_refused():
    # the joint's stops 10° beyond the crank's dead centre n·90°: the ratio g' changes sign
    # inside the range the joint may move in (model.circuit._check_dead_centres)
    circuit = joint_circuit(load_scenario(EXAMPLE))
    beyond = np.radians(2 * 90.0 + 10.0)
    circuit = circuit.with_values({"load.angle_min": -beyond, "load.angle_max": beyond})
    with pytest.raises(HydroarmError, match="dead centre") as e:
        build(circuit)
    assert e.value.field == "component.crank"


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_the_crank_angle_datum_shifts_the_joint_and_nothing_else(method):
    # the same joint with its crank's datum q_0 = 40°: every angle of the load (start, end
    # stops, the gravity torque's angle) moved by q_0 gives the same run moved by q_0. The
    # kernel evaluates (q − q_0) where it evaluated θ: the traces agree to the round-off of
    # adding and taking off q_0 (one ulp of ~1 rad per step, ~1e-16·√steps), so the module's
    # TOLERANCE holds
    sc = _scenario("ucl-arm-measured", method, "raise")
    circuit = joint_circuit(sc)
    q0 = np.radians(40.0)
    load = {c.name: c for c in circuit.components}["load"].values
    moved = circuit.with_values(
        {
            "crank.angle_offset": q0,
            "load.initial_angle": load["initial_angle"] + q0,
            "load.angle_min": load["angle_min"] + q0,
            "load.angle_max": load["angle_max"] + q0,
            "load.gravity_angle": load["gravity_angle"] + q0,
        }
    )
    a = simulate_circuit(circuit).to_pandas()
    b = simulate_circuit(moved).to_pandas()
    theta = np.radians(a["joint_angle_deg"].to_numpy())
    shifted = np.radians(b["joint_angle_deg"].to_numpy()) - q0
    assert np.ptp(theta) > 0.5  # it moved by more than 30°
    assert np.max(np.abs(shifted - theta)) <= TOLERANCE * np.ptp(theta)
    p_a, p_b = a["jack_load_pressure_bar"].to_numpy(), b["jack_load_pressure_bar"].to_numpy()
    assert np.max(np.abs(p_b - p_a)) <= TOLERANCE * np.ptp(p_a)
