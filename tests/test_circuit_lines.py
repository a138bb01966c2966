"""Hoses and lines (docs/components/hose.md, docs/components/line.md): the lumped hose's
friction, steady state, modes and energy; the transmission-line model's wave delay, closed-
end doubling, ringing period, steady friction drop and energy, with rk4 and Euler."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hydroarm.core.circuit.components import _pipe
from hydroarm.core.circuit.components import hose as hose_module
from hydroarm.core.circuit.components import line as line_module
from hydroarm.integrators.system import derivatives_at
from hydroarm.model.circuit import Circuit, ComponentSpec, build, simulate

RHO, BETA = 870.0, 1.5e9
SPEED = math.sqrt(BETA / RHO)  # rigid pipe: c = √(β/ρ) = 1313.1 m/s


def crossings(t, p, level, rising):
    """The times where p crosses the level (linear between records)."""
    a, b = p[:-1] - level, p[1:] - level
    idx = np.nonzero((a < 0) & (b >= 0) if rising else (a >= 0) & (b < 0))[0]
    return t[idx] + (t[idx + 1] - t[idx]) * a[idx] / (a[idx] - b[idx])


def cumulative(t, y):
    return np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t))])


# ----------------------------------------------------------------------------- pipe laws ---
def test_friction_laws_against_darcy_weisbach():
    """The friction drop against Darcy–Weisbach Δp = f·(L/d)·ρ·v²/2 written with Re: f = 64/Re
    (laminar), f = 0.3164/Re^(1/4) (Blasius) for the turbulent law above Re ≈ 1190, where the
    two meet (64/Re = 0.3164·Re^(−1/4) ⇔ Re = (64/0.3164)^(4/3) = 1188)."""
    d, length, nu = 0.01, 5.0, 32e-6
    area = math.pi * d * d / 4
    for re in (100.0, 1000.0, 3000.0, 5.0e4):
        v = re * nu / d
        darcy = (64.0 / re if re < 1188 else 0.3164 / re**0.25) * length / d * RHO * v * v / 2
        got = _pipe.friction_drop(v * area, RHO, nu, length, d, True)
        assert got == pytest.approx(darcy, rel=1e-12)  # the same closed form, rewritten
        assert _pipe.friction_drop(-v * area, RHO, nu, length, d, True) == -got
        lam = _pipe.friction_drop(v * area, RHO, nu, length, d, False)
        assert lam == pytest.approx(64.0 / re * length / d * RHO * v * v / 2, rel=1e-12)
    re_x = (64.0 / 0.3164) ** (4.0 / 3.0)
    q_x = re_x * nu / d * area
    lo = _pipe.friction_drop(q_x * (1 - 1e-9), RHO, nu, length, d, True)
    hi = _pipe.friction_drop(q_x * (1 + 1e-9), RHO, nu, length, d, True)
    assert hi == pytest.approx(lo, rel=1e-8)  # continuous where the laws meet
    assert _pipe.friction_drop(1e-3, RHO, 0.0, length, d, True) == 0.0  # ν = 0: frictionless


# ---------------------------------------------------------------------------------- hose ---
def _hose_circuit(values, p_b=None, **run):
    """tank (20 bar) → hose → tank (p_b) or a closed end (p_b None)."""
    comps = [
        ComponentSpec("tank", "supply", {"port": "A"}, {"pressure": 20e5}),
        ComponentSpec("hose", "hose", {"a": "A", "b": "B"}, values),
    ]
    if p_b is not None:
        comps.append(ComponentSpec("tank", "drain", {"port": "B"}, {"pressure": p_b}))
    return Circuit("hose", tuple(comps), **run)


def test_hose_states_and_one_segment():
    """N flows and N − 1 inner pressures (the declaration's counts "segments" and
    "segments - 1"); one segment has no inner node."""
    for n in (1, 2, 7):
        cc = build(_hose_circuit({"length": 2.0, "diameter": 0.01, "segments": n}, 1e5))
        names = [s for s, _ in cc.state_names]
        assert sum(s.startswith("hose.flow") for s in names) == n
        assert sum(s.startswith("hose.pressure") for s in names) == n - 1


def test_hose_reaches_the_hagen_poiseuille_flow():
    """From rest, a hose between two tanks settles at q = Δp/R, R = 128·μ·L/(π·d⁴). Thick oil
    in a thin hose: the slowest mode decays at R/(2·I) = 16·ν/d² = 100 /s (I = ρL/A), so
    after 0.25 s the flow is within e⁻²⁵ of its end value; 1e-6 allows the records' round-off.
    The inner pressures fall on the straight line between the ends."""
    d, length, nu, n = 0.004, 2.0, 1.0e-4, 6
    values = {"length": length, "diameter": d, "segments": n, "kinematic_viscosity": nu}
    r = simulate(_hose_circuit(values, 2e5, method="rk4", step=1e-5, duration=0.25))
    q_hp = (20e5 - 2e5) * math.pi * d**4 / (128 * RHO * nu * length)
    df = r.to_pandas()
    assert df["hose_flow_lpm"].iloc[-1] / 6e4 == pytest.approx(q_hp, rel=1e-6)
    for j in range(n - 1):
        expected = 20e5 + (2e5 - 20e5) * (j + 1) / n
        assert df[f"hose_pressure{j}_bar"].iloc[-1] * 1e5 == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("n", [1, 4, 25])
def test_hose_modes_are_the_ladders(n):
    """A lossless hose from a held pressure to a closed end is the ladder of N π segments;
    mirrored at the closed end it is a 2N ladder held at both ends, whose modes are
    ω_m = (2·N·c/L)·sin((2m − 1)·π/(4N)), m = 1 … N. The Jacobian (central differences of
    the exact right-hand side, which is linear here: only round-off, ~1e-9 relative) has
    eigenvalues ±i·ω_m; ω_1 tends to the quarter-wave π·c/(2L) as N grows."""
    length, wall = 12.0, 2.0e10
    values = {
        "length": length,
        "diameter": 0.02,
        "segments": n,
        "kinematic_viscosity": 0.0,
        "wall_bulk_modulus": wall,
    }
    cc = build(_hose_circuit(values, None))
    s0 = cc.s0.copy()
    s0[: len(cc.hydraulic)] = 20e5
    s0[cc.soff[1] + n :] = 20e5  # inner pressures at the supply's (any state: it is linear)
    scale = np.where(np.abs(s0) > 1.0, np.abs(s0), 1e-4) * 1e-6
    jac = np.empty((len(s0), len(s0)))
    for i in range(len(s0)):
        e = np.zeros(len(s0))
        e[i] = scale[i]
        jac[:, i] = (
            derivatives_at(0.0, s0 + e, cc.P, cc.net) - derivatives_at(0.0, s0 - e, cc.P, cc.net)
        ) / (2 * scale[i])
    ev = np.linalg.eigvals(jac)
    omega = ev.imag[ev.imag > 1.0]  # one of each ± pair (the held node's is 0)
    c = math.sqrt(1.0 / (1.0 / BETA + 1.0 / wall) / RHO)
    expected = 2 * n * c / length * np.sin((2 * np.arange(1, n + 1) - 1) * math.pi / (4 * n))
    np.testing.assert_allclose(np.sort(omega), expected, rtol=1e-7)
    quarter = math.pi * c / (2 * length)
    assert abs(expected[0] / quarter - 1) <= (math.pi / (4 * n)) ** 2 / 6 * 1.01


def test_hose_energy_balance():
    """The energy a hose absorbs is the change of what it stores, Σ ½·C·p² (ends: C/2) +
    Σ ½·I·q², plus what its friction dissipates, ∫ Σ Δp_f·q dt (turbulent law, a 19 bar step
    into a closed end, thin oil: Re up to 4500). Every step is recorded (1 µs): the
    trapezoid's error on the rings (period 4L/c = 6 ms) is ~(h·ω)² ≈ 1e-8 of the energy; 1e-6
    allows for it."""
    nu = 2e-6
    values = {
        "length": 2.0,
        "diameter": 0.006,
        "segments": 5,
        "friction": "turbulent",
        "kinematic_viscosity": nu,
    }
    circuit = _hose_circuit(values, None, method="rk4", step=1e-6, duration=0.02, record_every=1)
    circuit = circuit.replace(initial={"B": 1e5})
    r = simulate(circuit)
    cc = r.compiled
    n, seg, inertance, compliance = hose_module.segment_constants(cc.P, cc.poff[1])
    so = cc.soff[1]
    q = r.states[:, so : so + n]
    p_in = r.states[:, so + n : so + 2 * n - 1]
    p_a, p_b = r.states[:, cc.hydraulic["A"]], r.states[:, cc.hydraulic["B"]]
    stored = 0.5 * compliance * ((p_in**2).sum(1) + 0.5 * p_a**2 + 0.5 * p_b**2)
    stored += 0.5 * inertance * (q**2).sum(1)
    assert np.abs(q).max() / (math.pi * 0.006**2 / 4) * 0.006 / nu > 2000  # turbulent
    drop = np.vectorize(_pipe.friction_drop)(q, RHO, nu, seg, 0.006, True)
    dissipated = cumulative(r.t, (drop * q).sum(1))
    absorbed = r.energy()["hose_energy_j"]
    assert absorbed > 0.05  # joules: ½·C·Δp² of the hose's 57 cm³ at 19 bar
    assert dissipated[-1] > 0.01 * absorbed
    assert absorbed == pytest.approx(stored[-1] - stored[0] + dissipated[-1], rel=1e-6)
    assert abs(r.energy()["closure_energy_j"]) < 1e-9 * absorbed


# ---------------------------------------------------------------------------------- line ---
def _step_into_line(values, method, duration=0.2, p0=20e5, p1=50e5):
    """A tank stepping p0 → p1 at 1 ms into a line closed at b."""
    comps = (
        ComponentSpec(
            "signal_source",
            "step",
            {"out": "p_set"},
            {"waveform": "steps", "offset": p0},
            {"times": (1e-3,), "values": (p1,)},
        ),
        ComponentSpec("tank", "supply", {"port": "A", "setpoint": "p_set"}),
        ComponentSpec("line", "pipe", {"a": "A", "b": "B"}, values),
    )
    circuit = Circuit("line", comps, method=method, step=1e-5, duration=duration, record_every=1)
    return simulate(circuit.replace(initial={"B": p0}))


@pytest.mark.parametrize("method", ["rk4", "euler"])
def test_line_step_into_a_closed_end(method):
    """A lossless 20 m line at 20 bar, a 50 bar step at end a at 1 ms: the wave reaches the
    closed end b after T = (L − 2ℓ_e)/c, doubles there (p_b → 2·50 − 20 = 80 bar) and p_b
    rings as a square wave between 80 and 20 bar with the period 4·(L − ℓ_e)/c (the end
    volume ℓ_e at b reflects like that much more line; the one at a sits on the held node).
    Tolerances: the arrival within 0.1 ms (the end's lag ℓ_e/c = 38 µs); the plateaus within
    0.1 % (the end lags' reflections ring a few bar for 0.2 ms at each front, 5 ms away from
    where the plateau is read); the period within 2e-4 (crossings interpolated between 10 µs
    records, the history's linear interpolation over Δ = T/253 = 60 µs is symmetric about
    the front). The energy the line absorbs equals its stored energy's change within 0.3 %
    (the history's linear interpolation of w² at the fronts)."""
    length, end = 20.0, 0.05
    r = _step_into_line({"length": length, "diameter": 0.02, "kinematic_viscosity": 0.0}, method)
    t, p = r.t, r.output("B_pressure_bar")
    delay = (length - 2 * end) / SPEED
    period = 4 * (length - end) / SPEED
    up = crossings(t, p, 50.0, True)
    down = crossings(t, p, 50.0, False)
    assert up[0] == pytest.approx(1e-3 + delay, abs=1e-4)
    assert len(up) == 4 and len(down) == 3
    assert np.diff(up) == pytest.approx(period, rel=2e-4)
    assert np.diff(down) == pytest.approx(period, rel=2e-4)
    high = (t > up[0] + 0.005) & (t < down[0] - 0.005)
    low = (t > down[0] + 0.005) & (t < up[1] - 0.005)
    assert np.median(p[high]) == pytest.approx(80.0, rel=1e-3)
    assert np.median(p[low]) == pytest.approx(20.0, rel=1e-3)
    stored, dissipated = line_module.energy_account(r, "pipe")
    absorbed = cumulative(t, r.output("pipe_power_w"))
    assert dissipated[-1] == 0.0
    assert absorbed[-1] > 10.0
    assert stored[-1] - stored[0] == pytest.approx(absorbed[-1], rel=3e-3)


def test_line_friction_drop_is_steady():
    """With its laminar friction lumped in series at the ends (R/2 each), a line carrying
    q = Δp/R between two tanks, R = 128·μ·L/(π·d⁴) (Hagen–Poiseuille), is in a steady state:
    after many round trips the flow is still q (to 1e-9: round-off)."""
    d, length, nu = 0.01, 10.0, 32e-6
    q = 10e5 * math.pi * d**4 / (128 * RHO * nu * length)
    comps = (
        ComponentSpec("tank", "supply", {"port": "A"}, {"pressure": 20e5}),
        ComponentSpec(
            "line",
            "pipe",
            {"a": "A", "b": "B"},
            {"length": length, "diameter": d, "kinematic_viscosity": nu, "initial_flow": q},
        ),
        ComponentSpec("tank", "drain", {"port": "B"}, {"pressure": 10e5}),
    )
    r = simulate(Circuit("steady", comps, method="rk4", step=1e-5, duration=0.1, record_every=100))
    np.testing.assert_allclose(r.output("pipe_flow_lpm") / 6e4, q, rtol=1e-9)


def test_line_history_length_does_not_move_the_waves():
    """The delay is the line's, not the history's: with 16 samples instead of 256 the fronts
    are smoothed over Δ = T/13 = 1.2 ms instead of 60 µs, and where a front's crossing falls
    then depends on where it falls between samples; the ring period stays within 2e-3 (a
    tenth of Δ/period; measured 1e-3 at 8 and 16 samples, 1e-4 at 256)."""
    values = {"length": 20.0, "diameter": 0.02, "kinematic_viscosity": 0.0}
    periods = []
    for n in (16, 256):
        r = _step_into_line({**values, "buffer_length": n}, "rk4", duration=0.14)
        up = crossings(r.t, r.output("B_pressure_bar"), 50.0, True)
        periods.append(up[1] - up[0])
    assert periods[0] == pytest.approx(periods[1], rel=2e-3)
    assert periods[1] == pytest.approx(4 * (20.0 - 0.05) / SPEED, rel=2e-4)
