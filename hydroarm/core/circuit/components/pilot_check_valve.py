"""Pilot-operated check valve: free flow inlet → outlet above the cracking pressure; the
reverse flow outlet → inlet (a load held at the outlet) only when the pilot opens it.

Force balance on the poppet (seat area A_s, spring p_c·A_s) and its pilot piston (area
A_x = φ·A_s, its back side drained to the inlet: an internally drained valve, so that only
pressure differences appear), the pilot piston only pushing::

    e = (p_in − p_out) + φ·max(p_pilot − p_in, 0) − p_c
    x* = clip(e/Δp_o, 0, 1),   τ·ẋ = x* − x  (τ = 0: x = x*)
    q = k·x·√(p_in − p_out),   k = q_nom/√Δp_nom                (inlet → outlet positive)

With the pilot at the inlet's pressure this is a plain check valve cracking at p_c; held
by a load at the outlet (p_out > p_in) it opens when p_pilot > p_in + (p_out − p_in + p_c)/φ.
Once open the poppet passes flow either way (√ signed, regularised below the transition
pressure). The pilot port draws no flow (its piston's displacement is neglected) and adds
no compliance: the pilot node's compliance comes from what else is joined to it.

Hopsan HydraulicPilotControlledCheckValve (opens when p_1 − p_2 + φ·p_pilot > p_f, then
q = K_s·√(p_1 − p_2)), its on/off switch made linear over the opening band Δp_o and the
pilot taken against the inlet (the valve's internal drain); the opening and the optional
poppet lag are the shared laws of the pressure valves (`_valves`).
"""

from __future__ import annotations

from ...components import edge_flow
from ..declare import HYDRAULIC, Component, Param, Port, State
from ..laws import kernel
from ._valves import band_opening, lagged_opening, project_opening, rated_coefficient

DECLARATION = Component(
    type="pilot_check_valve",
    summary="a pilot-operated check valve (free flow inlet → outlet, pilot opens it back)",
    parameters=(
        Param("cracking_pressure", "Pa", 1.0e5, ">= 0", "p_c, the free-flow cracking drop"),
        Param("pilot_ratio", "", 3.5, "> 0", "φ = A_pilot/A_seat"),
        Param("opening_range", "Pa", 1.0e5, "> 0", "Δp_o: cracked to fully open"),
        Param("nominal_flow", "m**3/s", 5.0e-4, "> 0", "q_nom, fully open at Δp_nom"),
        Param("nominal_pressure_drop", "Pa", 1.0e6, "> 0", "Δp_nom of the rated flow"),
        Param("time_constant", "s", 0.0, ">= 0", "poppet lag τ (0: static)"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(State("opening", "", 1.0, 0.0, "poppet opening x in [0, 1]"),),
    ports=(
        Port("inlet", HYDRAULIC, "free-flow inlet (the directional valve's side)"),
        Port("outlet", HYDRAULIC, "outlet (the load's side)"),
        Port("pilot", HYDRAULIC, "pilot pressure (no flow)"),
    ),
    source=(
        "Hopsan HydraulicPilotControlledCheckValve (φ = 3.5, p_f = 1 bar, K_s = 5e-7 "
        "m³/s/√Pa: q_nom = 0.5 L/s at 10 bar), made linear over Δp_o; internal pilot drain"
    ),
    flow_port="inlet",
)
par, st, pt = DECLARATION.indices()


@kernel
def _static(P, po, p_in, p_out, p_pilot):
    assist = P[po + par.pilot_ratio] * max(p_pilot - p_in, 0.0)
    excess = p_in - p_out + assist - P[po + par.cracking_pressure]
    return band_opening(excess, P[po + par.opening_range])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_in = pn[port[pt.inlet]]
    p_out = pn[port[pt.outlet]]
    x_star = _static(P, po, p_in, p_out, pn[port[pt.pilot]])
    x = lagged_opening(x_star, s, d, so + st.opening, P[po + par.time_constant])
    k = rated_coefficient(P[po + par.nominal_flow], P[po + par.nominal_pressure_drop])
    q = edge_flow(k, x, p_in - p_out, P[po + par.transition_pressure])
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    x_star = _static(P, po, s[port[pt.inlet]], s[port[pt.outlet]], s[port[pt.pilot]])
    project_opening(x_star, s, so + st.opening, P[po + par.time_constant])
