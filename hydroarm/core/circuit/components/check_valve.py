"""Check valve: free flow from inlet to outlet above a cracking pressure, none back, with an
opening that grows over a pressure range and optional hysteresis.

    x = clip((Δp − p_c')/Δp_o, 0, 1),   Δp = p_in − p_out
    q = C_d·A·x·√(2/ρ)·√Δp + C_l·Δp

p_c' = p_c while closed and p_c − Δp_h once open (a latch state, set when Δp exceeds p_c,
cleared when Δp falls below p_c − Δp_h: the poppet's hysteresis); Δp_o the rise above
cracking that opens it fully (the spring's rate over the poppet's area and stroke); C_l the
leakage of the closed seat. The poppet is taken as quasi-static, its opening linear in the
pressure above cracking, as in Hopsan's HydraulicCheckValve (which opens over a pressure
overlap) and the spring-loaded poppet of Merritt 1967 §3.4; the flow is the turbulent
orifice of Merritt eq. 3-7, regularised below the transition pressure.
"""

from __future__ import annotations

from ...equations import signed_sqrt
from ..declare import HYDRAULIC, Component, Derived, Param, Port, State
from ..laws import clip, kernel, orifice_coefficient

DECLARATION = Component(
    type="check_valve",
    summary="a spring-loaded check valve with an opening range and optional hysteresis",
    parameters=(
        Param("cracking_pressure", "Pa", 0.5e5, ">= 0", "Δp at which it opens"),
        Param("opening_pressure", "Pa", 1.0e5, "> 0", "rise above cracking to full opening"),
        Param("hysteresis", "Pa", 0.0, ">= 0", "open: closes below cracking − hysteresis"),
        Param("area", "m**2", None, "> 0", "flow area fully open"),
        Param("discharge_coefficient", "", 0.61, "> 0", "C_d"),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density"),
        Param("leakage", "m**3/s/Pa", 0.0, ">= 0", "leakage C_l of the closed seat"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(State("open", "", 1.0, 0.0, "latch: 1 once open, 0 once reseated"),),
    ports=(
        Port("inlet", HYDRAULIC, "free flow enters here"),
        Port("outlet", HYDRAULIC, "free flow leaves here"),
    ),
    source="Hopsan HydraulicCheckValve; Merritt 1967 §3.4 (poppet) and eq. 3-7 (orifice)",
    flow_port="inlet",
    derived=(
        Derived(
            "flow_coefficient", "m**3/s/Pa**0.5", orifice_coefficient, "fully open k = C_d·A·√(2/ρ)"
        ),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def opening(P, po, dp, latched):
    """Opening fraction x ∈ [0, 1] at the drop dp [Pa] (module doc)."""
    crack = P[po + par.cracking_pressure]
    if latched:
        crack -= P[po + par.hysteresis]
    return clip((dp - crack) / P[po + par.opening_pressure], 0.0, 1.0)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    dp = pn[port[pt.inlet]] - pn[port[pt.outlet]]
    x = opening(P, po, dp, s[so + st.open] > 0.5)
    k = P[po + par.flow_coefficient]
    q = k * x * signed_sqrt(dp, P[po + par.transition_pressure]) + P[po + par.leakage] * dp
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q
    d[so + st.open] = 0.0


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    dp = s[port[pt.inlet]] - s[port[pt.outlet]]
    crack = P[po + par.cracking_pressure]
    if s[so + st.open] > 0.5:
        if dp < crack - P[po + par.hysteresis]:
            s[so + st.open] = 0.0
    elif dp > crack:
        s[so + st.open] = 1.0
