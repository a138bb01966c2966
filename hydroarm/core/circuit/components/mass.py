"""Mass: a translational node's inertia and the loads on it.

    m·ẍ = ΣF_ports − k·(x − x_k) − c·ẋ + F_ext − m·g

(ΣF_ports: the actuators' forces, summed by the kernel; g the gravity component along −x).
Dry friction (Coulomb F_c, breakaway F_s) and end stops are the step's projection, the
paper joint's time-stepping rule (`hydroarm.core.equations.stick_or_slide`): the node
sticks if the velocity the smooth step reaches, |v*|, is within h·F/M (M: the node's whole
mass, pistons included), and otherwise slides with v* reduced by h·F_c/M.
"""

from __future__ import annotations

from ..declare import TRANSLATIONAL, Component, Input, Param, Port
from ..laws import dry_friction, end_stop, kernel

DECLARATION = Component(
    type="mass",
    summary="a moving mass with spring, damper, constant force, gravity, friction and stops",
    parameters=(
        Param("mass", "kg", None, "> 0", "moving mass"),
        Param("spring_rate", "N/m", 0.0, ">= 0", "spring to ground k"),
        Param("spring_free_position", "m", 0.0, "", "position x_k at which the spring is free"),
        Param("damping", "N*s/m", 0.0, ">= 0", "viscous damping to ground c"),
        Param("force", "N", 0.0, "", "constant external force along +x"),
        Param("gravity", "m/s**2", 0.0, "", "gravity's acceleration along −x"),
        Param("coulomb_friction", "N", 0.0, ">= 0", "sliding friction F_c"),
        Param("breakaway_friction", "N", 0.0, ">= 0", "breakaway (stiction) force F_s"),
        Param("position_min", "m", float("-inf"), "", "lower end stop"),
        Param("position_max", "m", float("inf"), "", "upper end stop"),
        Param("initial_position", "m", 0.0, "", "position at t = 0"),
        Param("initial_velocity", "m/s", 0.0, "", "velocity at t = 0"),
    ),
    states=(),
    ports=(Port("body", TRANSLATIONAL, "the node it moves", inertial=True),),
    source="Newton's second law; dry friction as the paper joint's stick-or-slide rule",
    inputs=(Input("force", "force", "external force along +x, held over each step"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    x = xm[port[pt.body]]
    v = vm[port[pt.body]]
    m = P[po + par.mass]
    f = (
        P[po + par.force]
        - P[po + par.spring_rate] * (x - P[po + par.spring_free_position])
        - P[po + par.damping] * v
        - m * P[po + par.gravity]
    )
    thr[c, pt.body] = f
    cap[c, pt.body] = m


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    n = port[pt.body]
    ix = xo + n
    iv = vo + n
    dry_friction(
        s_old,
        s,
        ix,
        iv,
        h,
        P[po + par.coulomb_friction],
        P[po + par.breakaway_friction],
        mass[n],
        share,
    )
    end_stop(s, ix, iv, P[po + par.position_min], P[po + par.position_max])
