"""Equations of the hydraulic components a servo is built from (issue 14; docs/components.md).

Pure functions on SI floats, compiled with numba; pressures absolute [Pa]. Each is one
component's law, combined by `hydroarm.core.servo` into a servo's right-hand side.

Orifice (turbulent) flow through one metering edge (Merritt 1967, eq. 3-7)::

    q = C_q·A·√(2·Δp/ρ) = k·o·√Δp,    k = C_q·w·√(2/ρ),   A = w·o

with w the area gradient [m] (π·d·f for a spool of diameter d and circumference fraction f),
o the edge opening [m] and √Δp regularised near Δp = 0 (`signed_sqrt` of
`hydroarm.core.equations`: laminar below the transition pressure, so that the flow is
smooth and its pressure derivative finite).

Chamber continuity with an effective bulk modulus (Merritt 1967, eq. 2-28)::

    ṗ = β_e(p)/V · (Σq_in − dV/dt)

with entrained air (Yu, Chen and Lu 1994; Gholizadeh et al. 2011): a volume fraction α of
free air at atmospheric pressure p_atm, compressed polytropically (exponent κ)::

    a(p) = α·(p_atm/p)^(1/κ) / (1 − α + α·(p_atm/p)^(1/κ))
    1/β_e = (1 − a)/β + a/(κ·p)

Relief valve with first-order spool (Hopsan's HydraulicPressureReliefValve, Krus 1990, in
continuous time): a flow coefficient x_r [m³ s⁻¹ Pa⁻¹ᐟ²] that follows its static value
x* = clip((p − p_crack)/(C_s + (p − p_tank)·C_f), 0, x_max) with time constant τ, where
C_s = √p_nom/k_cs and C_f = 1/(k_cf·√p_nom) come from the steady pressure-flow slopes of the
spring (k_cs) and the flow forces (k_cf) at the nominal pressure drop p_nom, and
x_max = q_nom/√p_nom; the flow is x_r·√(p − p_tank).

Gas accumulator (Boyle–polytropic, Merritt 1967 §2.7): gas precharged to p₀ in a volume V₀
holds an oil volume V₀·(1 − (p₀/p)^(1/n)) above p₀, a capacitance
dV/dp = V₀/(n·p)·(p₀/p)^(1/n).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .equations import signed_sqrt


@njit(cache=True, nogil=True, error_model="numpy")
def edge_flow(k, opening, dp, dp_t):
    """Flow [m³/s] through one metering edge of coefficient k = C_q·w·√(2/ρ) [m² s⁻¹ Pa⁻¹ᐟ²]
    opened by ``opening`` [m] (closed below 0: an overlapped edge at a smaller spool stroke)
    under the pressure drop dp [Pa], regularised below dp_t [Pa]."""
    if opening <= 0.0:
        return 0.0
    return k * opening * signed_sqrt(dp, dp_t)


@njit(cache=True, nogil=True, error_model="numpy")
def spool_valve_flows(
    x_v, p_s, p_t, p_a, p_b, k_pa, k_at, k_pb, k_bt, lap_pa, lap_at, lap_pb, lap_bt, dp_t
):
    """Flows of a 4/3 spool valve with four metering edges (P→A, A→T, P→B, B→T) at spool
    position x_v [m] (positive: P→A and B→T open). ``lap_*`` [m] is each edge's overlap
    (negative: underlap, open at null); the edge opening is ±x_v − lap.

    Returns (Q_A, Q_B, Q_P, P_loss): the flows into chambers A and B [m³/s], the flow drawn
    from the supply [m³/s] and the power throttled in the four edges, Σ q·Δp [W]."""
    q_pa = edge_flow(k_pa, x_v - lap_pa, p_s - p_a, dp_t)
    q_at = edge_flow(k_at, -x_v - lap_at, p_a - p_t, dp_t)
    q_pb = edge_flow(k_pb, -x_v - lap_pb, p_s - p_b, dp_t)
    q_bt = edge_flow(k_bt, x_v - lap_bt, p_b - p_t, dp_t)
    loss = q_pa * (p_s - p_a) + q_at * (p_a - p_t) + q_pb * (p_s - p_b) + q_bt * (p_b - p_t)
    return q_pa - q_at, q_pb - q_bt, q_pa + q_pb, loss


@njit(cache=True, nogil=True, error_model="numpy")
def linearised_valve_flows(x_v, flow_gain, ratio, p_s, p_t, p_a, p_b):
    """Flows of the linearised valve (the paper's eq. (1) at the spool's side): q = K_q·x_v
    into A and α·q out of B [m³/s], α the B side's share (A_B/A_A for a valve matched to a
    single-rod cylinder, 1 for the paper's), P→A and B→T for x_v ≥ 0, P→B and A→T otherwise,
    each edge throttling q·Δp. The flows do not depend on the pressures.

    Returns (Q_A, Q_B, Q_P, P_loss) as `spool_valve_flows`."""
    q = flow_gain * x_v
    q_b = q * ratio
    if q >= 0.0:
        return q, -q_b, q, q * (p_s - p_a) + q_b * (p_b - p_t)
    return q, -q_b, -q_b, -q_b * (p_s - p_b) - q * (p_a - p_t)


@njit(cache=True, nogil=True, error_model="numpy")
def effective_bulk_modulus(p, beta, air_fraction, kappa, p_atm, p_floor):
    """β_e [Pa] of oil with a free-air volume fraction ``air_fraction`` at p_atm [Pa],
    compressed with polytropic exponent κ (module doc); β when there is no air. The pressure
    is taken at least ``p_floor`` [Pa] (> 0)."""
    if air_fraction <= 0.0:
        return beta
    pp = max(p, p_floor)
    v_air = air_fraction * (p_atm / pp) ** (1.0 / kappa)
    a = v_air / (1.0 - air_fraction + v_air)
    return 1.0 / ((1.0 - a) / beta + a / (kappa * pp))


@njit(cache=True, nogil=True, error_model="numpy")
def relief_static_opening(p, p_tank, p_crack, c_spring, c_flow, x_max):
    """Static flow coefficient x* of the relief valve [m³ s⁻¹ Pa⁻¹ᐟ²] at inlet pressure p [Pa]
    (module doc): 0 below the cracking pressure, x_max fully open."""
    if p <= p_crack:
        return 0.0
    x = (p - p_crack) / (c_spring + max(p - p_tank, 0.0) * c_flow)
    return min(x, x_max)


@njit(cache=True, nogil=True, error_model="numpy")
def relief_flow(x_r, p, p_tank, dp_t):
    """Flow [m³/s] through the relief valve of flow coefficient x_r from p to p_tank [Pa]."""
    if x_r <= 0.0:
        return 0.0
    return x_r * signed_sqrt(p - p_tank, dp_t)


@njit(cache=True, nogil=True, error_model="numpy")
def relief_flows(x_r, p, p_tank, dp_t):
    """`relief_flow` [m³/s] at every element of the arrays x_r (flow coefficients) and p
    [Pa]: the relief valve's flow along a recorded run."""
    out = np.zeros(x_r.shape[0])
    for i in range(x_r.shape[0]):
        out[i] = relief_flow(x_r[i], p[i], p_tank, dp_t)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def accumulator_capacitance(p, precharge, volume, exponent):
    """dV_oil/dp [m³/Pa] of a gas accumulator (precharge p₀ [Pa], gas volume V₀ [m³],
    polytropic exponent n) at pressure p [Pa]: V₀/(n·p)·(p₀/p)^(1/n) above p₀, 0 below."""
    if volume <= 0.0 or p <= precharge:
        return 0.0
    return volume / (exponent * p) * (precharge / p) ** (1.0 / exponent)


@njit(cache=True, nogil=True, error_model="numpy")
def accumulator_oil_volume(p, precharge, volume, exponent):
    """Oil volume [m³] in a gas accumulator at pressure p [Pa]: V₀·(1 − (p₀/p)^(1/n))."""
    if volume <= 0.0 or p <= precharge:
        return 0.0
    return volume * (1.0 - (precharge / p) ** (1.0 / exponent))


@njit(cache=True, nogil=True, error_model="numpy")
def pid_output(error, integral, rate, kp, ki, kd, u_min, u_max):
    """PID controller output and whether it integrates: u = clip(kp·e + ki·∫e + kd·ė) with
    ė the rate of the error [unit/s] (the caller passes −(sensor rate): derivative on the
    measurement, no kick at a reference step). Anti-windup by conditional integration: the
    integral holds while the output is saturated and the error would drive it further.

    Returns (u, integrate): the limited output and 1.0 or 0.0 for the integral's rate."""
    raw = kp * error + ki * integral + kd * rate
    u = min(max(raw, u_min), u_max)
    hold = (raw > u_max and error > 0.0) or (raw < u_min and error < 0.0)
    return u, 0.0 if hold else 1.0
