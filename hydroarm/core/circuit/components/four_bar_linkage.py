"""Four-bar linkage: a planar four-bar turning a rocker (the slave) from a joint (the master).

The ground link d runs from the input pivot O₂ (the joint's axis) to the output pivot O₄;
the input link a turns with the joint, the coupler b joins its end A to the output link's
end B, and the output link c turns about O₄ (an excavator's H-link: the bucket joint, the
link to the bucket, the rocker the bucket cylinder pushes). Angles are measured in the
four-bar's plane from the ground line O₂→O₄, positive in the joint's positive sense:

    θ₂ = q + φ₂,   s = θ₄ − φ₄   (taken in (−π, π])

with q the joint's angle (the master), φ₂ (``input_angle_offset``) the input link's angle at
q = 0, θ₄ the output link's angle and φ₄ (``output_angle_offset``) its angle at the slave's
zero; s is the slave's (rotational) position.

Position: Freudenstein's equation (F. Freudenstein, "Approximate synthesis of four-bar
linkages", Trans. ASME 77, 853–861, 1955; R. L. Norton, *Design of Machinery*, ch. 4,
the fourbar's position analysis), K₁ cos θ₄ − K₂ cos θ₂ + K₃ = cos(θ₂ − θ₄) with K₁ = d/a, K₂ = d/c,
K₃ = (a² − b² + c² + d²)/(2ac), solved in closed form by the half-angle tangent:

    A = cos θ₂ − K₁ − K₂ cos θ₂ + K₃,   B = −2 sin θ₂,   C = K₁ − (K₂ + 1) cos θ₂ + K₃
    θ₄ = 2·atan2(−B ∓ √(B² − 4AC), 2A)   (− open, + crossed)

In the open branch the pin B lies to the left of the line A→O₄ (counter-clockwise of it),
in the crossed branch to its right. The coupler's angle closes the vector loop
a·e^{iθ₂} + b·e^{iθ₃} = d + c·e^{iθ₄}: θ₃ = atan2(c sin θ₄ − a sin θ₂,
d + c cos θ₄ − a cos θ₂).

Velocity and acceleration: the loop differentiated once and twice in θ₂ (ω₂ = 1, α₂ = 0;
Norton chs. 6 and 7, written here in this form and checked by tests/test_four_bar.py),
each multiplied by e^{−iθ₃} (or e^{−iθ₄}) to drop the coupler's unknown:

    g'  = ω₄ = a·sin(θ₂ − θ₃) / (c·sin(θ₄ − θ₃))
    ω₃ = a·sin(θ₄ − θ₂) / (b·sin(θ₃ − θ₄))
    g'' = α₄ = (a·cos(θ₂ − θ₃) + b·ω₃² − c·ω₄²·cos(θ₄ − θ₃)) / (c·sin(θ₄ − θ₃))

A torque T on the rocker gives the joint g'·T (virtual work). Lossless and massless (the
links' inertia belongs to the mechanism's links or an ``inertia`` on the rocker).

Dead centres (Norton ch. 4, toggle positions): g' = 0 where the input link and the coupler
are in line (θ₂ − θ₃ = 0 or π: the rocker at an extreme, the joint's torque from the rocker
zero), and g' → ∞ where the coupler and the output link are in line (θ₄ − θ₃ = 0 or π: the toggle,
transmission angle 0 or 180°) with no assembly beyond it (B² − 4AC < 0: the position is
NaN). A build refuses a four-bar whose master's range reaches either, or whose rocker
passes 180° from its zero there (its angle would jump by a turn: docs/mechanism.md
"Linkages").
"""

from __future__ import annotations

import math

from ..declare import ROTATIONAL, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="four_bar_linkage",
    summary="a planar four-bar turning a rocker from a joint (an excavator's H-link)",
    parameters=(
        Param("ground_length", "m", None, "> 0", "ground link d: pivot O₂ (the joint) to pivot O₄"),
        Param("input_length", "m", None, "> 0", "input link a (turns with the joint)"),
        Param("coupler_length", "m", None, "> 0", "coupler b (input link's end to output's)"),
        Param("output_length", "m", None, "> 0", "output link c (the rocker, about O₄)"),
        Param("input_angle_offset", "rad", 0.0, "", "φ₂: input link's angle from O₂→O₄ at q = 0"),
        Param("output_angle_offset", "rad", 0.0, "", "φ₄: output link's angle at the slave's 0"),
        Param(
            "branch",
            "",
            "open",
            "",
            "assembly: open (B left of A→O₄) or crossed (B right of it)",
            ("open", "crossed"),
            sweepable=False,
        ),
    ),
    states=(),
    ports=(
        Port("joint", ROTATIONAL, "the joint it is turned by (master)"),
        Port("rocker", ROTATIONAL, "the output link's node (slave)", slaved=True),
    ),
    source="Freudenstein 1955 (Norton, Design of Machinery, ch. 4); velocity and "
    "acceleration loop equations (Norton, chs. 6-7); torque by virtual work",
)
par, st, pt = DECLARATION.indices()
CROSSED = 1


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # a massless, lossless linkage: the kernel carries the forces (transmit)


@kernel
def transmit(P, po, q, out):
    d = P[po + par.ground_length]
    a = P[po + par.input_length]
    b = P[po + par.coupler_length]
    c = P[po + par.output_length]
    t2 = q + P[po + par.input_angle_offset]
    c2, s2 = math.cos(t2), math.sin(t2)
    k1 = d / a
    k2 = d / c
    k3 = (a * a - b * b + c * c + d * d) / (2.0 * a * c)
    ca = c2 - k1 - k2 * c2 + k3
    cb = -2.0 * s2
    cc = k1 - (k2 + 1.0) * c2 + k3
    disc = cb * cb - 4.0 * ca * cc
    if disc < 0.0:  # cannot be assembled at this angle
        out[0] = math.nan
        out[1] = math.nan
        out[2] = math.nan
        out[3] = math.nan
        return
    root = math.sqrt(disc)
    if P[po + par.branch] == CROSSED:
        t4 = 2.0 * math.atan2(-cb + root, 2.0 * ca)
    else:
        t4 = 2.0 * math.atan2(-cb - root, 2.0 * ca)
    t3 = math.atan2(c * math.sin(t4) - a * s2, d + c * math.cos(t4) - a * c2)
    mu = math.sin(t4 - t3)  # sine of the transmission angle
    w4 = a * math.sin(t2 - t3) / (c * mu)
    w3 = a * math.sin(t4 - t2) / (b * math.sin(t3 - t4))
    s = t4 - P[po + par.output_angle_offset]
    out[0] = s - 2.0 * math.pi * math.ceil((s - math.pi) / (2.0 * math.pi))  # into (−π, π]
    out[1] = w4
    out[2] = (a * math.cos(t2 - t3) + b * w3 * w3 - c * w4 * w4 * math.cos(t4 - t3)) / (c * mu)
    out[3] = w4  # the force lever: by virtual work
