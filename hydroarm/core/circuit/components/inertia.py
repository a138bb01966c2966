"""Inertia: a rotational node's moment of inertia and the loads on it.

    J·θ̈ = ΣT_ports − k·(θ − θ_k) − c·θ̇ + T_ext − W·X·cos(θ − θ_h)

(ΣT_ports: the actuators' torques, summed by the kernel). W·X is the gravity moment of a
load of weight W at the distance X from the axis, largest at the angle θ_h (the horizontal
arm), as the component servo's rotary load (`hydroarm.reference.servo_kernel.load_force`). Dry
friction (Coulomb T_c, breakaway T_s) and end stops are the step's projection, the rule of
`mass` (`hydroarm.core.circuit.laws.dry_friction`, the paper joint's
stick-or-slide rule, with J the node's whole inertia, motor rotors included).
"""

from __future__ import annotations

import math

from ..declare import ROTATIONAL, Component, Input, Param, Port
from ..laws import dry_friction, end_stop, kernel

DECLARATION = Component(
    type="inertia",
    summary="a rotating inertia with torsion spring, damper, torque, gravity, friction and stops",
    parameters=(
        Param("inertia", "kg*m**2", None, "> 0", "moment of inertia J"),
        Param("spring_rate", "N*m/rad", 0.0, ">= 0", "torsion spring to ground k"),
        Param("spring_free_angle", "rad", 0.0, "", "angle θ_k at which the spring is free"),
        Param("damping", "N*m*s/rad", 0.0, ">= 0", "viscous damping to ground c"),
        Param("torque", "N*m", 0.0, "", "constant external torque along +θ"),
        Param("gravity_moment", "N*m", 0.0, "", "W·X, the largest gravity torque"),
        Param("gravity_angle", "rad", 0.0, "", "angle θ_h of the largest gravity torque"),
        Param("coulomb_friction", "N*m", 0.0, ">= 0", "sliding friction torque T_c"),
        Param("breakaway_friction", "N*m", 0.0, ">= 0", "breakaway (stiction) torque T_s"),
        Param("angle_min", "rad", float("-inf"), "", "lower end stop"),
        Param("angle_max", "rad", float("inf"), "", "upper end stop"),
        Param("initial_angle", "rad", 0.0, "", "angle at t = 0"),
        Param("initial_velocity", "rad/s", 0.0, "", "angular velocity at t = 0"),
    ),
    states=(),
    ports=(Port("body", ROTATIONAL, "the node it turns", inertial=True),),
    source="Newton's second law for rotation; gravity moment as the component servo's rotary "
    "load; dry friction as the paper joint's stick-or-slide rule",
    inputs=(Input("torque", "torque", "external torque along +θ, held over each step"),),
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    th = xm[port[pt.body]]
    w = vm[port[pt.body]]
    torque = (
        P[po + par.torque]
        - P[po + par.spring_rate] * (th - P[po + par.spring_free_angle])
        - P[po + par.damping] * w
    )
    if P[po + par.gravity_moment] != 0.0:
        torque -= P[po + par.gravity_moment] * math.cos(th - P[po + par.gravity_angle])
    thr[c, pt.body] = torque
    cap[c, pt.body] = P[po + par.inertia]


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    n = port[pt.body]
    dry_friction(
        s_old,
        s,
        xo + n,
        vo + n,
        h,
        P[po + par.coulomb_friction],
        P[po + par.breakaway_friction],
        mass[n],
        share,
    )
    end_stop(s, xo + n, vo + n, P[po + par.angle_min], P[po + par.angle_max])
