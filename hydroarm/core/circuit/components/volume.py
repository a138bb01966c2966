"""Volume: oil compliance at a node (a pipe's volume, a manifold, a chamber).

    C = V / β_e(p)                                           [m³/Pa]

with the effective bulk modulus of oil with entrained air (Yu, Chen and Lu 1994;
`hydroarm.core.components.effective_bulk_modulus`). Continuity at the node is the
kernel's: ṗ = Σq / ΣC (Merritt 1967, eq. 2-28).
"""

from __future__ import annotations

from ...components import effective_bulk_modulus
from ..declare import HYDRAULIC, Component, Param, Port
from ..laws import kernel

DECLARATION = Component(
    type="volume",
    summary="a fixed oil volume at a node (compliance)",
    parameters=(
        Param("volume", "m**3", None, "> 0", "oil volume"),
        Param("bulk_modulus", "Pa", 1.5e9, "> 0", "oil bulk modulus"),
        Param("air_fraction", "", 0.0, "in [0, 0.5]", "free-air volume fraction at 1 atm"),
        Param("air_exponent", "", 1.4, "> 0", "polytropic exponent of the air"),
    ),
    states=(),
    ports=(Port("port", HYDRAULIC, "the node", compliant=True),),
    source="Merritt 1967 eq. 2-28; air: Yu, Chen and Lu 1994",
)
par, st, pt = DECLARATION.indices()
ATMOSPHERE = 101325.0  # [Pa] reference of the air fraction


@kernel
def law(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    p = pn[port[pt.port]]
    beta = effective_bulk_modulus(
        p,
        P[po + par.bulk_modulus],
        P[po + par.air_fraction],
        P[po + par.air_exponent],
        ATMOSPHERE,
        1.0,
    )
    cap[c, pt.port] = P[po + par.volume] / beta
