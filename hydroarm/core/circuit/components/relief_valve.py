"""Relief valve: opens from inlet to outlet above its cracking pressure, with an optional
first-order poppet and hysteresis.

Static flow coefficient (Hopsan's HydraulicPressureReliefValve, Krus 1990, in continuous
time; `hydroarm.core.components.relief_static_opening`)::

    x* = clip((p − p_c)/(C_s + (p − p_out)·C_f), 0, x_max),  q = x·√(p − p_out)
    C_s = √p_nom/k_cs,   C_f = 1/(k_cf·√p_nom),   x_max = q_nom/√p_nom

with k_cs and k_cf the steady pressure-flow slopes of the spring and the flow forces at the
nominal drop p_nom (Hopsan's defaults: 1e-8 m³/s/Pa each, p_nom = 70 bar, q_nom = 1 L/s;
τ = 0 makes the valve static). Hysteresis: once open, the valve reseats only below
p_c − Δp_h (a latch state, updated by the step's projection).
"""

from __future__ import annotations

import math

from ...components import relief_flow, relief_static_opening
from ..declare import HYDRAULIC, Component, Derived, Param, Port, State
from ..laws import clip, kernel


def spring_term(nominal_pressure_drop, spring_slope):
    """C_s = √p_nom/k_cs [Pa³ᐟ² s m⁻³]."""
    return math.sqrt(nominal_pressure_drop) / spring_slope


def flow_force_term(nominal_pressure_drop, flow_force_slope):
    """C_f = 1/(k_cf·√p_nom) [Pa¹ᐟ² s m⁻³]."""
    return 1.0 / (flow_force_slope * math.sqrt(nominal_pressure_drop))


def max_opening(nominal_flow, nominal_pressure_drop):
    """x_max = q_nom/√p_nom [m³ s⁻¹ Pa⁻¹ᐟ²]: the fully open flow coefficient."""
    return nominal_flow / math.sqrt(nominal_pressure_drop)


DECLARATION = Component(
    type="relief_valve",
    summary="a pressure relief valve (any node to any node), optional poppet lag and hysteresis",
    parameters=(
        Param("cracking_pressure", "Pa", None, "> 0", "inlet pressure at which it opens"),
        Param("hysteresis", "Pa", 0.0, ">= 0", "open: reseats below cracking − hysteresis"),
        Param("time_constant", "s", 0.0, ">= 0", "poppet lag (0: static)"),
        Param("spring_slope", "m**3/s/Pa", 1.0e-8, "> 0", "k_cs, steady slope of the spring"),
        Param("flow_force_slope", "m**3/s/Pa", 1.0e-8, "> 0", "k_cf, slope of the flow forces"),
        Param("nominal_flow", "m**3/s", 1.0e-3, "> 0", "q_nom, flow when fully open"),
        Param("nominal_pressure_drop", "Pa", 7.0e6, "> 0", "p_nom of the slopes"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
        Param(
            "initial_opening",
            "m**3/s/Pa**0.5",
            0.0,
            ">= 0",
            "flow coefficient at t = 0 (a poppet with a lag; held within 0 … x_max)",
        ),
    ),
    states=(
        State("opening", "m**3/s/Pa**0.5", 1e-7, "initial_opening", "flow coefficient x"),
        State("open", "", 1.0, 0.0, "latch: 1 once open, 0 once reseated"),
    ),
    ports=(Port("inlet", HYDRAULIC, "the guarded node"), Port("outlet", HYDRAULIC, "to tank")),
    source="Hopsan HydraulicPressureReliefValve (Krus 1990), defaults as there",
    flow_port="inlet",
    derived=(
        Derived("spring_term", "s*Pa**1.5/m**3", spring_term, "C_s = √p_nom/k_cs"),
        Derived("flow_force_term", "s*Pa**0.5/m**3", flow_force_term, "C_f = 1/(k_cf·√p_nom)"),
        Derived("max_opening", "m**3/s/Pa**0.5", max_opening, "x_max = q_nom/√p_nom"),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def _static(P, po, p_in, p_out, latched):
    crack = P[po + par.cracking_pressure]
    if latched:
        crack -= P[po + par.hysteresis]
    return relief_static_opening(
        p_in,
        p_out,
        crack,
        P[po + par.spring_term],
        P[po + par.flow_force_term],
        P[po + par.max_opening],
    )


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_in = pn[port[pt.inlet]]
    p_out = pn[port[pt.outlet]]
    x_star = _static(P, po, p_in, p_out, s[so + st.open] > 0.5)
    tau = P[po + par.time_constant]
    if tau > 0.0:
        x = s[so + st.opening]
        d[so + st.opening] = (x_star - x) / tau
    else:
        x = x_star
        d[so + st.opening] = 0.0
    d[so + st.open] = 0.0
    q = relief_flow(x, p_in, p_out, P[po + par.transition_pressure])
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    p_in = s[port[pt.inlet]]
    p_out = s[port[pt.outlet]]
    crack = P[po + par.cracking_pressure]
    if s[so + st.open] > 0.5:
        if p_in < crack - P[po + par.hysteresis]:
            s[so + st.open] = 0.0
    elif p_in > crack:
        s[so + st.open] = 1.0
    if P[po + par.time_constant] > 0.0:
        s[so + st.opening] = clip(s[so + st.opening], 0.0, P[po + par.max_opening])
    else:  # static: the opening at the new pressures, recorded
        s[so + st.opening] = _static(P, po, p_in, p_out, s[so + st.open] > 0.5)
