"""Laws shared by the pressure-operated valves (pilot check, counterbalance, reducing valve).

Not a component (the name starts with ``_``: the registry skips it). One home each for:

* the opening of a pressure-operated poppet or spool, linear over a pressure band above its
  setting (Hopsan's pressure-controlled valves, Krus 1990: x* = (p − p_ref)/(C_s + C_f·Δp)
  with C_s = √p_nom/k_cs, taken without the flow-force term C_f, normalised by its largest
  value x_max = q_nom/√p_nom, so that the band is Δp_band = C_s·x_max = q_nom/k_cs)::

      x* = clip(e / Δp_band, 0, 1)        e: the opening pressure's excess over the setting

* the flow coefficient of the fully open valve from a rated flow at a rated drop,
  k = q_nom/√Δp_nom (the datasheet's point), the flow then being
  q = k·x·√Δp (`hydroarm.core.components.edge_flow`: Merritt 1967 eq. 3-7);
* the optional first-order lag of the poppet, τ·ẋ = x* − x (Hopsan's ``tao``), and the
  step's projection of the opening state: held in [0, 1] when lagged, the static opening
  at the new pressures recorded when not (as `relief_valve`).
"""

from __future__ import annotations

import math

from ..laws import clip, filtered, first_order_rate, kernel


@kernel
def band_opening(excess, band):
    """The opening x* in [0, 1] of a valve whose opening pressure exceeds its setting by
    ``excess`` [Pa], fully open ``band`` [Pa] above it (module doc)."""
    return clip(excess / band, 0.0, 1.0)


@kernel
def rated_coefficient(flow, drop):
    """k = q_nom/√Δp_nom [m³ s⁻¹ Pa⁻¹ᐟ²]: the fully open valve's flow coefficient."""
    return flow / math.sqrt(drop)


@kernel
def lagged_opening(x_star, s, d, i, time_constant):
    """The opening the flow sees, and ẋ into d[i]: the state s[i] lagging x* by τ, or x*
    itself (and ẋ = 0) when τ = 0."""
    d[i] = first_order_rate(x_star, s[i], time_constant)
    return filtered(x_star, s[i], time_constant)


@kernel
def project_opening(x_star, s, i, time_constant):
    """The step's projection of an opening state s[i]: kept in [0, 1] when lagged, set to
    the static opening x* at the new pressures when not."""
    if time_constant > 0.0:
        s[i] = clip(s[i], 0.0, 1.0)
    else:
        s[i] = x_star
