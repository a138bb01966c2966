"""The circuit's adaptive method (`hydroarm.integrators.adaptive.integrate_circuit_adaptive`)
at an end stop: the hit located on the dense output, against the closed form."""

from __future__ import annotations

import math

import numpy as np

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

# a 1 kg mass on a 10 kN/m spring (ω = 100 rad/s) let go 10 mm from the spring's free
# position, onto an inelastic stop at −5 mm: x = 10 mm·cos(ωt) until the hit at
# t_hit = acos(−1/2)/ω = 20.94 ms, then at rest on the stop and pulled back by the spring,
# x = −5 mm·cos(ω(t − t_hit)), never reaching the stop again
BOUNCE = """
name = "a mass on a spring against an inelastic stop"

[[component]]
type = "mass"
name = "body"
ports = { body = "x" }
mass = "1 kg"
spring_rate = "1e4 N/m"
initial_position = "10 mm"
position_min = "-5 mm"

[solver]
method = "adaptive"
step = "10 us"
duration = "0.06 s"
record_every = 10
"""
OMEGA, X0, STOP = 100.0, 0.01, -0.005
T_HIT = math.acos(STOP / X0) / OMEGA

# the hit resolved at the end of Radau's step (≤ 10 fixed steps = 100 µs late): measured
# 1.9e-3 of the travel; located by bisection on the dense output: 3.5e-10 (Radau's rtol
# 1e-8 on the motion); rk4 at 10 µs: 2.0e-4. 1e-6 tells the located hit from the other two
STOP_TOLERANCE = 1e-6


def test_the_adaptive_method_locates_an_end_stops_hit(tmp_path):
    """The instant a mechanical node reaches its stop is found on the step's dense output
    (not at the step's end), so the motion after it, which starts from rest there, follows
    the closed form; the records, 0.1 ms or 10 µs apart, sample one run."""
    path = tmp_path / "bounce.toml"
    path.write_text(BOUNCE)
    circuit = load_circuit(path)
    run = simulate(circuit)
    x = run.output("x_position_m")
    exact = np.where(
        run.t < T_HIT,
        X0 * np.cos(OMEGA * run.t),
        STOP * np.cos(OMEGA * (run.t - T_HIT)),
    )
    # it reached the stop (to its records' spacing), never went past it, and left it
    assert run.t[-1] > 2 * T_HIT and STOP <= np.min(x) < STOP + 1e-5 and x[-1] > 0.0
    assert np.max(np.abs(x - exact)) <= STOP_TOLERANCE * (X0 - STOP)
    fine = simulate(circuit.replace(record_every=1))
    np.testing.assert_array_equal(fine.states[::10], run.states)
