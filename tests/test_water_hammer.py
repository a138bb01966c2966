"""examples/water_hammer.toml (docs/examples/water_hammer.md): a valve shutting at the end
of 30 m of steel pipe. The first pressure rise against Joukowsky's ρ·c·Δv, the ringing
period against 4·L/c, the lumped hose against the transmission line, the energy account."""

from __future__ import annotations

import math
import pathlib
import runpy
import sys

import numpy as np
import pytest

from hydroarm.core.circuit.components.line import energy_account
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import ComponentSpec, build, simulate

EXAMPLE = pathlib.Path(__file__).resolve().parents[1] / "examples" / "water_hammer.toml"

# the example's pipe (its file's comments): steel, 20 mm bore, 2 mm wall, 30 m, ISO VG 32
RHO, NU, LENGTH, D, END = 870.0, 32e-6, 30.0, 0.02, 0.05
BETA_E = 1.0 / (1.0 / 1.5e9 + 1.0 / 21e9)  # oil and wall (E·s/d = 210 GPa·2/20)
SPEED = math.sqrt(BETA_E / RHO)  # 1268.5 m/s
AREA = math.pi * D * D / 4
Z = RHO * SPEED / AREA  # characteristic impedance
R = 128 * RHO * NU * LENGTH / (math.pi * D**4)  # Hagen–Poiseuille: R/Z = 6 %
Q0 = 6.283185e-4  # m³/s: 2 m/s
SUPPLY = 50.0  # bar
SHUT = (10e-3, 11e-3)  # the valve's closing ramp [s]


@pytest.fixture(scope="module")
def line_run():
    return simulate(load_circuit(EXAMPLE))


def _with_hose(circuit, segments):
    comps = []
    for c in circuit.components:
        if c.type == "line":
            values = {k: v for k, v in c.values.items() if k != "buffer_length"}
            c = ComponentSpec("hose", c.name, c.ports, {**values, "segments": segments})
        comps.append(c)
    return circuit.replace(components=tuple(comps))


def crossings(t, p, level, rising):
    """The times where p crosses the level (linear between records)."""
    a, b = p[:-1] - level, p[1:] - level
    idx = np.nonzero((a < 0) & (b >= 0) if rising else (a >= 0) & (b < 0))[0]
    return t[idx] + (t[idx + 1] - t[idx]) * a[idx] / (a[idx] - b[idx])


def _period(t, p):
    """The ringing period: the mean interval between successive crossings of the supply
    pressure, each way (the first upward crossing is the valve shutting, not the ring)."""
    up = crossings(t, p, SUPPLY, True)[1:]
    down = crossings(t, p, SUPPLY, False)
    return np.mean(np.concatenate([np.diff(up), np.diff(down)])), len(up) + len(down)


def test_the_first_rise_is_joukowskys(line_run):
    """Shut in 1 ms ≪ 2L/c = 47 ms, the oil column stops at the valve before any relief
    returns from the supply: the valve's pressure jumps by ρ·c·Δv = Z·q₀ = 22.07 bar
    (Joukowsky), and stays there for 2L/c. Friction adds to the frictionless rise: the
    pipe's steady drop, at most R·q₀ (6 % here), is recovered as the column stops (line
    packing, Wylie and Streeter 1993); this line lumps it at its ends, so its rise is
    (Z + R/2)·q₀ (+3.0 %) within 0.2 % (the end volume's lag ℓ_e/c = 40 µs and the valve's
    regularised last 0.1 bar are far below the 46 ms plateau read)."""
    t, p = line_run.t, line_run.output("valve_in_pressure_bar")
    before = np.median(p[(t > 5e-3) & (t < SHUT[0])])
    assert before == pytest.approx(SUPPLY - R * Q0 / 1e5, rel=1e-6)  # the steady start
    plateau = np.median(p[(t > SHUT[1] + 1e-3) & (t < SHUT[0] + 2 * LENGTH / SPEED - 1e-3)])
    rise = (plateau - before) * 1e5
    joukowsky = RHO * SPEED * Q0 / AREA
    assert 0.0 <= rise / joukowsky - 1 <= R / Z
    assert rise == pytest.approx((Z + R / 2) * Q0, rel=2e-3)


