"""Pivot linkage: a cylinder mounted between two pivots on neighbouring links.

The usual boom, stick, knee and ankle arrangement. One pivot sits on the parent link at the
distance a from the joint axis, the other on the child link at the distance b; at joint
angle θ the angle between them, seen from the axis, is θ + φ (φ: its value at θ = 0). The
pin-to-pin length and the rod position are (law of cosines)

    L = √(a² + b² − 2ab·cos(θ + φ)),   x = L − L_r
    g' = dL/dθ = a·b·sin(θ + φ)/L,     g'' = (a·b·cos(θ + φ) − g'²)/L

with L_r the pin-to-pin length of the retracted cylinder (the rod node at x = 0). The
moment arm g' follows the geometry: a rod force F gives the joint the torque g'·F. It
vanishes at the dead centres θ + φ = 0 and π, where the pivots and the axis are in line;
the joint's limits must keep θ + φ inside (0, π) or (−π, 0): a negative φ mounts the
cylinder so that extending it lowers θ.
"""

from __future__ import annotations

import math

from ..declare import ROTATIONAL, TRANSLATIONAL, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="pivot_linkage",
    summary="a cylinder between a pivot on the parent link and one on the child link",
    parameters=(
        Param("base_radius", "m", None, "> 0", "distance a of the parent-link pivot from the axis"),
        Param("link_radius", "m", None, "> 0", "distance b of the child-link pivot from the axis"),
        Param("angle_offset", "rad", None, "", "angle φ between the pivots at θ = 0"),
        Param("retracted_length", "m", None, "> 0", "pin-to-pin length L_r with the rod at x = 0"),
    ),
    states=(),
    ports=(
        Port("joint", ROTATIONAL, "the joint it turns (master)"),
        Port("rod", TRANSLATIONAL, "the cylinder rod's node (slave)", slaved=True),
    ),
    source="planar geometry (law of cosines); torque by virtual work",
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # a massless, lossless linkage: the kernel carries the forces (transmit)


@kernel
def transmit(P, po, q, out):
    a = P[po + par.base_radius]
    b = P[po + par.link_radius]
    ang = q + P[po + par.angle_offset]
    ab = a * b
    length = math.sqrt(a * a + b * b - 2.0 * ab * math.cos(ang))
    arm = ab * math.sin(ang) / length
    out[0] = length - P[po + par.retracted_length]
    out[1] = arm
    out[2] = (ab * math.cos(ang) - arm * arm) / length
    out[3] = out[1]  # the force lever: by virtual work
