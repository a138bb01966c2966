"""check_valve against its closed form: between a tank whose pressure is swept up and down
(a signal-driven tank) and a tank at 1 bar, the valve's flow is algebraic in the two
pressures, so the simulated flow must equal the formula of the module's docstring at every
record to round-off (rtol 1e-12); and the hysteresis makes the flow on the way down differ
from the way up."""

from __future__ import annotations

import math

import numpy as np

from hydroarm.io.circuit import circuit_from_doc
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import simulate

CIRCUIT = """
name = "check valve between a swept tank and a tank"
[[component]]
type = "signal_source"
name = "sweep"
ports = { out = "p_in" }
waveform = "table"
times = ["0 s", "1 s", "2 s"]
values = ["1 bar", "4 bar", "1 bar"]
[[component]]
type = "tank"
name = "upstream"
ports = { port = "in", setpoint = "p_in" }
[[component]]
type = "tank"
name = "downstream"
ports = { port = "out" }
pressure = "1 bar"
[[component]]
type = "check_valve"
name = "cv"
ports = { inlet = "in", outlet = "out" }
cracking_pressure = "1 bar"
opening_pressure = "1 bar"
hysteresis = "0.5 bar"
area = "10 mm**2"
[solver]
method = "rk4"
step = "1 ms"
duration = "2 s"
record_every = 1
"""


def _formula(dp, crack, full=1e5, area=10e-6, cd=0.61, rho=870.0, pt=1e4):
    x = np.clip((dp - crack) / full, 0.0, 1.0)
    return cd * area * x * math.sqrt(2 / rho) * dp / (dp * dp + pt * pt) ** 0.25


def test_check_valve_flow_and_hysteresis():
    r = simulate(circuit_from_doc(parse_toml(CIRCUIT, "cv"), "cv"))
    df = r.to_pandas()
    dp = (df["in_pressure_bar"] - df["out_pressure_bar"]).to_numpy() * 1e5
    q = df["cv_flow_lpm"].to_numpy() / 6e4
    up = df["t_s"].to_numpy() <= 1.0
    # rising: closed up to the cracking pressure (1 bar); once open it snaps to the opening
    # of the reseat pressure (cracking − hysteresis), as a poppet with hysteresis does
    want = np.where(dp[up] > 1e5, _formula(dp[up], 0.5e5), 0.0)
    np.testing.assert_allclose(q[up], want, rtol=1e-12, atol=1e-15)
    # falling: open until Δp < 0.5 bar, so the formula with cracking − hysteresis
    down = ~up & (dp >= 0.5e5)
    np.testing.assert_allclose(q[down], _formula(dp[down], 0.5e5), rtol=1e-12, atol=1e-15)
    # at Δp = 0.8 bar: closed on the way up, open (flowing) on the way down
    i_up = np.argmin(np.abs(dp[up] - 0.8e5))
    i_dn = np.argmin(np.abs(np.where(~up, dp, -1.0) - 0.8e5))
    assert q[up][i_up] == 0.0 and q[i_dn] > 0.0
    # never a reverse flow, and closed again at the end (Δp = 0)
    assert q.min() >= 0.0 and q[-1] == 0.0
