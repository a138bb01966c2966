"""Crank linkage: the paper's crank and gearbox between a joint and a cylinder's rod.

    x = x_0 + r·sin(θ/n),   g' = dx/dθ = (r/n)·cos(θ/n),   g'' = −(r/n²)·sin(θ/n)

The joint turns by θ (its rotational node, the master); the crank of radius r behind a
gearbox of ratio n turns by θ/n and moves the rod's translational node (the slave) to x.
A rod force F gives the joint the torque g'·F (virtual work: the paper's eq. (3) with the
kinematic torque arm r·cos(θ/n)/n, :func:`hydroarm.core.kinematics.crank_torque_arm`). The
crank's dead centres are at θ/n = ±90°, where g' = 0: the joint's limits must stay inside.
"""

from __future__ import annotations

import math

from ..declare import ROTATIONAL, TRANSLATIONAL, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="crank_linkage",
    summary="a crank and gearbox turning a joint from a cylinder's rod (the paper's joint)",
    parameters=(
        Param("crank_radius", "m", None, "> 0", "crank radius r"),
        Param("gear_ratio", "", 1.0, "> 0", "gearbox ratio n (joint angle over crank angle)"),
        Param("rod_position_at_zero", "m", 0.0, "", "rod node position x_0 at θ = 0"),
    ),
    states=(),
    ports=(
        Port("joint", ROTATIONAL, "the joint it turns (master)"),
        Port("rod", TRANSLATIONAL, "the cylinder rod's node (slave)", slaved=True),
    ),
    source="the paper's eq. (3)–(4) (crank x = r·sin(θ/n)); torque by virtual work",
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # a massless, lossless linkage: the kernel carries the forces (transmit)


@kernel
def transmit(P, po, q, out):
    r = P[po + par.crank_radius]
    inv_n = 1.0 / P[po + par.gear_ratio]
    a = q * inv_n
    out[0] = P[po + par.rod_position_at_zero] + r * math.sin(a)
    out[1] = r * inv_n * math.cos(a)
    out[2] = -r * inv_n * inv_n * math.sin(a)