def test_the_ring_period_is_four_transits(line_run):
    """After the valve shuts the pressure at it rings about the supply's with the period
    4·L/c = 94.6 ms (closed end, held end: a quarter-wave). The line's end volume at the
    closed valve reflects like ℓ_e more pipe and the one at the supply sits on a held node,
    so the line's period is 4·(L − ℓ_e)/c, ℓ_e/L = 0.17 % short; the crossings are read
    between 0.1 ms records (1e-3 of the period)."""
    period, n = _period(line_run.t, line_run.output("valve_in_pressure_bar"))
    assert n >= 4
    assert abs(period / (4 * LENGTH / SPEED) - 1) <= END / LENGTH + 1e-3
    assert period == pytest.approx(4 * (LENGTH - END) / SPEED, rel=1e-3)


def test_a_lumped_hose_rings_with_the_same_period(line_run):
    """The same pipe as a hose of 40 π segments: its quarter-wave mode is (π/(4N))/sin(π/(4N))
    − 1 = 6e-5 slower than the line's, but its fronts ring at the ladder's cut-off 2·N·c/L
    (3.4 krad/s), and a crossing of the supply pressure can fall anywhere within a quarter
    of that ringing, πL/(4Nc) = 0.46 ms, 0.5 % of the period: two crossings, 1 %."""
    r = simulate(_with_hose(load_circuit(EXAMPLE), 40))
    period, n = _period(r.t, r.output("valve_in_pressure_bar"))
    line_period, _ = _period(line_run.t, line_run.output("valve_in_pressure_bar"))
    assert n >= 4
    assert period == pytest.approx(4 * LENGTH / SPEED, rel=1e-2)
    assert period == pytest.approx(line_period, rel=1e-2)


def test_the_energy_account_closes(line_run):
    """Every joule the supply delivers is dissipated by the valve or absorbed by the pipe,
    to round-off; and the pipe's absorbed energy is the change of what it holds (waves in
    flight, end volumes) plus its friction's dissipation, within 0.3 % (the history's linear
    interpolation at the fronts, as in tests/test_circuit_lines.py)."""
    e = line_run.energy()
    assert e["valve_energy_j"] > 10.0 and e["pipe_energy_j"] > 10.0  # joules
    assert abs(e["closure_energy_j"]) < 1e-9 * abs(e["supply_energy_j"])
    stored, dissipated = energy_account(line_run, "pipe")
    assert e["pipe_energy_j"] == pytest.approx(stored[-1] - stored[0] + dissipated[-1], rel=3e-3)


def test_figure_script(tmp_path, monkeypatch):
    """examples/water_hammer_plot.py writes its figure into the folder it is given."""
    monkeypatch.setattr(sys, "argv", ["water_hammer_plot.py", str(tmp_path)])
    runpy.run_path(str(EXAMPLE.with_name("water_hammer_plot.py")), run_name="__main__")
    assert (tmp_path / "water_hammer.png").stat().st_size > 10_000


# rk4 at 1 µs is the reference (its own error: a tenth of rk4's at 10 µs, which is 1.1e-3 of
# the valve pressure's range over 0.1 s here). Radau with the line's history held out of its
# states and written every fixed step along its dense output: measured 8.2e-4 of the range
# (the history's own sample spacing, T/253 = 93 µs, as rk4's); written at Radau's step ends
# only (≤ 100 µs apart) 1.1e-2, and with the history among Radau's states 8.7e-3: 2e-3
# tells them apart
ADAPTIVE_LINE_TOLERANCE = 2e-3


def test_the_adaptive_method_follows_the_wave():
    """method = "adaptive" on the line (its wave history held out of Radau's states,
    `declare.State.held`): the pressure at the valve, front, plateau and the returning
    front, against rk4 at 1 µs; and its records, 0.1 ms or 10 µs apart, sample one run."""
    base = load_circuit(EXAMPLE).replace(duration=0.1)
    compiled = build(base)
    line_states = [
        i for i, (stem, _) in enumerate(compiled.state_names) if stem.startswith("pipe.")
    ]
    assert compiled.held == line_states and len(line_states) == 3 + 2 * 256
    fine = simulate(base.replace(step=1e-6, record_every=100)).output("valve_in_pressure_bar")
    run = simulate(base.replace(method="adaptive"))
    p = run.output("valve_in_pressure_bar")
    assert np.max(np.abs(p - fine)) <= ADAPTIVE_LINE_TOLERANCE * np.ptp(fine)
    dense = simulate(base.replace(method="adaptive", record_every=1))
    np.testing.assert_array_equal(dense.states[::10], run.states)
