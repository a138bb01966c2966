"""The two chambers of a double-acting actuator (shared by the cylinder and the rotary
actuator; not a component: the registry skips ``_`` modules).

    F = A_a·p_a − A_b·p_b − b·ẋ                               (on the output node)
    q_a = −A_a·ẋ − C_i·(p_a − p_b) − C_ea·(p_a − p_t)
    q_b =  A_b·ẋ + C_i·(p_a − p_b) − C_eb·(p_b − p_t)
    C_a = V_a/β_e(p_a),  V_a = V_0a + A_a·x,   C_b = V_b/β_e(p_b),  V_b = V_0b + A_b·(L − x)

(q: flows into the nodes; x ∈ [0, L] the travel from the A end; A: areas [m²] of a cylinder
or displacements [m³/rad] of a rotary actuator, whose F is then a torque). Merritt 1967
eq. 2-28 (chamber continuity) and §6.2 (the actuator's force); β_e with entrained air as
:func:`hydroarm.core.components.effective_bulk_modulus`.
"""

from __future__ import annotations

from ...components import effective_bulk_modulus
from ..laws import kernel

ATMOSPHERE = 101325.0  # [Pa] reference of the air fraction


@kernel
def chamber_law(c, ia, ib, im, p_a, p_b, x, v, geometry, fluid, leakage, friction, mass, thr, cap):
    """Write the chambers' flows and compliances and the output's force and mass into
    ``thr`` and ``cap`` at row c (columns ia, ib: the chambers' ports, im: the output's).
    ``geometry`` = (A_a, A_b, L, V_0a, V_0b); ``fluid`` = (β, air fraction, κ);
    ``leakage`` = (C_i, C_ea, C_eb, p_t); ``friction`` = b; ``mass`` the moving part's."""
    a_a, a_b, stroke, dead_a, dead_b = geometry
    beta, air, kappa = fluid
    c_i, c_ea, c_eb, p_t = leakage
    q_i = c_i * (p_a - p_b)
    thr[c, ia] = -a_a * v - q_i - c_ea * (p_a - p_t)
    thr[c, ib] = a_b * v + q_i - c_eb * (p_b - p_t)
    v_a = dead_a + a_a * x
    v_b = dead_b + a_b * (stroke - x)
    cap[c, ia] = v_a / effective_bulk_modulus(p_a, beta, air, kappa, ATMOSPHERE, 1.0)
    cap[c, ib] = v_b / effective_bulk_modulus(p_b, beta, air, kappa, ATMOSPHERE, 1.0)
    thr[c, im] = a_a * p_a - a_b * p_b - friction * v
    cap[c, im] = mass
