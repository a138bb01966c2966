"""Hydraulic motor: a fixed-displacement rotary actuator between two hydraulic nodes and a
rotational node.

    T = η·D·(p_a − p_b) − B·ω      (motoring: D·Δp·ω ≥ 0; driven: D·Δp/η − B·ω)
    q_a = −(D·ω + C_i·(p_a − p_b)) − C_e·(p_a − p_t)
    q_b =   D·ω + C_i·(p_a − p_b)  − C_e·(p_b − p_t)

(q: flows into the nodes: for positive ω the oil passes a → b through the motor; T: the
torque on the shaft's node). D the displacement per radian (files take any volume per
revolution), B the viscous friction, C_i the internal (cross-port) and C_e the external
(case drain, to p_t) leakage coefficients, η the mechanical (torque) efficiency: the torque
falls short of D·Δp when the motor drives its load and exceeds it when the load drives the
motor (it pumps), so that its loss (1 − η)·|D·Δp·ω| is never negative. The ideal motor with
laminar slip and viscous drag is Merritt 1967's (the motor's flow and torque equations) and
Hopsan's HydraulicFixedDisplacementMotorQ (D_m, B_m, C_lm; its inertia J_m is here the
``rotor_inertia`` added to the shaft node, 0 by default: the load's ``inertia`` component
moves the node). The ports add no compliance: join each to a volume (the motor's chamber and
line) or an accumulator.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, ROTATIONAL, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="hydraulic_motor",
    summary="a fixed-displacement hydraulic motor with leakage, viscous drag and efficiency",
    parameters=(
        Param("displacement", "m**3/rad", None, "> 0", "displacement D (per radian)"),
        Param("viscous_friction", "N*m*s/rad", 0.0, ">= 0", "viscous drag B"),
        Param("internal_leakage", "m**3/s/Pa", 0.0, ">= 0", "cross-port leakage C_i, a → b"),
        Param("external_leakage", "m**3/s/Pa", 0.0, ">= 0", "leakage C_e of each port to the case"),
        Param("tank_pressure", "Pa", 1.0e5, "> 0", "case (drain) pressure p_t"),
        Param("mechanical_efficiency", "", 1.0, "in [0.1, 1]", "torque efficiency η"),
        Param("rotor_inertia", "kg*m**2", 0.0, ">= 0", "rotor inertia, added to the shaft node's"),
    ),
    states=(),
    ports=(
        Port("a", HYDRAULIC, "inlet for positive speed"),
        Port("b", HYDRAULIC, "outlet for positive speed"),
        Port("shaft", ROTATIONAL, "the shaft's node (positive: a → b)", drives=True),
    ),
    source="Merritt 1967 (motor flow and torque with slip and viscous drag); Hopsan "
    "HydraulicFixedDisplacementMotorQ",
    flow_port="a",
)
par, st, pt = DECLARATION.indices()


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p_a = pn[port[pt.a]]
    p_b = pn[port[pt.b]]
    w = vm[port[pt.shaft]]
    dis = P[po + par.displacement]
    p_t = P[po + par.tank_pressure]
    c_e = P[po + par.external_leakage]
    q = dis * w + P[po + par.internal_leakage] * (p_a - p_b)  # through the motor, a → b
    thr[c, pt.a] = -q - c_e * (p_a - p_t)
    thr[c, pt.b] = q - c_e * (p_b - p_t)
    torque = dis * (p_a - p_b)
    eta = P[po + par.mechanical_efficiency]
    torque = torque * eta if torque * w >= 0.0 else torque / eta
    thr[c, pt.shaft] = torque - P[po + par.viscous_friction] * w
    cap[c, pt.shaft] = P[po + par.rotor_inertia]
