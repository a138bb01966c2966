"""Orifice: turbulent flow through a fixed area (Merritt 1967, eq. 3-7).

    q = C_d·A·√(2/ρ)·√Δp,    Δp = p_a − p_b

with √Δp regularised below the transition pressure p_t (laminar there, so that the flow is
smooth at Δp = 0: `hydroarm.core.equations.signed_sqrt`). Flow from a to b positive.
"""

from __future__ import annotations

from ...equations import signed_sqrt
from ..declare import HYDRAULIC, Component, Derived, Param, Port
from ..laws import kernel, orifice_coefficient

DECLARATION = Component(
    type="orifice",
    summary="a fixed turbulent orifice",
    parameters=(
        Param("area", "m**2", None, "> 0", "flow area"),
        Param("discharge_coefficient", "", 0.61, "> 0", "C_d (sharp edge: 0.61)"),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(),
    ports=(Port("a", HYDRAULIC, "inlet (positive flow a → b)"), Port("b", HYDRAULIC, "outlet")),
    source="Merritt 1967 eq. 3-7 (C_d = 0.61: sharp-edged orifice, Merritt §3.2)",
    flow_port="a",
    derived=(
        Derived("flow_coefficient", "m**3/s/Pa**0.5", orifice_coefficient, "k = C_d·A·√(2/ρ)"),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    k = P[po + par.flow_coefficient]
    dp = pn[port[pt.a]] - pn[port[pt.b]]
    q = k * signed_sqrt(dp, P[po + par.transition_pressure])
    thr[c, pt.a] = -q
    thr[c, pt.b] = q
