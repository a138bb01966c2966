"""examples/pump_speed.toml (docs/examples/pump_speed.md): a fixed pump run up from rest to
1500 rpm in 1 s into a 1 L hose guarded by a relief valve. The closed forms are the figure
script's (examples/pump_speed_plot.py), so that the figure shows what is checked here."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PLOT = runpy.run_path(str(EXAMPLES / "pump_speed_plot.py"))  # its functions, not its main


@pytest.fixture(scope="module")
def run():
    circuit = load_circuit(EXAMPLES / "pump_speed.toml")
    r = simulate(circuit)
    assert r.bad_step == -1
    return circuit, r, r.to_pandas(), PLOT["values"](circuit)


def test_pressure_follows_the_hose_compression_until_the_relief_cracks(run):
    """Relief shut: C·ṗ = D·α·t − C_l·(p − p_T), whose solution (T = C/C_l ≈ 0.67 s) is
    the figure script's ``hose_pressure``. RK4 at h = 10 µs on a solution of time scale
    0.67 s: error ~ (h/T)⁴ ≈ 1e-20 relative, so the bound (1 Pa in 100 bar) is round-off
    over 25 000 steps. The relief cracks when that closed form reaches p_c (bisected
    here), within the record in which the valve's latch opens."""
    _, _, df, v = run
    t = df["t_s"].to_numpy()
    p = df["supply_pressure_bar"].to_numpy() * 1e5
    shut = df["relief_open"].to_numpy() < 0.5
    assert shut.sum() > 100  # the first quarter second: 240 records
    np.testing.assert_allclose(p[shut], PLOT["hose_pressure"](t[shut], v), rtol=0, atol=1.0)
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if PLOT["hose_pressure"](mid, v) < v["p_c"] else (lo, mid)
    t_crack = 0.5 * (lo + hi)
    first_open = t[np.argmax(~shut)]
    dt = t[1] - t[0]
    assert first_open - dt < t_crack <= first_open
    assert 0.2 < t_crack < 0.3  # 0.2443 s


def test_relief_holds_the_pressure_at_its_steady_state(run):
    """After the run-up (1 s) the relief passes the pump's whole flow at the pressure where
    its static opening x*(p) = (p − p_c)/(C_s + (p − p_T)·C_f) lets D·ω − C_l·(p − p_T)
    through (bisected on the shared laws in the figure script): the fixed point of the
    node's equation, which RK4 keeps exactly, reached with the relief's time constant
    C/(∂q/∂p) ≈ 0.14 ms, i.e. at once. Bound: 1 Pa of the 0.49 bar override."""
    _, _, df, v = run
    p_ss = PLOT["relief_steady_pressure"](v)
    end = df["t_s"].to_numpy() > 1.1
    p = df["supply_pressure_bar"].to_numpy()[end] * 1e5
    np.testing.assert_allclose(p, p_ss, rtol=0, atol=1.0)
    assert 0.4e5 < p_ss - v["p_c"] < 0.6e5  # the override at 14.4 L/min: 0.49 bar
    q_pump = df["pump_flow_lpm"].to_numpy()[end]
    np.testing.assert_allclose(df["relief_flow_lpm"].to_numpy()[end], q_pump, rtol=1e-9)
    leak = v["C_l"] * (p_ss - v["p_t"])
    full = v["D"] * v["accel"] * v["ramp_end"]
    np.testing.assert_allclose(q_pump, (full - leak) * 6e4, rtol=1e-12)
    # while the speed ramps (once the cracking transient of a few τ_r has passed), the
    # relief follows its steady state at each speed, behind by its lag: the override's rate
    # (0.51 bar/s) times τ_r = C/(∂q/∂p) ≈ 0.14 ms, 7 Pa; bound 20 Pa
    t = df["t_s"].to_numpy()
    t_open = t[np.argmax(df["relief_open"].to_numpy() > 0.5)]
    ramp = (t > t_open + 0.005) & (t < 1.0)
    speed = df["motor_speed_signal"].to_numpy()[ramp][::10]
    quasi = np.array([PLOT["relief_steady_pressure"](v, w) for w in speed])
    p_ramp = df["supply_pressure_bar"].to_numpy()[ramp][::10] * 1e5
    np.testing.assert_allclose(p_ramp, quasi, rtol=0, atol=20.0)


def test_energy_account(run):
    """The power sums to zero at every record (system.port_quantities), so the energies
    close to round-off. The hose stores C·(p² − p₀²)/2; the trapezoid over 1 ms records
    cannot follow the compression power's drop (≈ 0.5 kW to 0.3 W within 0.1 ms) when the
    relief cracks: its error is at most half a record of the largest recorded power, 0.25 J
    (measured: 0.11 J)."""
    _, r, df, v = run
    e = r.energy()
    assert e["pump_energy_j"] < -3000.0  # the pump delivers 3.5 kJ
    assert abs(e["closure_energy_j"]) < 1e-9 * abs(e["pump_energy_j"])
    p_end = df["supply_pressure_bar"].iloc[-1] * 1e5
    stored = v["C"] * (p_end**2 - v["p_0"] ** 2) / 2
    peak = df["hose_power_w"].max()
    dt = df["t_s"].iloc[1] - df["t_s"].iloc[0]
    assert e["hose_energy_j"] == pytest.approx(stored, abs=0.5 * peak * dt)
    # the relief dissipates the rest (the tank's term: p_T times the flow it takes back)
    assert e["relief_energy_j"] == pytest.approx(
        -e["pump_energy_j"] - e["hose_energy_j"] - e["tank_energy_j"], rel=1e-9
    )


def test_figure_script_writes_the_png(tmp_path):
    out = PLOT["main"](str(tmp_path))
    assert out == tmp_path / "pump_speed.png" and out.stat().st_size > 10_000
