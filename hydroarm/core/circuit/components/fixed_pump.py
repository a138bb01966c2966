"""Fixed-displacement pump driven at a speed (a parameter or a signal).

    q = D·ω − C_l·(p_out − p_in),      T_shaft = D·(p_out − p_in)

D the displacement per radian (files take any volume per revolution), ω the shaft speed,
C_l the volumetric-loss (leakage) coefficient (Merritt 1967 §7.2, the pump's flow with
slip; Hopsan HydraulicFixedDisplacementPump). The flow enters at the inlet and leaves at the
outlet; the ``speed`` signal (a ramp, a sine, a table: `signal_source`) drives it.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_IN, Component, Energy, Input, Param, Port
from ..laws import kernel, signal_or

DECLARATION = Component(
    type="fixed_pump",
    summary="a fixed-displacement pump with a speed input",
    parameters=(
        Param("displacement", "m**3/rad", None, "> 0", "displacement (per radian)"),
        Param("speed", "rad/s", 0.0, "", "shaft speed when no speed signal is connected"),
        Param("leakage", "m**3/s/Pa", 0.0, ">= 0", "volumetric-loss coefficient C_l"),
    ),
    states=(),
    ports=(
        Port("inlet", HYDRAULIC, "suction"),
        Port("outlet", HYDRAULIC, "delivery"),
        Port("speed", SIGNAL_IN, "shaft speed [rad/s]", optional=True),
    ),
    source="Merritt 1967 §7.2; Hopsan HydraulicFixedDisplacementPump",
    flow_port="inlet",
    inputs=(Input("speed", "speed", "shaft speed, held over each step", unless_port="speed"),),
    energies=(
        Energy("leakage", "C_l·(p_out − p_in)², dissipated by the volumetric loss"),
        Energy("shaft", "the rest, −D·ω·(p_out − p_in): delivered by the shaft (negative)"),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    w = signal_or(port[pt.speed], sig, P[po + par.speed])
    dp = pn[port[pt.outlet]] - pn[port[pt.inlet]]
    q = P[po + par.displacement] * w - P[po + par.leakage] * dp
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q


@kernel
def energy(t, c, P, po, s, so, d, eo, port, pn, xm, vm, sig, thr, cap, pref):
    dp = pn[port[pt.outlet]] - pn[port[pt.inlet]]
    d[eo] = P[po + par.leakage] * dp * dp
