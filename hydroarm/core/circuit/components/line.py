"""Line: a pipe with wave propagation, the transmission-line model (TLM) of Krus, Jansson,
Palmberg and Weddfelt 1990 ("Distributed simulation of hydromechanical systems"; Hopsan's
HydraulicTLMlossless and HydraulicTLMRlineR), the method of characteristics of a lossless
line (Wylie and Streeter 1993, *Fluid Transients in Systems*, ch. 2–3).

A wave crosses the line in the delay T = L′/c; at each end the line is its characteristic
impedance Z behind the wave arriving from the other end:

    p′_a = c_a + Z·q_a,     c_a(t) = w_b(t − T),     w_b = p′_b + Z·q_b = c_b + 2·Z·q_b
    p′_b = c_b + Z·q_b,     c_b(t) = w_a(t − T),     w_a = p′_a + Z·q_a = c_a + 2·Z·q_a
    c = √(β_e/ρ),   Z = ρ·c/A,   A = π·d²/4,   1/β_e = 1/β + 1/β_w

(q_a, q_b: the flows into the line at its ends; p′ the pressures at the ends of the TLM
section). Between each port's node and its TLM end sits half the line's laminar resistance,
R/2 with R = 128·μ·L/(π·d⁴) (the friction lumped at the ends as in HydraulicTLMRlineR, but
in series, so that a steady flow drops R·q along the line), and at the node the compliance
of an end piece of length ℓ_e, C_e = A·ℓ_e/β_e; the TLM spans the rest, L′ = L − 2·ℓ_e,
so that the line's whole volume is there (ℓ_e is at most L/4). Each port is then

    q into the node = (c − p)/(Z + R/2),     compliance C_e,

a lag of time constant (Z + R/2)·C_e ≈ ℓ_e/c towards the arriving wave: keep ℓ_e/c above
the solver's step (stability of the explicit steppers) and well below the times of
interest. A closed end with C_e reflects like a line ℓ_e longer, so a line from a held
pressure to a closed end rings with the period 4·(L − ℓ_e)/c.

The waves leaving each end, w_a and w_b, are kept among the line's own states: the newest
(at the last step's end) and two ring buffers of ``buffer_length`` samples spaced
Δ = T/(buffer_length − 3), written after each step (linear in time between the step's ends)
and read at t − T by linear interpolation. A Runge–Kutta stage at t + c_j·h reads t + c_j·h
− T, in the past while T ≥ h; a delay shorter than the step reads the newest wave (a delay
of one step, as in Hopsan). At the start the line carries ``initial_flow`` at the mean of
its end pressures (a steady state where they differ by R·q; any other difference starts a
wave from each end).
"""

from __future__ import annotations

import math

import numpy as np

from ..declare import HYDRAULIC, Component, Param, Port, State
from ..laws import kernel
from ._pipe import laminar_resistance, line_bulk_modulus, pipe_area, wave_speed

DECLARATION = Component(
    type="line",
    summary="a pipe with wave propagation (transmission-line model, delays of L/c)",
    parameters=(
        Param("length", "m", None, "> 0", "length L"),
        Param("diameter", "m", None, "> 0", "inner diameter d"),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density ρ (mineral oil)"),
        Param(
            "kinematic_viscosity",
            "m**2/s",
            32.0e-6,
            ">= 0",
            "ν (ISO VG 32 at 40 °C: 32 mm²/s; 0: lossless)",
        ),
        Param("bulk_modulus", "Pa", 1.5e9, "> 0", "oil bulk modulus β"),
        Param(
            "wall_bulk_modulus", "Pa", float("inf"), "> 0", "β_w: E·s/d of a thin wall; ∞: rigid"
        ),
        Param("end_length", "m", 0.05, "> 0", "ℓ_e: the length lumped at each end's node"),
        Param("initial_flow", "m**3/s", 0.0, "", "steady flow a → b at t = 0"),
        Param(
            "buffer_length",
            "",
            256,
            "integer in [8, 100000]",
            "samples of each end's wave history over the delay",
            sweepable=False,
        ),
    ),
    states=(
        State("time", "s", 1.0, 0.0, "time of the newest wave (the last step's end)", held=True),
        State("wave_a", "Pa", 1.0e7, 0.0, "w_a = p′_a + Z·q_a, the wave leaving end a", held=True),
        State("wave_b", "Pa", 1.0e7, 0.0, "w_b, the wave leaving end b", held=True),
        State("history_a", "Pa", 1.0e7, 0.0, "w_a at times k·Δ (a ring)", "buffer_length", True),
        State("history_b", "Pa", 1.0e7, 0.0, "w_b at times k·Δ (a ring)", "buffer_length", True),
    ),
    ports=(
        Port("a", HYDRAULIC, "end a (positive flow a → b)", compliant=True),
        Port("b", HYDRAULIC, "end b", compliant=True),
    ),
    source=(
        "Krus et al. 1990 (TLM); Hopsan HydraulicTLMlossless, HydraulicTLMRlineR; "
        "Wylie and Streeter 1993 (characteristics); friction: Hagen–Poiseuille; "
        "ν default: ISO 3448 VG 32"
    ),
    flow_port="a",
)
par, st, pt = DECLARATION.indices()
N_SCALAR = 3  # the states before the histories


