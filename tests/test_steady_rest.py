"""Static states that the solve used to miss (hydroarm/model/circuit_steady.py; docs/linear.md
"Operating point"): a line with wave propagation at rest, a proportional loop holding a
load (a PID's ∫e at K_i = 0 is an accumulator, no condition of a static state), and loads
held by closed valves at null beside a deadheaded pump (the state on the laws' kinks)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import CircuitResult, build
from hydroarm.model.circuit_steady import RESIDUAL_TOL, steady_state

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _columns(compiled, point) -> dict[str, float]:
    t = point.t
    states = np.vstack([point.state, point.state])
    r = CircuitResult(compiled, np.array([t, t + 1e-9]), states, -1, point.P)
    return {k: float(v[0]) for k, v in r.columns().items()}


@pytest.fixture(scope="module")
def water_hammer():
    return build(load_circuit(EXAMPLES / "water_hammer.toml"))


def test_a_closed_line_rests_at_its_supply_pressure(water_hammer):
    # the valve closed (the run's end): uniform pressure, no flow, whatever flow the line
    # started the run with (its initial_flow, 37.7 L/min)
    point = steady_state(water_hammer, 0.3)
    cols = _columns(water_hammer, point)
    assert point.residual <= RESIDUAL_TOL
    # 1e-9: round-off of the solve on 50 bar
    assert cols["valve_in_pressure_bar"] == pytest.approx(50.0, rel=1e-9)
    assert abs(cols["pipe_flow_lpm"]) < 1e-9


def test_a_line_at_rest_carrying_a_flow_drops_r_times_q(water_hammer):
    # the valve open (t = 0): the line is its laminar resistance R = 128·μ·L/(π·d⁴)
    point = steady_state(water_hammer, 0.0)
    cols = _columns(water_hammer, point)
    mu = 32e-6 * 870.0
    r = 128 * mu * 30.0 / (math.pi * 0.02**4)
    q = cols["pipe_flow_lpm"] / 60e3
    drop = (cols["inlet_pressure_bar"] - cols["valve_in_pressure_bar"]) * 1e5
    # 1e-9: round-off (the flow and the drop are of the same solve)
    assert drop == pytest.approx(r * q, rel=1e-9)
    assert cols["valve_flow_lpm"] == pytest.approx(cols["pipe_flow_lpm"], rel=1e-9)
    # the file's own start, 50 bar less R·q at its initial_flow (its 7 digits)
    assert cols["valve_in_pressure_bar"] == pytest.approx(48.66368, rel=1e-7)


def test_a_proportional_loop_holds_its_load_with_an_error():
    # the UCL arm's elbow: lever feedback by a PID of gain 1, no integral action; at rest
    # the spool sits off null by the error that holds the forearm (its underlapped valve)
    path = EXAMPLES / "ucl-arm-mechanism.toml"
    compiled = build(load_circuit(path))
    point = steady_state(compiled, compiled.circuit.duration)
    names = [n for n, _ in compiled.state_names]
    assert point.residual <= RESIDUAL_TOL
    assert point.held[names.index("elbow_reach_controller.integral")]
    cols = _columns(compiled, point)
    error = cols["elbow_reach_reference_signal"] - cols["elbow_reach_measurement_signal"]
    assert abs(error) > 1e-7  # a real offset: [m] of spool, the valve's 0.27 mm underlap
    # the held spool is its command, the controller's output K_p·e (K_p = 1): 1e-12 m of
    # round-off
    assert cols["elbow_reach_valve_spool_m"] == pytest.approx(error, abs=1e-12)


@pytest.mark.parametrize("seed", [0, 7])
def test_loads_held_by_closed_valves_rest_on_their_kinks(seed):
    # the excavator at its cycle's end: three closed-centre valves at null (each edge's
    # opening clipped at 0) and its pump deadheaded at zero stroke (the compensator's target
    # clipped at 0). From the file's start (seed 0) and from a start moved by 1e-9 of itself
    # (seed 7), round-off of another law or CPU: the trust region alone stopped 2.3e-7 off,
    # at seed 0 with √√x in the orifice law, at seed 7 with pow (the Newton polish)
    compiled = build(load_circuit(EXAMPLES / "excavator.toml"))
    rng = np.random.default_rng(seed)
    guess = compiled.s0 * (1.0 + (1e-9 * rng.standard_normal(compiled.s0.size) if seed else 0.0))
    point = steady_state(compiled, compiled.circuit.duration, guess=guess)
    assert point.residual <= RESIDUAL_TOL
    cols = _columns(compiled, point)
    assert cols["pump_fraction"] == 0.0
    for joint in ("boom", "stick", "bucket"):
        # at null within the static state's tolerance of the spool's scale, 1 mm
        assert abs(cols[f"{joint}_valve_spool_m"]) <= RESIDUAL_TOL * 1e-3
    # P anywhere from the pump's zero stroke (290 + 12.5 bar) to the relief's 310 bar
    assert 302.5 <= cols["P_pressure_bar"] <= 310.0
