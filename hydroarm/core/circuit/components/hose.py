"""Hose: a hose or pipe as a chain of N lumped segments, each a resistance and an inertance
in series, with the compliance of each segment split between its two ends (π segments):

    node:      a ── R,I ── p_1 ── R,I ── p_2 ··· p_N−1 ── R,I ── b
    I·q̇_j  = p_j−1 − p_j − Δp_f(q_j),     j = 1 … N   (p_0 = p_a, p_N = p_b)
    C·ṗ_j  = q_j − q_j+1,                 j = 1 … N−1
    C/2 at a and at b (the ports are compliant); q into a's node −q_1, into b's q_N

per segment of length ℓ = L/N and area A = π·d²/4:

    I = ρ·ℓ/A                       inertance
    C = A·ℓ/β_e,  1/β_e = 1/β + 1/β_w   compliance, the wall's bulk modulus β_w in series
    Δp_f = 128·μ·ℓ·q/(π·d⁴)         laminar friction (Hagen–Poiseuille, μ = ρ·ν), or the larger
                                    of it and Blasius's turbulent drop (``friction = "turbulent"``)

(Watton 2009, *Fundamentals of Fluid Power Control*, the chapter on pipelines: the lumped
π-segment line; Hopsan's HydraulicLaminarOrifice–HydraulicVolume chain; the shared laws:
`_pipe`). Its undamped modes are those of the mirrored ladder: with a closed end and a
held one, ω_m = (2·N·c/L)·sin((2m − 1)·π/(4·N)), c = √(β_e/ρ) — the quarter-wave frequency
π·c/(2·L) of the continuous line to within (π/(4N))²/6. The inner pressures start on the
straight line between the end pressures, the flows at ``initial_flow`` (a steady laminar
flow is then a steady state). The inner nodes have no cavitation floor (column separation is
not modelled).
"""

from __future__ import annotations

from ..declare import HYDRAULIC, Component, Param, Port, State
from ..laws import kernel
from ._pipe import friction_drop, line_bulk_modulus, pipe_area

DECLARATION = Component(
    type="hose",
    summary="a hose or pipe as N lumped segments (resistance, inertance, compliance)",
    parameters=(
        Param("length", "m", None, "> 0", "length L"),
        Param("diameter", "m", None, "> 0", "inner diameter d"),
        Param("segments", "", 10, "integer in [1, 10000]", "number of segments N", sweepable=False),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density ρ (mineral oil)"),
        Param(
            "kinematic_viscosity",
            "m**2/s",
            32.0e-6,
            ">= 0",
            "ν (ISO VG 32 at 40 °C: 32 mm²/s; 0: no friction)",
        ),
        Param("bulk_modulus", "Pa", 1.5e9, "> 0", "oil bulk modulus β"),
        Param(
            "wall_bulk_modulus", "Pa", float("inf"), "> 0", "β_w: E·s/d of a thin wall; ∞: rigid"
        ),
        Param(
            "friction",
            "",
            "laminar",
            "",
            "friction law",
            ("laminar", "turbulent"),
            sweepable=False,
        ),
        Param("initial_flow", "m**3/s", 0.0, "", "flow a → b in every segment at t = 0"),
    ),
    states=(
        State("flow", "m**3/s", 1.0e-4, "initial_flow", "q_1 … q_N, a → b", count="segments"),
        State("pressure", "Pa", 1.0e7, 0.0, "inner pressures p_1 … p_N−1", count="segments - 1"),
    ),
    ports=(
        Port("a", HYDRAULIC, "end a (positive flow a → b)", compliant=True),
        Port("b", HYDRAULIC, "end b", compliant=True),
    ),
    source=(
        "Watton 2009, Fundamentals of Fluid Power Control (lumped π-segment pipeline); "
        "Hagen–Poiseuille and Blasius friction; Hopsan HydraulicLaminarOrifice/HydraulicVolume "
        "chain; ν default: ISO 3448 VG 32"
    ),
    flow_port="a",
)
par, st, pt = DECLARATION.indices()
LAMINAR, TURBULENT = range(2)


@kernel
def segment_constants(P, po):
    """(N, segment length ℓ, inertance I, compliance C) of the hose's segments."""
    n = int(P[po + par.segments])
    seg = P[po + par.length] / n
    area = pipe_area(P[po + par.diameter])
    beta = line_bulk_modulus(P[po + par.bulk_modulus], P[po + par.wall_bulk_modulus])
    return n, seg, P[po + par.density] * seg / area, area * seg / beta


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    n, seg, inertance, compliance = segment_constants(P, po)
    rho = P[po + par.density]
    nu = P[po + par.kinematic_viscosity]
    dia = P[po + par.diameter]
    turbulent = P[po + par.friction] == TURBULENT
    qo = so + st.flow
    pr = qo + n  # the inner pressures follow the flows
    p_prev = pn[port[pt.a]]
    for j in range(n):
        p_next = pn[port[pt.b]] if j == n - 1 else s[pr + j]
        q = s[qo + j]
        d[qo + j] = (p_prev - p_next - friction_drop(q, rho, nu, seg, dia, turbulent)) / inertance
        p_prev = p_next
    for j in range(n - 1):
        d[pr + j] = (s[qo + j] - s[qo + j + 1]) / compliance
    thr[c, pt.a] = -s[qo]
    thr[c, pt.b] = s[qo + n - 1]
    cap[c, pt.a] = 0.5 * compliance
    cap[c, pt.b] = 0.5 * compliance


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    if h != 0.0:
        return
    n = int(P[po + par.segments])  # at the start: the inner pressures between the ends'
    p_a = s[port[pt.a]]
    p_b = s[port[pt.b]]
    for j in range(n - 1):
        s[so + st.flow + n + j] = p_a + (p_b - p_a) * (j + 1) / n
