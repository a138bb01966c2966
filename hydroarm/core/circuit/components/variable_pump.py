"""Variable-displacement pump with a pressure compensator (a pressure-controlled pump).

    q = ε·D·ω − C_l·(p_out − p_in)
    τ·ε̇ = ε* − ε,     ε* = clip((p_c + Δp_r − p_out)/Δp_r, 0, 1)

D the full displacement per radian, ω the shaft speed (a parameter or the ``speed`` signal),
C_l the volumetric-loss coefficient (the pump's flow with slip, Merritt 1967, as
`fixed_pump`) and ε ∈ [0, 1] the displacement fraction (swash-plate angle over its
largest). The compensator holds the pump on full stroke below its cracking pressure p_c,
destrokes it linearly over the regulation band Δp_r (the steady pressure-flow characteristic
of a compensator's spring and control piston: Watton 2009, "Fundamentals of Fluid Power
Control", the pressure-compensated pump; Hopsan's static characteristic r_p) and holds it at
zero stroke from p_c + Δp_r on. A blocked outlet settles where ε·D·ω = C_l·Δp, at
p_c + Δp_r·(1 − C_l·Δp/(D·ω)): the "deadhead" pressure, just below p_c + Δp_r.

The regulator's dynamics are one lag τ, a reduction of Hopsan's HydraulicPressureControlledPump
(Krus; a second-order regulator with stroking times t_p = 0.15 s up and t_m = 0.12 s down):
the default τ = 0.04 s makes the full-to-zero stroke time 3τ ≈ t_m; the default band is
Hopsan's static characteristic r_p = 1e9 Pa/(m³/s) (pressure droop per flow) times its
default full flow q_max = 1.25e-3 m³/s: 12.5 bar. τ = 0 makes the compensator static.
p_out is absolute, as the relief valve's cracking pressure. The ε state starts settled on
the initial outlet pressure.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_IN, Component, Input, Param, Port, State
from ..laws import clip, first_order_rate, kernel, signal_or

DECLARATION = Component(
    type="variable_pump",
    summary="a variable-displacement pump with a pressure compensator and a speed input",
    parameters=(
        Param("displacement", "m**3/rad", None, "> 0", "full displacement D (per radian)"),
        Param("speed", "rad/s", 0.0, "", "shaft speed when no speed signal is connected"),
        Param("leakage", "m**3/s/Pa", 0.0, ">= 0", "volumetric-loss coefficient C_l"),
        Param("cracking_pressure", "Pa", None, "> 0", "outlet pressure p_c where it destrokes"),
        Param("regulation_band", "Pa", 1.25e6, "> 0", "Δp_r from full to zero stroke"),
        Param("time_constant", "s", 0.04, ">= 0", "compensator lag τ (0: static)"),
    ),
    states=(State("fraction", "", 1.0, 1.0, "displacement fraction ε"),),
    ports=(
        Port("inlet", HYDRAULIC, "suction"),
        Port("outlet", HYDRAULIC, "delivery (the compensator senses it)"),
        Port("speed", SIGNAL_IN, "shaft speed [rad/s]", optional=True),
    ),
    source=(
        "Merritt 1967 (pump flow with slip); Watton 2009 (pressure-compensated pump); Hopsan "
        "HydraulicPressureControlledPump (stroking time and static band of the defaults)"
    ),
    flow_port="inlet",
    inputs=(Input("speed", "speed", "shaft speed, held over each step", unless_port="speed"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def target(P, po, p_out):
    """ε*, the compensator's steady displacement fraction at outlet pressure p_out [Pa]."""
    band = P[po + par.regulation_band]
    return clip((P[po + par.cracking_pressure] + band - p_out) / band, 0.0, 1.0)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_in = pn[port[pt.inlet]]
    p_out = pn[port[pt.outlet]]
    tau = P[po + par.time_constant]
    eps_star = target(P, po, p_out)
    eps = s[so + st.fraction] if tau > 0.0 else eps_star
    d[so + st.fraction] = first_order_rate(eps_star, eps, tau)
    w = signal_or(port[pt.speed], sig, P[po + par.speed])
    q = eps * P[po + par.displacement] * w - P[po + par.leakage] * (p_out - p_in)
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    if h == 0.0 or P[po + par.time_constant] == 0.0:  # settled (static: recorded)
        s[so + st.fraction] = target(P, po, s[port[pt.outlet]])
    else:
        s[so + st.fraction] = clip(s[so + st.fraction], 0.0, 1.0)
