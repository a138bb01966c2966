"""examples/counterbalance.toml: an 800 kg load lowered through a counterbalance valve and
held (docs/examples/counterbalance.md).

The load is lowered without running away, at the speed the steady flow balance gives, then
stops and is held when the spool centres; the energy account closes. Every number of the
closed forms below is read from the file (the compiled circuit's parameters), so that the
test follows the example.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "counterbalance.toml"
BAR = 1.0e5


@pytest.fixture(scope="module")
def run():
    r = simulate(load_circuit(EXAMPLE))
    assert r.bad_step == -1
    return r


def value(r, name):
    """A parameter of the example in SI (``component.parameter``)."""
    return float(r.P[r.compiled.parameter_index[name]])


def physics(r):
    """The example's numbers: areas, the 4/3 valve's edge coefficient at the lowering
    stroke, pressures, the load."""
    v = {n: value(r, n) for n in r.compiled.parameter_index}
    k_v = (
        v["valve.discharge_coefficient"]
        * math.pi
        * v["valve.spool_diameter"]
        * v["valve.circumference_fraction"]
        * math.sqrt(2.0 / v["valve.density"])
    )
    stroke = -float(np.min(r.output("spool_demand_signal")))  # lowering: x_v < 0
    return {
        "A_a": v["jack.area_a"],
        "A_b": v["jack.area_b"],
        "b": v["jack.viscous_friction"],
        "W": v["payload.mass"] * v["payload.gravity"],
        "m": v["payload.mass"],
        "g": v["payload.gravity"],
        "edge": k_v * stroke,  # k_v·|x_v| [m³ s⁻¹ Pa⁻¹ᐟ²]
        "p_s": v["supply.pressure"],
        "p_t": v["tank.pressure"],
        "floor": v["system.cavitation_pressure"],
        "set": v["cbv.setting"],
        "phi": v["cbv.pilot_ratio"],
        "band": v["cbv.opening_range"],
        "k_cb": v["cbv.nominal_flow"] / math.sqrt(v["cbv.nominal_pressure_drop"]),
    }


def steady_lowering_speed(ph):
    """The lowering speed u at which every flow balances (the float-centre orifices shut):

    rod side fed through P→B:       A_b·u = k_v·|x_v|·√(p_s − p_B)
    cap side metered by the valve:  A_a·u = k·x·√(p_A − p_a),
                                    x = clip((p_A − p_a + φ·(p_B − p_a) − p_set)/Δp_o, 0, 1)
    line A drained through A→T:     A_a·u = k_v·|x_v|·√(p_a − p_T)
    the load in equilibrium:        A_a·p_A − A_b·p_B + b·u = m·g

    given u, the first, third and fourth give p_B, p_a, p_A; the second is solved for u.
    (√ plain: the regularisation's ¼(p_t/Δp)² is < 1e-5 at these drops of 10–100 bar.)"""

    def residual(u):
        p_b = ph["p_s"] - (ph["A_b"] * u / ph["edge"]) ** 2
        p_a_line = ph["p_t"] + (ph["A_a"] * u / ph["edge"]) ** 2
        p_cap = (ph["W"] - ph["b"] * u + ph["A_b"] * p_b) / ph["A_a"]
        excess = p_cap - p_a_line + ph["phi"] * (p_b - p_a_line) - ph["set"]
        x = min(max(excess / ph["band"], 0.0), 1.0)
        return ph["k_cb"] * x * math.sqrt(max(p_cap - p_a_line, 0.0)) - ph["A_a"] * u

    return brentq(residual, 1e-9, runaway_bound(ph), xtol=1e-12)


def runaway_bound(ph):
    """The fastest the load can go down with the rod side filled: the meter-in edge's flow
    with the rod side at the cavitation floor, k_v·|x_v|·√(p_s − p_floor)/A_b. Faster, the
    rod side would cavitate, the pilot pressure vanish and the valve shut (its setting is
    above the load-induced pressure)."""
    return ph["edge"] * math.sqrt(ph["p_s"] - ph["floor"]) / ph["A_b"]


def test_counterbalance_lowers_at_the_metered_speed_without_runaway(run):
    """While the spool is open (0.4–1.4 s) the load goes down at the speed of the steady
    flow balance (51.7 mm/s; within 1e-4 over the last 0.4 s, where the run has settled to
    7 digits), never faster than the runaway bound (101.6 mm/s) at any time (the start
    overshoots to 62 mm/s), and the rod side never reaches the cavitation floor (lowering it
    is at 74 bar; its lowest, 0.3 bar absolute, is in the stop's ringing with the line
    vented)."""
    ph = physics(run)
    t = run.output("t_s")
    v = run.output("load_velocity_m_s")
    u_star = steady_lowering_speed(ph)
    assert u_star == pytest.approx(0.0517, abs=5e-4)  # the number the docs quote
    steady = (t >= 1.0) & (t <= 1.4)
    np.testing.assert_allclose(-v[steady], u_star, rtol=1e-4)
    assert np.max(-v) < runaway_bound(ph)
    assert np.min(run.output("line_b_pressure_bar")) * BAR > ph["floor"] + 0.1 * BAR
    # the counterbalance valve meters: partly open, the pilot at the pressure that opens it
    x = run.output("cbv_opening")[steady]
    assert np.all((x > 0.05) & (x < 0.5))


def test_counterbalance_stops_and_holds_the_load(run):
    """After the spool centres (1.5 s; float centre: lines A and B vented to tank) the valve,
    its pilot gone, shuts (its setting 52 bar is 1.3 × the 40 bar load pressure): the load
    stops, and the cap side holds (m·g + A_b·p_T)/A_a = 40.61 bar. No leakage is modelled and
    the valve is shut by 12 bar, so all that moves is the ringing of the stop on the oil's
    stiffness, decaying under the rod's viscous friction; from 2.0 s the position stays
    within 20 µm (measured: 9 µm) and its last 0.1 s average within 5 µm of its 2.0–2.1 s
    average (no drift; measured: 0.6 µm)."""
    ph = physics(run)
    t = run.output("t_s")
    x = run.output("load_position_m")
    hold = t >= 2.0
    assert np.ptp(x[hold]) < 20e-6
    first = x[(t >= 2.0) & (t < 2.1)].mean()
    last = x[t >= 2.4].mean()
    assert abs(last - first) < 5e-6
    assert np.max(np.abs(run.output("load_velocity_m_s")[hold])) < 1e-3
    assert np.max(run.output("cbv_opening")[hold]) < 1e-9
    p_hold = (ph["W"] + ph["A_b"] * ph["p_t"]) / ph["A_a"]
    assert run.output("cap_pressure_bar")[-1] * BAR == pytest.approx(p_hold, abs=0.2 * BAR)
    assert x[-1] < 0.4 - 0.05  # it did go down, some 57 mm


def test_counterbalance_energy_closes(run):
    """The energy account: the components' energies sum to zero (the power sums to zero at
    every record; 1e-6 of the supply's work bounds the round-off), gravity's work m·g·Δx is
    the payload's (kinetic energy is nil at both ends; 1e-3 for the records' trapezoid), and
    every valve only dissipates."""
    ph = physics(run)
    e = run.energy()
    assert abs(e["closure_energy_j"]) < 1e-6 * abs(e["supply_energy_j"])
    x = run.output("load_position_m")
    assert e["payload_energy_j"] == pytest.approx(ph["m"] * ph["g"] * (x[-1] - x[0]), rel=1e-3)
    for name in ("valve", "cbv", "float_a", "float_b"):
        assert np.all(run.output(f"{name}_power_w") >= -1e-9), name
