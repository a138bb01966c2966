"""Pressure sensor: a hydraulic node's pressure as a signal, with a first-order filter.

    y = g·p + y_0          (τ = 0),     τ·ẏ_f = g·p + y_0 − y_f,  y = y_f   (τ > 0)

p the node's absolute pressure [Pa]; a transducer reading gauge pressure has y_0 = −g·p_atm.
The sensor draws no flow and adds no compliance (an ideal transducer; Hopsan's
HydraulicPressureSensor). Its filter starts settled on the initial pressure.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_OUT, Component, Param, Port, State
from ..laws import filtered, first_order_rate, kernel

DECLARATION = Component(
    type="pressure_sensor",
    summary="a pressure transducer with a first-order filter",
    parameters=(
        Param("gain", "*", 1.0, "", "output per pascal"),
        Param("offset", "*", 0.0, "", "output at 0 Pa absolute"),
        Param("time_constant", "s", 0.0, ">= 0", "filter τ (0: none)"),
    ),
    states=(State("filtered", "", 1.0, 0.0, "the filter's output"),),
    ports=(
        Port("node", HYDRAULIC, "the node measured (no flow)"),
        Port("out", SIGNAL_OUT, "the measurement"),
    ),
    source="first-order transducer model (Hopsan HydraulicPressureSensor)",
)
par, st, pt = DECLARATION.indices()


@kernel
def _raw(P, po, p):
    return P[po + par.gain] * p + P[po + par.offset]


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    u = _raw(P, po, pn[port[pt.node]])
    sig[port[pt.out]] = filtered(u, s[so + st.filtered], P[po + par.time_constant])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    u = _raw(P, po, pn[port[pt.node]])
    d[so + st.filtered] = first_order_rate(u, s[so + st.filtered], P[po + par.time_constant])


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    if h == 0.0:  # the filter starts settled on the initial pressure
        s[so + st.filtered] = _raw(P, po, s[port[pt.node]])
