"""Flow source: an ideal flow from inlet to outlet, whatever the pressures.

    q = q_set        (or the ``flow`` signal when connected)

The flow leaves the inlet's node and enters the outlet's (a negative q runs backwards). An
ideal source delivers any pressure, so the outlet's node needs a compliance (a volume, an
accumulator) or a relief. Hopsan's HydraulicFlowSourceQ (Hopsan component library; Modelica
Fluid's MassFlowSource with a volume flow).
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_IN, Component, Input, Param, Port
from ..laws import kernel, signal_or

DECLARATION = Component(
    type="flow_source",
    summary="an ideal flow source (any node to any node) with a flow input",
    parameters=(
        Param("flow", "m**3/s", 0.0, "", "flow from inlet to outlet when no signal is connected"),
    ),
    states=(),
    ports=(
        Port("inlet", HYDRAULIC, "the flow leaves this node"),
        Port("outlet", HYDRAULIC, "the flow enters this node"),
        Port("flow", SIGNAL_IN, "flow [m³/s] instead of the parameter", optional=True),
    ),
    source="ideal flow source (Hopsan HydraulicFlowSourceQ)",
    flow_port="inlet",
    inputs=(
        Input("flow", "flow", "flow from inlet to outlet, held over each step", unless_port="flow"),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    q = signal_or(port[pt.flow], sig, P[po + par.flow])
    thr[c, pt.inlet] = -q
    thr[c, pt.outlet] = q