@kernel
def line_constants(P, po):
    """(Z, R/2, delay T, C_e, sample spacing Δ, buffer length n) of the line."""
    length = P[po + par.length]
    dia = P[po + par.diameter]
    rho = P[po + par.density]
    area = pipe_area(dia)
    beta = line_bulk_modulus(P[po + par.bulk_modulus], P[po + par.wall_bulk_modulus])
    speed = wave_speed(beta, rho)
    end = min(P[po + par.end_length], 0.25 * length)
    delay = (length - 2.0 * end) / speed
    n = int(P[po + par.buffer_length])
    r_half = 0.5 * laminar_resistance(rho, P[po + par.kinematic_viscosity], length, dia)
    return rho * speed / area, r_half, delay, area * end / beta, delay / (n - 3), n


@kernel
def wave_at(s, h0, n, spacing, t_new, w_new, tau):
    """The wave of the history starting at s[h0] (n samples spaced Δ, newest value w_new at
    t_new) at the time tau, linear between samples; the newest value beyond t_new."""
    if tau >= t_new:
        return w_new
    k = math.floor(tau / spacing)
    t0 = k * spacing
    v0 = s[h0 + k % n]
    if k + 1 <= math.floor(t_new / spacing):
        v1 = s[h0 + (k + 1) % n]
        t1 = t0 + spacing
    else:
        v1 = w_new
        t1 = t_new
    if t1 <= t0:
        return v1
    return v0 + (v1 - v0) * (tau - t0) / (t1 - t0)


@kernel
def arriving(P, po, s, so, t):
    """(c_a, c_b): the waves arriving at the ends at time t."""
    z, r_half, delay, c_end, spacing, n = line_constants(P, po)
    ha = so + N_SCALAR
    t_new = s[so + st.time]
    c_a = wave_at(s, ha + n, n, spacing, t_new, s[so + st.wave_b], t - delay)
    c_b = wave_at(s, ha, n, spacing, t_new, s[so + st.wave_a], t - delay)
    return c_a, c_b


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    z, r_half, delay, c_end, spacing, n = line_constants(P, po)
    c_a, c_b = arriving(P, po, s, so, t)
    thr[c, pt.a] = (c_a - pn[port[pt.a]]) / (z + r_half)
    thr[c, pt.b] = (c_b - pn[port[pt.b]]) / (z + r_half)
    cap[c, pt.a] = c_end
    cap[c, pt.b] = c_end
    for i in range(N_SCALAR + 2 * n):  # the history changes only in project
        d[so + i] = 0.0


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    z, r_half, delay, c_end, spacing, n = line_constants(P, po)
    ha = so + N_SCALAR
    hb = ha + n
    p_a = s[port[pt.a]]
    p_b = s[port[pt.b]]
    if h == 0.0:  # the start: a steady flow q0 at the ends' mean pressure, all the way back
        q0 = P[po + par.initial_flow]
        w_a = 0.5 * (p_a + p_b) + z * q0
        w_b = 0.5 * (p_a + p_b) - z * q0
        for i in range(n):
            s[ha + i] = w_a
            s[hb + i] = w_b
    else:
        c_a, c_b = arriving(P, po, s, so, t)
        w_a = c_a + 2.0 * z * (p_a - c_a) / (z + r_half)
        w_b = c_b + 2.0 * z * (p_b - c_b) / (z + r_half)
        t_old = s[so + st.time]
        wa_old = s[so + st.wave_a]
        wb_old = s[so + st.wave_b]
        for k in range(math.floor(t_old / spacing) + 1, math.floor(t / spacing) + 1):
            f = (k * spacing - t_old) / (t - t_old)
            s[ha + k % n] = wa_old + f * (w_a - wa_old)
            s[hb + k % n] = wb_old + f * (w_b - wb_old)
    s[so + st.time] = t
    s[so + st.wave_a] = w_a
    s[so + st.wave_b] = w_b


