"""Gear drive: a fixed ratio between two mechanical nodes.

    x_s = ratio·x_m + offset,   g' = ratio,   g'' = 0

A gearbox between a motor and a joint (both rotational: ratio = motor turns per joint turn),
a rack and pinion or a cable drum (a linear node from a rotational one: ratio = the pitch
radius, m/rad) or a lever on a linear joint. The master is the joint side; a force F on the
slave gives the master ratio·F, and a mass M on the slave adds ratio²·M (the reflected
inertia of a motor's rotor through its gearbox). Lossless.
"""

from __future__ import annotations

from ..declare import MECHANICAL_ANY, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="gear_drive",
    summary="a fixed ratio between two mechanical nodes (gearbox, rack and pinion, lever)",
    parameters=(
        Param("ratio", "*", None, "", "slave motion per master motion (m/rad for a rack)"),
        Param("offset", "*", 0.0, "", "slave position at master position 0"),
    ),
    states=(),
    ports=(
        Port("joint", MECHANICAL_ANY, "the driven node (master)"),
        Port("drive", MECHANICAL_ANY, "the driving node (slave)", slaved=True),
    ),
    source="rigid transmission; forces by virtual work",
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # lossless: the kernel carries the forces (transmit)


@kernel
def transmit(P, po, q, out):
    r = P[po + par.ratio]
    out[0] = r * q + P[po + par.offset]
    out[1] = r
    out[2] = 0.0
    out[3] = out[1]  # the force lever: by virtual work
