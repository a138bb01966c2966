"""The two chambers of a double-acting actuator (shared by the cylinder and the rotary
actuator; not a component: the registry skips ``_`` modules).

    F = A_a·p_a − A_b·p_b − b·ẋ                               (on the output node)
    q_a = −A_a·ẋ − C_i·(p_a − p_b) − C_ea·(p_a − p_t)
    q_b =  A_b·ẋ + C_i·(p_a − p_b) − C_eb·(p_b − p_t)
    C_a = V_a/β_e(p_a),  V_a = V_0a + A_a·x,   C_b = V_b/β_e(p_b),  V_b = V_0b + A_b·(L − x)

(q: flows into the nodes; x ∈ [0, L] the travel from the A end; A: areas [m²] of a cylinder
or displacements [m³/rad] of a rotary actuator, whose F is then a torque). Merritt 1967
eq. 2-28 (chamber continuity) and §6.2 (the actuator's force); β_e with entrained air as
`hydroarm.core.components.effective_bulk_modulus`, the air fraction measured at the
``atmospheric_pressure``.

Both actuators declare the same parameter layout, their own names and units for the
geometry (A_a, A_b, L, x_0, V_0a, V_0b), then `OIL_AND_SEALS`, then the viscous
friction b and the moving part's mass, and the ports a, b and the output in that order;
`actuator_law` and `actuator_stops` read them by position from the component's
offset, and `check_layout` holds each module to it at import.
"""

from __future__ import annotations

from ...components import effective_bulk_modulus
from ..declare import Energy, Param
from ..laws import clip, end_stop, inlined_kernel, kernel

ATMOSPHERE = 101325.0  # [Pa] the air fraction's reference pressure by default

#: the oil and the seals, declared once for both actuators
OIL_AND_SEALS = (
    Param("bulk_modulus", "Pa", 1.5e9, "> 0", "oil bulk modulus"),
    Param("air_fraction", "", 0.0, "in [0, 0.5]", "free-air volume fraction at 1 atm"),
    Param("air_exponent", "", 1.4, "> 0", "polytropic exponent of the air"),
    Param(
        "atmospheric_pressure",
        "Pa",
        ATMOSPHERE,
        "> 0",
        "the pressure at which the air fraction is measured",
    ),
    Param("internal_leakage", "m**3/s/Pa", 0.0, ">= 0", "leakage A → B across the piston or vane"),
    Param("external_leakage_a", "m**3/s/Pa", 0.0, ">= 0", "leakage A → outside"),
    Param("external_leakage_b", "m**3/s/Pa", 0.0, ">= 0", "leakage B → outside"),
    Param("tank_pressure", "Pa", 1.0e5, "> 0", "pressure outside the seals"),
)
#: the shares of the actuator's absorbed power (its energy account; docs/components.md)
ENERGIES = (
    Energy("compression", "Σ (p − p_ref)·C·ṗ over both chambers: stored in the oil"),
    Energy("leakage", "C_i·(p_a − p_b)² + C_ea·(p_a − p_t)² + C_eb·(p_b − p_t)²"),
    Energy(
        "piston",
        "the rest: viscous friction b·ẋ², the moving part's kinetic energy and the "
        "reference pressure's work on the area difference, −p_ref·(A_a − A_b)·ẋ",
    ),
)
# positions in the layout (module doc)
AREA_A, AREA_B, TRAVEL, AT_A_END, DEAD_A, DEAD_B = range(6)
BETA, AIR, KAPPA, P_ATM, LEAK_I, LEAK_A, LEAK_B, P_OUT = range(6, 14)
FRICTION, MASS = 14, 15
PORT_A, PORT_B, PORT_OUT = range(3)


def check_layout(decl) -> None:
    """Refuse (at import) an actuator declaration out of the shared layout."""
    names = [p.name for p in decl.parameters]
    shared = [p.name for p in OIL_AND_SEALS]
    ports = [q.name for q in decl.ports]
    if len(names) != MASS + 1 or names[BETA:FRICTION] != shared or ports[:2] != ["a", "b"]:
        raise ImportError(f"{decl.type}: parameters out of the two-chamber layout")


@kernel
def pressure_force(P, po, port, pn):
    """A_a·p_a − A_b·p_b: the chambers' pressure force [N] (a torque [N m] of a rotary
    actuator) on the output, its viscous friction left out (module doc)."""
    return P[po + AREA_A] * pn[port[PORT_A]] - P[po + AREA_B] * pn[port[PORT_B]]


@inlined_kernel
def actuator_law(c, P, po, port, pn, xm, vm, thr, cap):
    """Write the chambers' flows and compliances and the output's force and mass into
    ``thr`` and ``cap`` at row c (module doc)."""
    p_a = pn[port[PORT_A]]
    p_b = pn[port[PORT_B]]
    stroke = P[po + TRAVEL]
    x = clip(xm[port[PORT_OUT]] - P[po + AT_A_END], 0.0, stroke)
    v = vm[port[PORT_OUT]]
    a_a = P[po + AREA_A]
    a_b = P[po + AREA_B]
    p_t = P[po + P_OUT]
    q_i = P[po + LEAK_I] * (p_a - p_b)
    thr[c, PORT_A] = -a_a * v - q_i - P[po + LEAK_A] * (p_a - p_t)
    thr[c, PORT_B] = a_b * v + q_i - P[po + LEAK_B] * (p_b - p_t)
    beta = P[po + BETA]
    air = P[po + AIR]
    kappa = P[po + KAPPA]
    p_atm = P[po + P_ATM]
    v_a = P[po + DEAD_A] + a_a * x
    v_b = P[po + DEAD_B] + a_b * (stroke - x)
    cap[c, PORT_A] = v_a / effective_bulk_modulus(p_a, beta, air, kappa, p_atm, 1.0)
    cap[c, PORT_B] = v_b / effective_bulk_modulus(p_b, beta, air, kappa, p_atm, 1.0)
    thr[c, PORT_OUT] = pressure_force(P, po, port, pn) - P[po + FRICTION] * v
    cap[c, PORT_OUT] = P[po + MASS]


@kernel
def actuator_energy(c, P, po, port, pn, thr, cap, d, eo, pref):
    """The rates [W] of the chambers' compression and leakage terms into d[eo], d[eo + 1]
    (`ENERGIES`; ``thr``, ``cap``: the row c its law wrote, d the nodes' ṗ)."""
    ia, ib = port[PORT_A], port[PORT_B]
    p_a = pn[ia]
    p_b = pn[ib]
    p_t = P[po + P_OUT]
    d[eo] = (p_a - pref) * cap[c, PORT_A] * d[ia] + (p_b - pref) * cap[c, PORT_B] * d[ib]
    d[eo + 1] = (
        P[po + LEAK_I] * (p_a - p_b) * (p_a - p_b)
        + P[po + LEAK_A] * (p_a - p_t) * (p_a - p_t)
        + P[po + LEAK_B] * (p_b - p_t) * (p_b - p_t)
    )


@kernel
def actuator_stops(P, po, s, port, xo, vo):
    """The inelastic stops at both ends of the travel (the step's projection)."""
    lo = P[po + AT_A_END]
    m = port[PORT_OUT]
    end_stop(s, xo + m, vo + m, lo, lo + P[po + TRAVEL])
