"""examples/two_actuators.toml: two cylinders on one pump sharing its flow through a
pressure-compensated flow control (issue 28), and the same circuit without the
compensation (the light load takes the whole flow first)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "two_actuators.toml"
PUMP_FLOW = 10e-6 / (2 * np.pi) * 1500 * 2 * np.pi / 60  # 10 cm³/rev at 1500 rpm [m³/s]
Q_SET = 8e-3 / 60  # [m³/s]


@pytest.fixture(scope="module")
def shared():
    return simulate(load_circuit(EXAMPLE)).to_pandas()


def _mean_speed(df, node, t0=0.5, t1=2.0):
    t = df["t_s"].to_numpy()
    x = df[f"{node}_position_m"].to_numpy()
    i0, i1 = np.searchsorted(t, [t0, t1 - 1e-9])
    return (x[i1] - x[i0]) / (t[i1] - t[i0])


def test_both_cylinders_move_at_once(shared):
    """The light cylinder runs at q_set/A_a: within 1 % (the flow control's regulation,
    0.76 % measured in tests/test_valves.py, plus the branch volume's compression as the
    pressure swings); the heavy one takes the rest of the pump's flow, within 2 % (its
    3 t load rings on the oil column, so its chambers' compression over the window adds
    to the error)."""
    assert _mean_speed(shared, "light") == pytest.approx(Q_SET / 20e-4, rel=0.01)
    assert _mean_speed(shared, "heavy") == pytest.approx((PUMP_FLOW - Q_SET) / 50e-4, rel=0.02)
    assert shared["relief_flow_lpm"].max() < 1e-6  # the relief valve never opened
    # the pump pressure is the heavy load's: m·g/A_a = 58.9 bar gauge, ringing about it
    late = shared["t_s"] > 0.5
    mean_p = shared.loc[late, "supply_pressure_bar"].mean()
    assert mean_p == pytest.approx(1.0 + 3000 * 9.81 / 50e-4 / 1e5, rel=0.05)


def test_without_compensation_the_light_load_goes_first():
    """With a flow setting above the pump's flow the compensator never acts: the light load
    (4.9 bar) takes the whole pump flow and the heavy one (58.9 bar) does not move."""
    circuit = load_circuit(EXAMPLE).with_values({"priority.flow_setting": 1e-3})
    df = simulate(circuit.replace(duration=1.0)).to_pandas()
    assert _mean_speed(df, "light", 0.3, 1.0) == pytest.approx(PUMP_FLOW / 20e-4, rel=0.02)
    assert df["heavy_position_m"].max() < 1e-3


def test_energy_closes():
    """The powers sum to zero at every record; and after the start (the light load bounces
    on its stop as the pressure builds: an inelastic stop's loss is a projection, outside
    the power account), each load's absorbed energy is its gain m·g·Δx + ½·m·Δ(v²), to the
    trapezoid rule's error over records 0.1 ms apart (2e-3)."""
    r = simulate(load_circuit(EXAMPLE).replace(duration=0.6, record_every=10))
    e = r.energy()
    assert abs(e["closure_energy_j"]) < 1e-9 * abs(e["pump_energy_j"])
    df = r.to_pandas()
    late = df[df["t_s"] >= 0.3]
    for node, mass in (("light", 100.0), ("heavy", 3000.0)):
        absorbed = np.trapezoid(late[f"{node}_load_power_w"], late["t_s"])
        x = late[f"{node}_position_m"].to_numpy()
        v = late[f"{node}_velocity_m_s"].to_numpy()
        gain = mass * 9.81 * (x[-1] - x[0]) + 0.5 * mass * (v[-1] ** 2 - v[0] ** 2)
        assert absorbed == pytest.approx(gain, rel=2e-3)


def test_figure_script(tmp_path):
    import runpy
    import sys

    script = EXAMPLE.with_name("two_actuators_plot.py")
    old = sys.argv
    sys.argv = [str(script), str(tmp_path)]
    try:
        runpy.run_path(str(script), run_name="__main__")
    finally:
        sys.argv = old
    assert (tmp_path / "two_actuators.png").stat().st_size > 10_000
