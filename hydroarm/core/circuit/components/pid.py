"""PID controller: a signal from a reference and a measurement.

    e = r − y,   u = clip(K_p·e + K_i·∫e dt − K_d·ẏ_f, u_min, u_max)

with the derivative on the measurement, so that a reference step gives no kick, and
anti-windup by conditional integration (`hydroarm.core.components.pid_output`; Åström and
Hägglund 2006, §3.5 and §3.3). The measurement's rate ẏ_f is the signal on
``measurement_rate`` where one is connected (a `position_sensor`'s ``rate``: the exact
derivative, ẏ_f = ẏ, the component servo's law), the filter's state then following the
measurement (ẏ_f its rate); otherwise the measurement filtered by a first-order lag τ_d,
ẏ_f = (y − y_f)/τ_d. The paper's mechanical feedback is the proportional case: a spool
demand K_p·(lever − jack).
"""

from __future__ import annotations

from ...components import pid_output
from ..declare import SIGNAL_IN, SIGNAL_OUT, Component, Input, Param, Port, State
from ..laws import kernel

DECLARATION = Component(
    type="pid",
    summary="a PID controller (derivative on the measurement or its rate, anti-windup)",
    parameters=(
        Param("proportional_gain", "*", 1.0, "", "K_p (output per unit of error)"),
        Param("integral_gain", "*", 0.0, "", "K_i"),
        Param("derivative_gain", "*", 0.0, "", "K_d"),
        Param("derivative_time_constant", "s", 1.0e-3, "> 0", "τ_d of the derivative's filter"),
        Param("output_min", "*", float("-inf"), "", "lower output limit"),
        Param("output_max", "*", float("inf"), "", "upper output limit"),
        Param("reference", "*", 0.0, "", "reference when no reference signal is connected"),
        Param("initial_integral", "*", 0.0, "", "∫e dt at t = 0"),
    ),
    states=(
        State("integral", "", 1.0, "initial_integral", "∫e dt"),
        State("measurement_filtered", "", 1.0, 0.0, "the derivative filter's state y_f"),
    ),
    ports=(
        Port("reference", SIGNAL_IN, "r", optional=True),
        Port("measurement", SIGNAL_IN, "y"),
        Port("measurement_rate", SIGNAL_IN, "ẏ (unconnected: y filtered)", optional=True),
        Port("out", SIGNAL_OUT, "u"),
    ),
    source="Åström and Hägglund 2006, Advanced PID Control, §3.3 and §3.5",
    inputs=(
        Input("reference", "reference", "reference, held over each step", unless_port="reference"),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def _measurement_rate(P, po, s, so, port, sig, y):
    """ẏ_f: the ``measurement_rate`` signal if connected, else the filter's (module doc)."""
    if port[pt.measurement_rate] >= 0:
        return sig[port[pt.measurement_rate]]
    return (y - s[so + st.measurement_filtered]) / P[po + par.derivative_time_constant]


@kernel
def _output(P, po, s, so, port, sig):
    r = sig[port[pt.reference]] if port[pt.reference] >= 0 else P[po + par.reference]
    y = sig[port[pt.measurement]]
    e = r - y
    rate = -_measurement_rate(P, po, s, so, port, sig, y)
    u, runs = pid_output(
        e,
        s[so + st.integral],
        rate,
        P[po + par.proportional_gain],
        P[po + par.integral_gain],
        P[po + par.derivative_gain],
        P[po + par.output_min],
        P[po + par.output_max],
    )
    return u, runs * e, y


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    sig[port[pt.out]] = _output(P, po, s, so, port, sig)[0]


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    u, rate_i, y = _output(P, po, s, so, port, sig)
    d[so + st.integral] = rate_i
    d[so + st.measurement_filtered] = _measurement_rate(P, po, s, so, port, sig, y)


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    if h == 0.0:  # the derivative's filter starts settled on the initial measurement
        s[so + st.measurement_filtered] = sig[port[pt.measurement]]
