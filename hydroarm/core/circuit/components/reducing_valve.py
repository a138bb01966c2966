"""Pressure-reducing valve (direct-acting, two-way): throttles the flow from the inlet so as
to hold the outlet near its set pressure.

The spool, pushed shut by the outlet pressure against its spring, is open below the set
pressure and closes over the regulation band Δp_r up to it::

    x* = clip((p_set − p_out)/Δp_r, 0, 1),   τ·ẋ = x* − x  (τ = 0: x = x*)
    q = k·x·√(p_in − p_out),                 k = q_nom/√Δp_nom     (inlet → outlet positive)

so the outlet settles in [p_set − Δp_r, p_set] whatever the inlet pressure above it and the
flow drawn, within the valve's capacity (the outlet pressure p_out solves
k·x*(p_out)·√(p_in − p_out) = q_load). Open, the spool passes flow either way (√ signed,
regularised below the transition pressure); a two-way valve does not relieve an outlet
pushed above p_set (a three-way reducing-relieving valve would: add a relief valve).

Hopsan HydraulicPressureReducingValve (x = (p_ref − p_2)/(C_s + C_f·Δp), first-order
spool) without the flow-force term, so that Δp_r = q_nom/k_cs (1 bar with Hopsan's
k_cs = 1e-8 m³/s/Pa and q_nom = 1 L/s at 70 bar); the opening laws are those of the
pressure valves (`_valves`).
"""

from __future__ import annotations

from ...components import edge_flow
from ..declare import HYDRAULIC, Component, Param, Port, State
from ..laws import kernel
from ._valves import band_opening, lagged_opening, project_opening, rated_coefficient

DECLARATION = Component(
    type="reducing_valve",
    summary="a direct-acting pressure-reducing valve (holds its outlet near p_set)",
    parameters=(
        Param("set_pressure", "Pa", None, "> 0", "p_set, outlet pressure at which it shuts"),
        Param("regulation_band", "Pa", 1.0e5, "> 0", "Δp_r: fully open Δp_r below p_set"),
        Param("nominal_flow", "m**3/s", 1.0e-3, "> 0", "q_nom, fully open at Δp_nom"),
        Param("nominal_pressure_drop", "Pa", 7.0e6, "> 0", "Δp_nom of the rated flow"),
        Param("time_constant", "s", 0.0, ">= 0", "spool lag τ (0: static)"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(State("opening", "", 1.0, 0.0, "spool opening x in [0, 1]"),),
    ports=(
        Port("inlet", HYDRAULIC, "supply (high pressure)"),
        Port("outlet", HYDRAULIC, "reduced pressure"),
    ),
    source="Hopsan HydraulicPressureReducingValve (Krus 1990), defaults as there",
    flow_port="inlet",
)
par, st, pt = DECLARATION.indices()


@kernel
def _static(P, po, p_out):
    return band_opening(P[po + par.set_pressure] - p_out, P[po + par.regulation_band])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_in = pn[port[pt.inlet]]
    p_out = pn[port[pt.outlet]]
    x = lagged_opening(_static(P, po, p_out), s, d, so + st.opening, P[po + par.time_constant])
    k = rated_coefficient(P[po + par.nominal_flow], P[po + par.nominal_pressure_drop])
    q = edge_flow(k, x, p_in - p_out, P[po + par.transition_pressure])
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    x_star = _static(P, po, s[port[pt.outlet]])
    project_opening(x_star, s, so + st.opening, P[po + par.time_constant])
