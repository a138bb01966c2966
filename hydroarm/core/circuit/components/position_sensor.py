"""Position sensor: a mechanical node's position (or angle) as a signal, with a first-order
filter, and optionally the measurement's rate.

    y = g·x + y_0          (τ = 0),     τ·ẏ_f = g·x + y_0 − y_f,  y = y_f   (τ > 0)
    ẏ = g·ẋ                (τ = 0),     ẏ = (g·x + y_0 − y_f)/τ           (τ > 0)

The rate (the optional ``rate`` signal) is the time derivative of the measurement itself,
from the node's velocity (no differencing): what a `pid`'s ``measurement_rate`` takes for
its derivative on the measurement.
"""

from __future__ import annotations

from ..declare import MECHANICAL_ANY, SIGNAL_OUT, Component, Param, Port, State
from ..laws import filtered, first_order_rate, kernel

DECLARATION = Component(
    type="position_sensor",
    summary="a position or angle sensor with a first-order filter",
    parameters=(
        Param("gain", "*", 1.0, "", "output per metre (per radian)"),
        Param("offset", "*", 0.0, "", "output at position 0"),
        Param("time_constant", "s", 0.0, ">= 0", "filter τ (0: none)"),
    ),
    states=(State("filtered", "", 1.0, 0.0, "the filter's output"),),
    ports=(
        Port("body", MECHANICAL_ANY, "the node measured"),
        Port("out", SIGNAL_OUT, "the measurement"),
        Port("rate", SIGNAL_OUT, "the measurement's rate ẏ [per s]", optional=True),
    ),
    source="first-order sensor model",
)
par, st, pt = DECLARATION.indices()


@kernel
def _raw(P, po, x):
    return P[po + par.gain] * x + P[po + par.offset]


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    u = _raw(P, po, xm[port[pt.body]])
    tau = P[po + par.time_constant]
    sig[port[pt.out]] = filtered(u, s[so + st.filtered], tau)
    if port[pt.rate] >= 0:
        if tau > 0.0:
            sig[port[pt.rate]] = first_order_rate(u, s[so + st.filtered], tau)
        else:
            sig[port[pt.rate]] = P[po + par.gain] * vm[port[pt.body]]


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    u = _raw(P, po, xm[port[pt.body]])
    d[so + st.filtered] = first_order_rate(u, s[so + st.filtered], P[po + par.time_constant])


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    if h == 0.0:  # the filter starts settled on the initial position
        s[so + st.filtered] = _raw(P, po, s[xo + port[pt.body]])
