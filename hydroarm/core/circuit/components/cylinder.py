"""Cylinder: a double-acting linear actuator (double- or single-rod) between two hydraulic
nodes and a translational node.

    F = A_a·p_a − A_b·p_b − b·ẋ                               (on the rod's node)
    q_a = −A_a·ẋ − C_i·(p_a − p_b) − C_ea·p_a',  q_b = A_b·ẋ + C_i·(p_a − p_b) − C_eb·p_b'
    C_a = V_a/β_e(p_a),  V_a = V_0a + A_a·(x − x_0)
    C_b = V_b/β_e(p_b),  V_b = V_0b + A_b·(x_0 + L − x)

(q: flows into the nodes; p': gauge pressure above the ``tank_pressure`` of the external
leakage). The chamber volumes are the nodes' compliance (Merritt 1967 eq. 2-28 and §6.2);
the rod's position x is the mechanical node's, x_0 its value with the piston at the A end
(``position_at_a_end``), L the stroke. At the stroke's ends an inelastic stop (the step's
projection). The optional signal ``force`` is the chambers' pressure force A_a·p_a − A_b·p_b
(without the viscous term): the load a crank's gearbox transmits, which sets its
load-dependent loss (a `crank_linkage`'s ``drive_force``, as the component servo's
kernel takes it: `hydroarm.reference.servo_kernel.dry_friction_capacity`).
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_OUT, TRANSLATIONAL, Component, Param, Port
from ..laws import kernel
from ._chambers import (
    ENERGIES,
    OIL_AND_SEALS,
    actuator_energy,
    actuator_law,
    actuator_stops,
    check_layout,
    pressure_force,
)

DECLARATION = Component(
    type="cylinder",
    summary="a double-acting cylinder (double- or single-rod)",
    parameters=(
        Param("area_a", "m**2", None, "> 0", "piston area on the A (cap) side"),
        Param("area_b", "m**2", None, "> 0", "annulus area on the B (rod) side"),
        Param("stroke", "m", None, "> 0", "stroke L"),
        Param("position_at_a_end", "m", 0.0, "", "rod node position x_0 with chamber A smallest"),
        Param("dead_volume_a", "m**3", 1.0e-5, "> 0", "chamber A volume at x_0, lines included"),
        Param("dead_volume_b", "m**3", 1.0e-5, "> 0", "chamber B volume at x_0 + L"),
        *OIL_AND_SEALS,
        Param("viscous_friction", "N*s/m", 0.0, ">= 0", "piston viscous friction b"),
        Param("piston_mass", "kg", 0.0, ">= 0", "piston and rod mass, added to the node's"),
    ),
    states=(),
    ports=(
        Port("a", HYDRAULIC, "cap-side chamber", compliant=True),
        Port("b", HYDRAULIC, "rod-side chamber", compliant=True),
        Port("rod", TRANSLATIONAL, "the rod's node (positive: extending)", drives=True),
        Port("force", SIGNAL_OUT, "A_a·p_a − A_b·p_b, the pressure force [N]", optional=True),
    ),
    source="Merritt 1967 eq. 2-28 and §6.2 (chamber continuity, piston force)",
    flow_port="a",
    energies=ENERGIES,
)
par, st, pt = DECLARATION.indices()


check_layout(DECLARATION)


@kernel
def signals(t, P, po, s, so, port, pn, xm, vm, sig):
    if port[pt.force] >= 0:
        sig[port[pt.force]] = pressure_force(P, po, port, pn)


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    actuator_law(c, P, po, port, pn, xm, vm, thr, cap)


@kernel
def energy(t, c, P, po, s, so, d, eo, port, pn, xm, vm, sig, thr, cap, pref):
    actuator_energy(c, P, po, port, pn, thr, cap, d, eo, pref)


@kernel
def project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share):
    actuator_stops(P, po, s, port, xo, vo)
