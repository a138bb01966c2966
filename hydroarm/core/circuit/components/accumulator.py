"""Gas accumulator: a gas-charged (bladder or piston) accumulator at a node.

Gas precharged to p₀ in a volume V₀, compressed polytropically (p·V_gas^n constant), holds
above p₀ the oil volume (Merritt 1967 §2.7, Boyle's law for n = 1; Hopsan's
HydraulicAckumulator)::

    V_oil(p) = V₀·(1 − (p₀/p)^(1/n)),      C_gas(p) = dV_oil/dp = V₀/(n·p)·(p₀/p)^(1/n)

(none below p₀: the bladder lies empty against its poppet). The oil in the accumulator's
connection (its neck and hose, V_c) adds V_c/β, so the node is compliant at every pressure::

    C = C_gas(p) + V_c/β                                                     [m³/Pa]

`hydroarm.core.components.accumulator_capacitance`, shared with the component servo.
n = 1 is isothermal (slow charging), 1.4 adiabatic (fast cycles, nitrogen), the servo's
default.
"""

from __future__ import annotations

from ...components import accumulator_capacitance
from ..declare import HYDRAULIC, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="accumulator",
    summary="a gas accumulator (polytropic gas above its precharge) with its connection's oil",
    parameters=(
        Param("gas_volume", "m**3", None, "> 0", "gas volume V₀ at the precharge (nominal size)"),
        Param("precharge_pressure", "Pa", None, "> 0", "absolute gas precharge p₀"),
        Param("exponent", "", 1.4, ">= 1", "polytropic exponent n (1: isothermal)"),
        Param("connection_volume", "m**3", 1.0e-5, "> 0", "oil volume of the neck and hose V_c"),
        Param("bulk_modulus", "Pa", 1.5e9, "> 0", "oil bulk modulus β"),
    ),
    states=(),
    ports=(Port("port", HYDRAULIC, "the node", compliant=True),),
    source="Merritt 1967 §2.7 (polytropic gas); Hopsan HydraulicAckumulator",
    flow_port="port",
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p = pn[port[pt.port]]
    cap[c, pt.port] = (
        accumulator_capacitance(
            p, P[po + par.precharge_pressure], P[po + par.gas_volume], P[po + par.exponent]
        )
        + P[po + par.connection_volume] / P[po + par.bulk_modulus]
    )
