"""Crank linkage: the paper's crank and gearbox between a joint and a jack's rod, with the
gearbox's friction.

    x = x_0 + r·sin(θ/n),   g' = dx/dθ = (r/n)·cos(θ/n),   g'' = −(r/n²)·sin(θ/n),
    θ = q − q_0

The joint turns by q (its rotational node, the master); the servo's angle θ is q less the
angle datum q_0 (``angle_offset``: the joint's angle where the crank is at its centre, as the
UCL arm's shoulder is 60° from hanging there; 0 unless given). The crank of radius r behind a
gearbox of ratio n turns by θ/n and moves the rod's translational node (the slave) to x.
A rod force F gives the joint the torque a·F, with the torque arm a = g' (virtual work: the
paper's eq. (3) with the kinematic torque arm r·cos(θ/n)/n,
`hydroarm.core.kinematics.crank_torque_arm`) or, with ``torque_arm = "paper"``, the
r/n printed in the paper's eq. (3) (not energy-conserving: the linkage then makes or loses
(r/n − g')·F·θ̇). The crank's dead centres are at θ/n = ±90°, where g' = 0: the joint's
limits must stay inside (q_0 ± n·90°).

Dry friction at the joint (the paper's option O3, `hydroarm.core.equations.friction_capacity`): the
piston's Coulomb force F_c (breakaway F_s from rest) through the torque arm, the gearbox's no-load
torque T_g0 and its load-dependent loss c·γᵏ·|a·F_d|, with F_d the jack's pressure force (the
``drive_force`` signal, a `servo_jack`'s ``force``) and γ = min(|F_d|/F_rated, 1) its share of the
rated stall force. It is the step's projection on the joint's node
(`hydroarm.core.circuit.laws.dry_friction`, the paper joint's stick-or-slide rule), with the torque
arm at the step's start and the drive force at its end, as the paper joint's steppers take them
(`hydroarm.integrators.fixed`).
"""

from __future__ import annotations

import math

from ...equations import friction_capacity
from ..declare import ROTATIONAL, SIGNAL_IN, TRANSLATIONAL, Component, Param, Port
from ..laws import dry_friction, kernel

DECLARATION = Component(
    type="crank_linkage",
    summary="a crank and gearbox turning a joint from a jack's rod (the paper's joint)",
    parameters=(
        Param("crank_radius", "m", None, "> 0", "crank radius r"),
        Param("gear_ratio", "", 1.0, "> 0", "gearbox ratio n (joint angle over crank angle)"),
        Param("rod_position_at_zero", "m", 0.0, "", "rod node position x_0 at θ = 0"),
        Param(
            "torque_arm",
            "",
            "kinematic",
            "",
            "kinematic: r·cos(θ/n)/n (virtual work); paper: r/n as printed in eq. (3)",
            ("kinematic", "paper"),
            sweepable=False,
        ),
        Param("coulomb_friction", "N", 0.0, ">= 0", "piston Coulomb (sliding) friction F_c"),
        Param("breakaway_friction", "N", 0.0, ">= 0", "piston breakaway (stiction) force F_s"),
        Param("gearbox_friction_torque", "N*m", 0.0, ">= 0", "gearbox no-load torque T_g0"),
        Param("gearbox_loss_at_stall", "", 0.0, ">= 0", "gearbox loss c at the rated stall"),
        Param("gearbox_loss_exponent", "", 1.0, "> 0", "exponent k of the loss law c·γᵏ"),
        Param("rated_force", "N", float("inf"), "> 0", "the jack's rated stall force F_rated"),
        Param("angle_offset", "rad", 0.0, "", "angle datum q_0: the joint's angle at θ = 0"),
    ),
    states=(),
    ports=(
        Port("joint", ROTATIONAL, "the joint it turns (master)"),
        Port("rod", TRANSLATIONAL, "the jack rod's node (slave)", slaved=True),
        Port("drive_force", SIGNAL_IN, "the jack's force F_d [N], for the loss", optional=True),
    ),
    source="the paper's eqs. (3)–(4) (crank x = r·sin(θ/n)) and option O3 (docs/physics.md: "
    "piston and gearbox friction); torque by virtual work",
)
par, st, pt = DECLARATION.indices()
PAPER_TORQUE_ARM = 1


@kernel
def torque_arm(P, po, q):
    """The torque arm a [m] at the joint angle q [rad] (module doc)."""
    r_n = P[po + par.crank_radius] / P[po + par.gear_ratio]
    if P[po + par.torque_arm] == PAPER_TORQUE_ARM:
        return r_n
    return r_n * math.cos((q - P[po + par.angle_offset]) / P[po + par.gear_ratio])


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    return None  # a massless linkage: the kernel carries the forces (transmit)


@kernel
def transmit(P, po, q, out):
    r = P[po + par.crank_radius]
    inv_n = 1.0 / P[po + par.gear_ratio]
    a = (q - P[po + par.angle_offset]) * inv_n
    out[0] = P[po + par.rod_position_at_zero] + r * math.sin(a)
    out[1] = r * inv_n * math.cos(a)
    out[2] = -r * inv_n * inv_n * math.sin(a)
    out[3] = torque_arm(P, po, q)


@kernel
def _capacity(P, po, force, arm, drive, rated):
    """Dry friction torque [N m] with the piston force ``force`` [N] (module doc)."""
    gamma = min(abs(drive) / rated, 1.0)
    return friction_capacity(
        force,
        arm,
        P[po + par.gearbox_friction_torque],
        P[po + par.gearbox_loss_at_stall],
        P[po + par.gearbox_loss_exponent],
        gamma,
        drive * arm,
    )


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    coulomb = P[po + par.coulomb_friction]
    breakaway = P[po + par.breakaway_friction]
    rated = P[po + par.rated_force]
    no_load = P[po + par.gearbox_friction_torque]
    loss = P[po + par.gearbox_loss_at_stall] if port[pt.drive_force] >= 0 else 0.0
    if h <= 0.0 or (coulomb == 0.0 and breakaway == 0.0 and no_load == 0.0 and loss == 0.0):
        return
    n = port[pt.joint]
    arm = torque_arm(P, po, s_old[xo + n])  # at the step's start
    drive = sig[port[pt.drive_force]] if port[pt.drive_force] >= 0 else 0.0
    dry_friction(
        s_old,
        s,
        xo + n,
        vo + n,
        h,
        _capacity(P, po, coulomb, arm, drive, rated),
        _capacity(P, po, max(breakaway, coulomb), arm, drive, rated),
        mass[n],
        share,
    )
