"""4/3 directional spool valve: four turbulent metering edges, closed or open centre, with
the spool driven by a demand signal (a controller's output, or a direct open-loop input).

    q_PA = k_PA·(x_v − u_PA)·√(p_P − p_A),   q_AT = k_AT·(−x_v − u_AT)·√(p_A − p_T)
    q_PB = k_PB·(−x_v − u_PB)·√(p_P − p_B),  q_BT = k_BT·(x_v − u_BT)·√(p_B − p_T)
    q_PT = k·(o_c − |x_v|)·√(p_P − p_T)                          (open centre only)
    k = C_d·w·√(2/ρ),   w = π·d·f,   k_e = r_e·k,   u_e = u + Δu_e

each edge closed where its opening is ≤ 0 (u: the overlap, negative for an underlap, and
Δu_e an edge's own above it; r_e an edge's share of the ported width, 1 unless the edges
differ; o_c the open centre's P→T opening at null). √Δp is regularised below the transition pressure
(`hydroarm.core.components.spool_valve_flows`; Merritt 1967 §5.2, eq. 3-7). The spool
follows the demand u_d, limited to ±x_max, at once (``dynamics = "none"``), with a first-
order lag τ, or as a second-order system (ω_n, ζ) (Merritt 1967 §5.6: the valve's dynamics
as a low-order transfer function).
"""

from __future__ import annotations

import math

from ...components import edge_flow, spool_valve_flows
from ..declare import Component, Derived, Energy, Param
from ..laws import kernel
from ._spool import (
    DYNAMICS,
    INITIAL_SPOOL,
    INITIAL_SPOOL_VELOCITY,
    INPUTS,
    PORTS,
    STATES,
    valve_spool,
    valve_spool_projection,
)

EDGES = ("pa", "at", "pb", "bt")  # the metering edges P→A, A→T, P→B, B→T


def flow_coefficient(discharge_coefficient, spool_diameter, circumference_fraction, density):
    """k = C_d·w·√(2/ρ), w = π·d·f [m² s⁻¹ Pa⁻¹ᐟ²]: each metering edge's."""
    return (
        discharge_coefficient
        * math.pi
        * spool_diameter
        * circumference_fraction
        * math.sqrt(2.0 / density)
    )


DECLARATION = Component(
    type="valve_4_3",
    summary="a 4/3 spool valve (closed or open centre) driven by a spool demand signal",
    parameters=(
        Param("spool_diameter", "m", None, "> 0", "spool diameter d"),
        Param("circumference_fraction", "", 1.0, "in [0, 1]", "f: the ported share of π·d"),
        Param("discharge_coefficient", "", 0.67, "> 0", "C_d of the edges"),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density"),
        Param("overlap", "m", 0.0, "", "u on each edge (negative: underlap)"),
        *(
            Param(f"width_ratio_{e}", "", 1.0, ">= 0", f"r of edge {e.upper()}: its k over k")
            for e in EDGES
        ),
        *(
            Param(f"extra_overlap_{e}", "m", 0.0, "", f"Δu of edge {e.upper()}, added to u")
            for e in EDGES
        ),
        Param("centre_opening", "m", 0.0, ">= 0", "P→T opening at null (0: closed centre)"),
        Param("max_stroke", "m", None, "> 0", "largest spool stroke |x_v|"),
        *DYNAMICS,
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
        Param("demand", "m", 0.0, "", "spool demand when no signal is connected"),
        INITIAL_SPOOL,
        INITIAL_SPOOL_VELOCITY,
    ),
    states=STATES,
    ports=PORTS,
    source="Merritt 1967 §5.2 and eq. 3-7 (metering edges), §5.6 (spool dynamics)",
    flow_port="P",
    inputs=INPUTS,
    energies=(Energy("throttle", "dissipated in the metering edges (and the open centre)"),),
    derived=(Derived("flow_coefficient", "m**2/s/Pa**0.5", flow_coefficient, "k of each edge"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def _spool_args(po):
    return po + par.max_stroke, po + par.dynamics, po + par.demand


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    lim, dyn, dem = _spool_args(po)
    x_v = valve_spool(P, lim, dyn, dem, port[pt.command], sig, s, d, so + st.spool)
    k = P[po + par.flow_coefficient]
    lap = P[po + par.overlap]
    p_p = pn[port[pt.P]]
    p_t = pn[port[pt.T]]
    dp_t = P[po + par.transition_pressure]
    q_a, q_b, q_p, loss = spool_valve_flows(
        x_v,
        p_p,
        p_t,
        pn[port[pt.A]],
        pn[port[pt.B]],
        k * P[po + par.width_ratio_pa],
        k * P[po + par.width_ratio_at],
        k * P[po + par.width_ratio_pb],
        k * P[po + par.width_ratio_bt],
        lap + P[po + par.extra_overlap_pa],
        lap + P[po + par.extra_overlap_at],
        lap + P[po + par.extra_overlap_pb],
        lap + P[po + par.extra_overlap_bt],
        dp_t,
    )
    q_pt = edge_flow(k, P[po + par.centre_opening] - abs(x_v), p_p - p_t, dp_t)
    thr[c, pt.P] = -(q_p + q_pt)
    thr[c, pt.T] = q_p + q_pt - q_a - q_b
    thr[c, pt.A] = q_a
    thr[c, pt.B] = q_b


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    lim, dyn, dem = _spool_args(po)
    valve_spool_projection(P, lim, dyn, dem, port[pt.command], sig, s, so + st.spool)
