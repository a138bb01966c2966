"""Tank: a node held at a given pressure (a reservoir, or any ideal pressure source).

The node's pressure is prescribed, p = p_set (or the ``setpoint`` signal when connected);
the tank takes whatever flow the other components deliver to the node, so the node needs
no compliance. Hopsan's HydraulicPressureSourceC (Krus, Hopsan component library).
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_IN, Component, Input, Param, Port
from ..laws import kernel, signal_or

DECLARATION = Component(
    type="tank",
    summary="a node held at a pressure: reservoir or ideal pressure source",
    parameters=(Param("pressure", "Pa", 1.0e5, "> 0", "absolute pressure of the node"),),
    states=(),
    ports=(
        Port("port", HYDRAULIC, "the node held at the pressure", prescribes=True),
        Port("setpoint", SIGNAL_IN, "pressure [Pa] instead of the parameter", optional=True),
    ),
    source="ideal pressure source (Hopsan HydraulicPressureSourceC)",
    flow_port="port",
    inputs=(
        Input(
            "pressure",
            "pressure",
            "the node's pressure, held over each step",
            unless_port="setpoint",
        ),
    ),
)
par, st, pt = DECLARATION.indices()


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    pn[port[pt.port]] = signal_or(port[pt.setpoint], sig, P[po + par.pressure])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # the node's balance is the tank's flow (system.port_quantities)
