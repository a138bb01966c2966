"""Pressure-compensated flow control valve (two-way): a metering orifice and a compensator
that holds the drop across it at the compensator's spring setting Δp_c, so that the flow
stays at its setting q_set whatever the drop across the valve, once that drop exceeds Δp_c.

Ideal characteristic: below Δp_c the compensator is wide open and the valve is its
metering orifice, sized so that it passes q_set at Δp_c (Merritt 1967 eq. 3-7); above, the
compensator throttles the excess (a pressure-drop valve, as Hopsan's
HydraulicPressureCompensatingValve)::

    q_o = k_m·√Δp,   k_m = q_set/√Δp_c,   Δp = p_in − p_out
    q = min(q_o, q_set)                                           (ideal)
    q = q_o / (1 + (q_o/q_set)^m)^(1/m)                           (as computed, Δp > 0)

the smooth minimum of exponent m (default 8: q within 0.8 % of q_set at 2·Δp_c, 0.15 % at
3·Δp_c; 8 % below it at the knee Δp = Δp_c), smooth in Δp, √ regularised below the transition
pressure. The compensator does not act on reverse flow (p_out > p_in): ``reverse =
"orifice"`` passes it through the metering orifice, q = k_m·√Δp (a compensator spool held
open by its spring), ``reverse = "blocked"`` stops it (a check in series). A free reverse
flow (a bypass check) is a check valve joined in parallel.
"""

from __future__ import annotations

from ...equations import signed_sqrt
from ..declare import HYDRAULIC, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="flow_control",
    summary="a pressure-compensated flow control valve (q ≈ q_set above Δp_c)",
    parameters=(
        Param("flow_setting", "m**3/s", None, "> 0", "q_set, the regulated flow"),
        Param("compensator_pressure", "Pa", None, "> 0", "Δp_c, the least drop that regulates"),
        Param("sharpness", "", 8.0, ">= 1", "m, exponent of the smooth minimum"),
        Param(
            "reverse",
            "",
            "orifice",
            "",
            "reverse flow: through the metering orifice, or blocked",
            ("orifice", "blocked"),
            sweepable=False,
        ),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "laminar below this drop"),
    ),
    states=(),
    ports=(
        Port("inlet", HYDRAULIC, "inlet (regulated flow inlet → outlet)"),
        Port("outlet", HYDRAULIC, "outlet"),
    ),
    source=(
        "ideal two-way pressure-compensated valve: metering orifice (Merritt 1967 eq. 3-7) "
        "held at Δp_c by its compensator (Hopsan HydraulicPressureCompensatingValve); "
        "smooth minimum: this module"
    ),
    flow_port="inlet",
)
par, st, pt = DECLARATION.indices()
ORIFICE, BLOCKED = range(2)


@kernel
def compensated_flow(q_o, q_set, m):
    """The smooth minimum q_o/(1 + (q_o/q_set)^m)^(1/m) of an orifice flow q_o ≥ 0 and the
    setting q_set (module doc)."""
    return q_o / (1.0 + (q_o / q_set) ** m) ** (1.0 / m)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    q_set = P[po + par.flow_setting]
    k_m = q_set / P[po + par.compensator_pressure] ** 0.5
    dp = pn[port[pt.inlet]] - pn[port[pt.outlet]]
    q_o = k_m * signed_sqrt(dp, P[po + par.transition_pressure])
    if q_o >= 0.0:
        q = compensated_flow(q_o, q_set, P[po + par.sharpness])
    elif P[po + par.reverse] == BLOCKED:
        q = 0.0
    else:
        q = q_o
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q