@kernel
def _square_integral(s, h0, n, spacing, t_new, w_new, t0):
    """∫ w² dτ over [t0, t_new] of a history read as `wave_at` reads it (exact: w is
    linear between the samples and from the newest sample to t_new)."""
    total = 0.0
    k_last = math.floor(t_new / spacing)
    for k in range(math.floor(t0 / spacing), k_last + 1):
        a = max(k * spacing, t0)
        b = t_new if k == k_last else min((k + 1) * spacing, t_new)
        if b > a:
            va = wave_at(s, h0, n, spacing, t_new, w_new, a)
            vb = wave_at(s, h0, n, spacing, t_new, w_new, b)
            total += (b - a) * (va * va + va * vb + vb * vb) / 3.0
    return total


@kernel
def wave_energy(P, po, s, so):
    """Energy [J] of the waves in flight in the TLM section at the state s (pressures from
    0 Pa): ∫ (w_a² + w_b²) dτ / (4·Z) over the last delay T; with the end volumes' ½·C_e·p²
    it is the energy the line holds, so that the energy it absorbs is its change plus the
    end resistances' dissipation R/2·(q_a² + q_b²) (p′·q = (w² − c²)/(4·Z) at each end)."""
    z, r_half, delay, c_end, spacing, n = line_constants(P, po)
    t_new = s[so + st.time]
    ha = so + N_SCALAR
    e_a = _square_integral(s, ha, n, spacing, t_new, s[so + st.wave_a], t_new - delay)
    e_b = _square_integral(s, ha + n, n, spacing, t_new, s[so + st.wave_b], t_new - delay)
    return (e_a + e_b) / (4.0 * z)


def energy_account(result, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(stored, dissipated) [J] of the line ``name`` at every record of a circuit's result:
    what it holds (`wave_energy` and the end volumes' ½·C_e·p²) and what its friction
    has dissipated since the start (∫ R/2·(q_a² + q_b²) dt, trapezoid over the records). The
    energy it absorbed, ``result.component_energies()[name]``, is stored[−1] − stored[0] +
    dissipated[−1] to the records' trapezoid error and the history's interpolation."""
    cc = result.compiled
    ci = [c.name for c in cc.circuit.components].index(name)
    so, po = int(cc.soff[ci]), int(cc.poff[ci])
    z, r_half, _, c_end, _, _ = line_constants(cc.P, po)
    ports = cc.circuit.components[ci].ports
    ia, ib = cc.hydraulic[ports["a"]], cc.hydraulic[ports["b"]]
    stored = np.empty(len(result.t))
    loss = np.empty(len(result.t))
    for i, (t, s) in enumerate(zip(result.t, result.states, strict=True)):
        stored[i] = wave_energy(cc.P, po, s, so) + 0.5 * c_end * (s[ia] ** 2 + s[ib] ** 2)
        c_a, c_b = arriving(cc.P, po, s, so, t)
        loss[i] = r_half * ((s[ia] - c_a) ** 2 + (s[ib] - c_b) ** 2) / (z + r_half) ** 2
    steps = 0.5 * (loss[1:] + loss[:-1]) * np.diff(result.t)
    return stored, np.concatenate([[0.0], np.cumsum(steps)])
