"""Counterbalance (over-centre, motion control) valve: a check valve giving free flow from
the directional valve to the load, in parallel with a pilot-assisted relief valve metering
the flow from the load back to the directional valve.

Relief stage (load → valve), its spring chamber referenced to the valve port (the standard,
non-vented cartridge)::

    e = (p_load − p_valve) + φ·(p_pilot − p_valve) − p_set
    x* = clip(e/Δp_o, 0, 1),   τ·ẋ = x* − x  (τ = 0: x = x*)
    q_r = k·x·√(p_load − p_valve),        k = q_nom/√Δp_nom

so it cracks at p_load = p_set + p_valve + φ·(p_valve − p_pilot): the pilot lowers the
effective setting at the pilot ratio φ, and back pressure at the valve port adds to it at
1 + φ (Sun Hydraulics, CBCA/CBEA technical notes). Check stage (valve → load)::

    x_c = clip((p_valve − p_load − p_cc)/Δp_oc, 0, 1),   q_c = k_c·x_c·√(p_valve − p_load)

The flow into the load port is q_c − q_r; √ signed and regularised below the transition
pressure (`hydroarm.core.components.edge_flow`). The pilot port draws no flow and
adds no compliance. Sizing (Sun): the setting at least 1.3 × the largest load-induced
pressure, so that the valve holds the load with the pilot vented; lowering, the pilot
pressure needed is (p_set − p_load)/φ above the valve port's.

Hopsan HydraulicOverCenterValve (x = (p_1 − p_ref + a_ratio·p_control)/(C_s + C_f·Δp),
first-order spool), taken without the flow-force term (linear over the band Δp_o =
q_nom/k_cs) and with the back-pressure reference of the Sun cartridge; the opening laws
are those of the pressure valves (`_valves`).
"""

from __future__ import annotations

from ...components import edge_flow
from ..declare import HYDRAULIC, Component, Param, Port, State
from ..laws import kernel
from ._valves import band_opening, lagged_opening, project_opening, rated_coefficient

DECLARATION = Component(
    type="counterbalance_valve",
    summary="a counterbalance (over-centre) valve: integral check and pilot-assisted relief",
    parameters=(
        Param("setting", "Pa", None, "> 0", "p_set, relief setting (≥ 1.3 × load pressure)"),
        Param("pilot_ratio", "", 3.0, "> 0", "φ, pilot ratio"),
        Param("opening_range", "Pa", 1.0e5, "> 0", "Δp_o: relief cracked to fully open"),
        Param("nominal_flow", "m**3/s", 1.0e-3, "> 0", "q_nom, relief fully open at Δp_nom"),
        Param("nominal_pressure_drop", "Pa", 7.0e6, "> 0", "Δp_nom of the rated flows"),
        Param("check_cracking_pressure", "Pa", 1.7e5, ">= 0", "p_cc, the check's cracking drop"),
        Param("check_opening_range", "Pa", 1.0e5, "> 0", "Δp_oc: check cracked to fully open"),
        Param("check_nominal_flow", "m**3/s", 1.0e-3, "> 0", "check fully open at Δp_nom"),
        Param("time_constant", "s", 0.0, ">= 0", "relief spool lag τ (0: static)"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(State("opening", "", 1.0, 0.0, "relief stage opening x in [0, 1]"),),
    ports=(
        Port("load", HYDRAULIC, "port 1: the load (cylinder chamber)"),
        Port("valve", HYDRAULIC, "port 2: the directional valve's line"),
        Port("pilot", HYDRAULIC, "port 3: pilot pressure (no flow)"),
    ),
    source=(
        "Hopsan HydraulicOverCenterValve (Δp_o = q_nom/k_cs = 1 bar, q_nom = 1 L/s at "
        "70 bar) and Sun Hydraulics counterbalance cartridges (3:1 pilot ratio, 1.7 bar "
        "check, back pressure additive at 1 + φ, setting ≥ 1.3 × load pressure)"
    ),
    flow_port="load",
)
par, st, pt = DECLARATION.indices()


@kernel
def _static(P, po, p_load, p_valve, p_pilot):
    excess = p_load - p_valve + P[po + par.pilot_ratio] * (p_pilot - p_valve) - P[po + par.setting]
    return band_opening(excess, P[po + par.opening_range])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_load = pn[port[pt.load]]
    p_valve = pn[port[pt.valve]]
    x_star = _static(P, po, p_load, p_valve, pn[port[pt.pilot]])
    x = lagged_opening(x_star, s, d, so + st.opening, P[po + par.time_constant])
    drop = P[po + par.nominal_pressure_drop]
    dp_t = P[po + par.transition_pressure]
    q_r = edge_flow(rated_coefficient(P[po + par.nominal_flow], drop), x, p_load - p_valve, dp_t)
    x_c = band_opening(
        p_valve - p_load - P[po + par.check_cracking_pressure], P[po + par.check_opening_range]
    )
    k_c = rated_coefficient(P[po + par.check_nominal_flow], drop)
    q_c = edge_flow(k_c, x_c, p_valve - p_load, dp_t)
    thr[c, pt.load] = q_c - q_r
    thr[c, pt.valve] = q_r - q_c


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    x_star = _static(P, po, s[port[pt.load]], s[port[pt.valve]], s[port[pt.pilot]])
    project_opening(x_star, s, so + st.opening, P[po + par.time_constant])
