"""Rotary actuator: a double-acting vane (or rack-and-pinion) actuator of limited travel
between two hydraulic nodes and a rotational node.

    T = D_a·p_a − D_b·p_b − b·ω                               (on the shaft's node)
    q_a = −D_a·ω − C_i·(p_a − p_b) − C_ea·(p_a − p_t)
    q_b =  D_b·ω + C_i·(p_a − p_b) − C_eb·(p_b − p_t)
    C_a = V_a/β_e(p_a),  V_a = V_0a + D_a·(θ − θ_0)
    C_b = V_b/β_e(p_b),  V_b = V_0b + D_b·(θ_0 + Θ − θ)

(q: flows into the nodes; D: the chambers' displacements per radian, equal for a vane; θ
the shaft node's angle, θ_0 its value with chamber A smallest, Θ the travel). The cylinder's
chamber law (`_chambers`; Merritt 1967 eq. 2-28) with displacements for areas and a
torque for a force; an inelastic stop at each end of the travel (the step's projection).
Unlike `hydraulic_motor` (a motor turns without end through its own small chambers),
the chambers' volumes change with the angle and are the nodes' compliance.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, ROTATIONAL, Component, Param, Port
from ..laws import kernel
from ._chambers import (
    ENERGIES,
    OIL_AND_SEALS,
    actuator_energy,
    actuator_law,
    actuator_stops,
    check_layout,
)

DECLARATION = Component(
    type="rotary_actuator",
    summary="a double-acting rotary (vane) actuator of limited travel",
    parameters=(
        Param("displacement_a", "m**3/rad", None, "> 0", "chamber A's volume per radian D_a"),
        Param("displacement_b", "m**3/rad", None, "> 0", "chamber B's volume per radian D_b"),
        Param("travel", "rad", None, "> 0", "travel Θ between the stops"),
        Param("angle_at_a_end", "rad", 0.0, "", "shaft angle θ_0 with chamber A smallest"),
        Param("dead_volume_a", "m**3", 1.0e-5, "> 0", "chamber A volume at θ_0, lines included"),
        Param("dead_volume_b", "m**3", 1.0e-5, "> 0", "chamber B volume at θ_0 + Θ"),
        *OIL_AND_SEALS,
        Param("viscous_friction", "N*m*s/rad", 0.0, ">= 0", "viscous friction b"),
        Param("rotor_inertia", "kg*m**2", 0.0, ">= 0", "vane and shaft inertia, added to the node"),
    ),
    states=(),
    ports=(
        Port("a", HYDRAULIC, "chamber A", compliant=True),
        Port("b", HYDRAULIC, "chamber B", compliant=True),
        Port("shaft", ROTATIONAL, "the shaft's node (positive: chamber A grows)", drives=True),
    ),
    source="Merritt 1967 eq. 2-28 and §6.2 (chamber continuity, actuator torque)",
    flow_port="a",
    energies=ENERGIES,
)
par, st, pt = DECLARATION.indices()


check_layout(DECLARATION)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    actuator_law(c, P, po, port, pn, xm, vm, thr, cap)


@kernel
def energy(t, c, P, po, s, so, d, eo, port, pn, xm, vm, sig, thr, cap, pref):
    actuator_energy(c, P, po, port, pn, thr, cap, d, eo, pref)


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    actuator_stops(P, po, s, port, xo, vo)
