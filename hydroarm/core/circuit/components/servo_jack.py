"""Servo jack: the paper's valve-and-jack servo, lumped by its load pressure (the UCL joint's
eqs. (1)–(2) of Appendix I).

    e = clip(y − x, −e_o, +e_o)                        (mechanical feedback: the valve rides
                                                        on the jack; y the lever, x the rod)
    (V/β)·ṗ = q(e, p) − A·ẋ − 2·L·p [− 2·L₀·p·(1 − (e/e_o)²)]
    q = K·√(p_s/2)·e                                   (linear valve, eq. (1))
    q = K·e·√((p_s − sgn(e)·p)/2)                      (orifice valve, option O1)
    F = A·p − b·ẋ                                      (on the rod's node)

p is the load pressure (the difference of the two chambers' pressures), p_s the pressure
across the valve, that of its P port less that of its T port (a sagging power pack's
supply, or a tank held at the supply pressure), ẋ the rod node's velocity. The jack draws
q from P whichever way the valve is open (−q when the load pressure drives oil back into
the supply) and returns it to T. With ``feedback = "none"`` the lever signal is the valve
opening itself (e = clip(y, ±e_o)), for a jack whose valve is driven from outside.

The laws are the paper joint's own (`hydroarm.core.equations.load_flow`,
`load_pressure_rate`), so that the paper's joint, written as
a circuit (a tank at the supply pressure, this jack, a `crank_linkage` and an
`inertia`), is the same model on the system kernel (``hydroarm expand`` of a joint
file; tests/test_joint_circuit.py). The projection is the orifice valve's cavitation floor:
with chamber pressures (p_rated ± p)/2 about the rated supply, |p| ≤ p_rated + 2·p_atm
(`hydroarm.core.equations.lumped_pressure_limit`); a finite ``rated_supply_pressure``
turns it on.
"""

from __future__ import annotations

from ...equations import load_flow, load_pressure_rate, lumped_pressure_limit
from ..declare import (
    HYDRAULIC,
    SIGNAL_IN,
    SIGNAL_OUT,
    TRANSLATIONAL,
    Component,
    Param,
    Port,
    State,
)
from ..laws import clip, kernel

DECLARATION = Component(
    type="servo_jack",
    summary="the paper's servo valve and jack, lumped by its load pressure",
    parameters=(
        Param("piston_area", "m**2", None, "> 0", "piston area A"),
        Param("flow_coefficient", "m**2/s/Pa**0.5", None, "> 0", "valve flow coefficient K"),
        Param("valve_saturation", "m", None, "> 0", "largest valve opening e_o"),
        Param("leakage_coefficient", "m**3/s/Pa", 0.0, ">= 0", "leakage coefficient L"),
        Param("trapped_volume", "m**3", None, "> 0", "oil volume under compression V"),
        Param("bulk_modulus", "Pa", None, "> 0", "oil bulk modulus β"),
        Param(
            "valve_model",
            "",
            "linear",
            "",
            "linear: eq. (1); orifice: √Δp on each metering edge (option O1)",
            ("linear", "orifice"),
            sweepable=False,
        ),
        Param("transition_pressure", "Pa", 1.0e4, "> 0", "orifice: regularisation pressure"),
        Param("null_leakage_coefficient", "m**3/s/Pa", 0.0, ">= 0", "valve leakage at null L₀"),
        Param("viscous_friction", "N*s/m", 0.0, ">= 0", "piston viscous friction b"),
        Param(
            "rated_supply_pressure",
            "Pa",
            float("inf"),
            "> 0",
            "orifice: the rated supply of the cavitation floor (inf: no floor)",
        ),
        Param("atmospheric_pressure", "Pa", 101325.0, ">= 0", "return pressure of the floor"),
        Param("initial_pressure", "Pa", 0.0, "", "load pressure at t = 0"),
        Param(
            "feedback",
            "",
            "mechanical",
            "",
            "mechanical: opening = lever − rod position; none: opening = lever",
            ("mechanical", "none"),
            sweepable=False,
        ),
    ),
    states=(State("load_pressure", "Pa", 1.0e6, "initial_pressure", "p = p_A − p_B"),),
    ports=(
        Port("P", HYDRAULIC, "supply"),
        Port("T", HYDRAULIC, "return"),
        Port("rod", TRANSLATIONAL, "the jack's rod (positive: extending)", drives=True),
        Port("lever", SIGNAL_IN, "the lever (valve input) position [m], in rod coordinates"),
        Port("force", SIGNAL_OUT, "A·p, the jack's pressure force [N]", optional=True),
    ),
    source="the paper's eqs. (1)–(2) and options O1, O2, O6 (docs/model.md, docs/physics.md); "
    "Merritt 1967 eq. 5-35 (the orifice load flow)",
    flow_port="P",
)
par, st, pt = DECLARATION.indices()
MECHANICAL_FEEDBACK = 0


@kernel
def opening(P, po, port, xm, sig):
    """The valve opening e [m] (module doc)."""
    e = sig[port[pt.lever]]
    if P[po + par.feedback] == MECHANICAL_FEEDBACK:
        e -= xm[port[pt.rod]]
    lim = P[po + par.valve_saturation]
    return clip(e, -lim, lim)


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    if port[pt.force] >= 0:
        sig[port[pt.force]] = P[po + par.piston_area] * s[so + st.load_pressure]


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p = s[so + st.load_pressure]
    e = opening(P, po, port, xm, sig)
    xdot = vm[port[pt.rod]]
    area = P[po + par.piston_area]
    q = load_flow(
        e,
        p,
        pn[port[pt.P]] - pn[port[pt.T]],
        P[po + par.flow_coefficient],
        P[po + par.valve_model] != 0.0,
        P[po + par.transition_pressure],
    )
    d[so + st.load_pressure] = load_pressure_rate(
        q,
        xdot,
        p,
        e,
        area,
        P[po + par.leakage_coefficient],
        P[po + par.null_leakage_coefficient],
        P[po + par.valve_saturation],
        P[po + par.bulk_modulus],
        P[po + par.trapped_volume],
    )
    q_supply = q if e >= 0.0 else -q
    thr[c, pt.P] = -q_supply
    thr[c, pt.T] = q_supply
    thr[c, pt.rod] = area * p - P[po + par.viscous_friction] * xdot


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    rated = P[po + par.rated_supply_pressure]
    if P[po + par.valve_model] != 0.0 and rated < float("inf"):
        lim = lumped_pressure_limit(rated, P[po + par.atmospheric_pressure])
        s[so + st.load_pressure] = clip(s[so + st.load_pressure], -lim, lim)
