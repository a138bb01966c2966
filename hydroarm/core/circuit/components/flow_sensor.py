"""Flow sensor: the flow into another component's hydraulic port as a signal, through a
first-order filter.

    τ·ẏ = g·q + y_0 − y,      output y

q [m³/s] the flow *into* the measured component at the measured port (``measures =
"pump.outlet"``: negative while the pump delivers; ``"relief.inlet"``: the relief's flow),
read from the law the kernel has just evaluated. A flowmeter in line, without the pressure
drop or the volume of a real one (Hopsan's HydraulicFlowSensor reads its node's flow the same
way).

τ must be positive: the output is the filter's state. The kernel evaluates every signal
before any law (the laws read signals: a controller's output drives a valve), and the flows
exist only once the laws have run; an unfiltered output g·q would be the flow of the
previous evaluation (another Runge–Kutta stage, another state), not a function of the state.
With the filter the flow enters only the state's derivative, read after the flows (the
sensor's law runs after every other's: ``reads_flows``). The compliance flow of a volume
(C·ṗ) is not a law's flow: measure a volume's inflow at the components that deliver it; a
tank's port reads 0 (its flow is the node's balance, known only after the sum).
"""

from __future__ import annotations

from ..declare import FLOW_TAP, MAX_PORTS, SIGNAL_OUT, Component, Param, Port, State
from ..laws import kernel

DECLARATION = Component(
    type="flow_sensor",
    summary="a flowmeter on another component's port, with a first-order filter",
    parameters=(
        Param("gain", "*", 1.0, "", "output per m³/s"),
        Param("offset", "*", 0.0, "", "output at no flow"),
        Param("time_constant", "s", 1.0e-3, "> 0", "filter τ (its state is the output)"),
    ),
    states=(State("filtered", "", 1.0, "offset", "the filter's output"),),
    ports=(
        Port("measures", FLOW_TAP, 'the port measured, "component.port"'),
        Port("out", SIGNAL_OUT, "the measurement"),
    ),
    source="first-order flowmeter model (Hopsan HydraulicFlowSensor)",
    reads_flows=True,
)
par, st, pt = DECLARATION.indices()


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    sig[port[pt.out]] = s[so + st.filtered]


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    tap = port[pt.measures]
    q = -thr[tap // MAX_PORTS, tap % MAX_PORTS]  # into the measured component
    u = P[po + par.gain] * q + P[po + par.offset]
    d[so + st.filtered] = (u - s[so + st.filtered]) / P[po + par.time_constant]
