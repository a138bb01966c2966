"""Linearised directional valve: the paper's valve, a flow proportional to the spool's
position whatever the pressures, with the spool driven by a demand signal.

    q_A = K_q·x_v,   q_B = −α·K_q·x_v
    x_v ≥ 0: P → A and B → T;   x_v < 0: P → B and A → T

(q: flows into the work ports' nodes; K_q the flow gain, α the B side's share: 1 for the
paper's valve and a double-rod cylinder, A_B/A_A for a valve matched to a single-rod one, so
that both chambers see the same piston speed). The UCL joint's eq. (1) without its pressure
term (that term is the flow-pressure coefficient, a leakage of the actuator); Merritt 1967
§5.3, the linearised valve's flow gain K_q = ∂Q/∂x_v at its operating point. The spool is
the 4/3 valve's (`_spool`: none, first or second order; ±x_max).
"""

from __future__ import annotations

from ...components import linearised_valve_flows
from ..declare import Component, Energy, Param
from ..laws import kernel
from ._spool import (
    DYNAMICS,
    INITIAL_SPOOL,
    INITIAL_SPOOL_VELOCITY,
    INPUTS,
    PORTS,
    STATES,
    valve_spool,
    valve_spool_projection,
)

DECLARATION = Component(
    type="linear_valve",
    summary="a linearised directional valve: flow proportional to the spool (the paper's)",
    parameters=(
        Param("flow_gain", "m**2/s", None, "> 0", "K_q, flow per metre of spool"),
        Param("area_ratio", "", 1.0, "> 0", "α: the B side's flow per unit of the A side's"),
        Param("max_stroke", "m", None, "> 0", "largest spool stroke |x_v|"),
        *DYNAMICS,
        Param("demand", "m", 0.0, "", "spool demand when no signal is connected"),
        INITIAL_SPOOL,
        INITIAL_SPOOL_VELOCITY,
    ),
    states=STATES,
    ports=PORTS,
    source="the paper's eq. (1); Merritt 1967 §5.3 (the valve's flow gain K_q)",
    flow_port="P",
    inputs=INPUTS,
    energies=(Energy("throttle", "dissipated in the metering edges"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def _spool_args(po):
    return po + par.max_stroke, po + par.dynamics, po + par.demand


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    lim, dyn, dem = _spool_args(po)
    x_v = valve_spool(P, lim, dyn, dem, port[pt.command], sig, s, d, so + st.spool)
    q_a, q_b, q_p, loss = linearised_valve_flows(
        x_v,
        P[po + par.flow_gain],
        P[po + par.area_ratio],
        pn[port[pt.P]],
        pn[port[pt.T]],
        pn[port[pt.A]],
        pn[port[pt.B]],
    )
    thr[c, pt.P] = -q_p
    thr[c, pt.T] = q_p - q_a - q_b
    thr[c, pt.A] = q_a
    thr[c, pt.B] = q_b


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    lim, dyn, dem = _spool_args(po)
    valve_spool_projection(P, lim, dyn, dem, port[pt.command], sig, s, so + st.spool)
