"""Variable orifice: turbulent flow through an area set by a signal (a throttle, a needle
valve, a proportional 2/2 valve).

    A = clip(g·u, 0, A_max)
    q = C_d·A·√(2/ρ)·√Δp,    Δp = p_a − p_b

u the ``opening`` signal (any quantity: a spool stroke in m, a fraction, a current), g the
area gain [m² per unit of u]; the orifice law is `orifice`'s (Merritt 1967 eq. 3-7),
computed by the shared metering-edge law `hydroarm.core.components.edge_flow` with
the area as its opening, √Δp regularised below the transition pressure. Closed (A = 0) for
u ≤ 0. Flow from a to b positive.
"""

from __future__ import annotations

import math

from ...components import edge_flow
from ..declare import HYDRAULIC, SIGNAL_IN, Component, Derived, Param, Port
from ..laws import clip, kernel


def area_coefficient(discharge_coefficient, density):
    """C_d·√(2/ρ) [m s⁻¹ Pa⁻¹ᐟ²]: the flow coefficient per unit of area."""
    return discharge_coefficient * math.sqrt(2.0 / density)


DECLARATION = Component(
    type="variable_orifice",
    summary="a turbulent orifice whose area follows a signal",
    parameters=(
        Param("area_gain", "*", None, "> 0", "g: area [m²] per unit of the signal"),
        Param("max_area", "m**2", math.inf, "> 0", "A_max, the largest area"),
        Param("discharge_coefficient", "", 0.61, "> 0", "C_d (sharp edge: 0.61)"),
        Param("density", "kg/m**3", 870.0, "> 0", "oil density"),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(),
    ports=(
        Port("a", HYDRAULIC, "inlet (positive flow a → b)"),
        Port("b", HYDRAULIC, "outlet"),
        Port("opening", SIGNAL_IN, "the opening signal u"),
    ),
    source="Merritt 1967 eq. 3-7 (as the orifice; C_d = 0.61: sharp edge, Merritt §3.2)",
    flow_port="a",
    derived=(Derived("area_coefficient", "m/s/Pa**0.5", area_coefficient, "C_d·√(2/ρ)"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    area = clip(P[po + par.area_gain] * sig[port[pt.opening]], 0.0, P[po + par.max_area])
    k = P[po + par.area_coefficient]
    dp = pn[port[pt.a]] - pn[port[pt.b]]
    q = edge_flow(k, area, dp, P[po + par.transition_pressure])
    thr[c, pt.a] = -q
    thr[c, pt.b] = q
