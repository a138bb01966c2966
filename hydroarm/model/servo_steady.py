"""Static states of a component servo: ṡ = 0 on its kernel (issue 29; docs/linear.md).

`servo_steady_state` finds the state of a `hydroarm.core.servo` servo at rest at
a position, and the reference that holds it there, on the servo's one right-hand side
(`servo_rhs`) with the circuit solve's numerics
(`hydroarm.model.circuit_steady`: its central differences, row scaling, bounded least
squares, floating levels and mid-pressure rule), so that no equation is written twice:

1. the unknowns are the states with dynamics in the servo's configuration
   (`dynamic_states`) other than the pinned position and velocity, and the reference;
   the rows are their derivatives and the velocity's (the load's force balance);
2. first guess: the pump's pressure where its flow balances its leakage and the relief
   valve (with a pump), the chambers half-way between supply and tank with the difference
   that holds the load, the spool and the controller's integral at zero, the reference the
   measurement;
3. least squares on the rows (each divided by the norm of its Jacobian row in scaled
   unknowns, pressures bounded below by the cavitation pressure), first with the valve's
   overlaps set to zero (a zero-lap valve meters at every spool position, so the solve is
   not stranded inside a dead band), then with the servo's own overlaps from there and, if
   that leaves a residual, from there with the spool displaced by its overlap (just outside
   its overlap an overlapped valve meters as the zero-lap valve did);
4. floating levels (a chamber pair sealed with no leakage path, the spool and integral of a
   closed overlapped valve: J·v = 0 and ṡ unchanged by a shift) reported; a floating
   pressure level is put at mid-pressure (p_A + p_B = p_s + p_T for equal chambers);
5. checks: the residual below `RESIDUAL_TOL`, every
   absolute pressure above zero and the cavitation pressure and at most the highest source
   pressure (the fixed supply's; a pump's relief setting × 1.5), the position within the
   actuator's stroke and the load's stops; otherwise a one-line
   [`HydroarmError`][hydroarm.HydroarmError].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.components import relief_flow, relief_static_opening
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    N_STATES,
    P_AREA_A,
    P_AREA_B,
    P_FEEDBACK,
    P_KI,
    P_LAP_AT,
    P_LAP_BT,
    P_LAP_PA,
    P_LAP_PB,
    P_LOAD,
    P_P_CAV,
    P_P_SUPPLY,
    P_P_TANK,
    P_P_TRANS,
    P_PUMP_LEAK,
    P_PUMP_Q,
    P_Q_MAX,
    P_Q_MIN,
    P_RELIEF_CF,
    P_RELIEF_CS,
    P_RELIEF_P,
    P_RELIEF_TAU,
    P_RELIEF_XMAX,
    P_SENSE_ACT,
    P_SENSOR_GAIN,
    P_SPOOL_MAX,
    P_SPOOL_OMEGA,
    P_SPOOL_ORDER,
    P_STROKE_MAX,
    P_STROKE_MIN,
    P_SUPPLY,
    P_VALVE,
    S_INT,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_VV,
    S_XR,
    S_XV,
    STATES,
    SUPPLY_PUMP,
    VALVE_SPOOL,
    actuator_motion,
    load_force,
    servo_rhs,
)
from ..errors import HydroarmError
from .circuit_steady import (
    RESIDUAL_TOL,
    bounded_least_squares,
    centre_levels,
    check_pressure,
    jacobian,
    null_levels,
)

STATE_NAMES = [name for name, _, _ in STATES]
LAPS = (P_LAP_PA, P_LAP_AT, P_LAP_PB, P_LAP_BT)


@dataclass
class ServoSteadyState:
    """A static state of a component servo: ``state`` (the full state vector, SI),
    ``reference`` (the reference that holds it), ``P`` (the parameter vector), ``states``
    (the indices with dynamics), ``floating`` (null directions: (label, vector over the
    state)), ``residual`` (largest scaled residual)."""

    state: np.ndarray
    reference: float
    P: np.ndarray
    states: list[int]
    floating: list[tuple[str, np.ndarray]] = field(default_factory=list)
    residual: float = 0.0


def dynamic_states(P) -> list[int]:
    """The state indices with dynamics in this servo's configuration: position, velocity,
    both chamber pressures; the spool with first- or second-order spool dynamics, the PID
    integral with an integral gain, the supply pressure with a pump, the relief opening with
    a dynamic relief valve."""
    idx = [S_Q, S_V, S_PA, S_PB]
    order = int(P[P_SPOOL_ORDER])
    if order >= 1:
        idx.append(S_XV)
    if order >= 2:
        idx.append(S_VV)
    if P[P_FEEDBACK] != FEEDBACK_MECHANICAL and P[P_KI] != 0.0:
        idx.append(S_INT)
    if P[P_SUPPLY] == SUPPLY_PUMP:
        idx.append(S_PS)
        if P[P_RELIEF_P] < np.inf and P[P_RELIEF_TAU] > 0.0:
            idx.append(S_XR)
    return idx


def pressure_ceiling(P) -> float:
    """The highest absolute pressure a static state may hold: the fixed supply's (or the
    tank's), a pump's relief setting × 1.5 (room for its override); inf for a pump without
    a relief valve."""
    if P[P_SUPPLY] == SUPPLY_PUMP:
        return 1.5 * P[P_RELIEF_P] if P[P_RELIEF_P] < np.inf else math.inf
    return max(P[P_P_SUPPLY], P[P_P_TANK])


def state_scales(P) -> np.ndarray:
    """A typical magnitude of every state (finite-difference steps, the solve's scaling):
    pressures the ceiling (at least 10 bar; 100 bar without one), position and velocity the
    actuator's stroke (1 without a finite one; per second), the spool its stroke (its
    velocity per spool time unit), the integral the error that drives the full spool, the
    relief opening its largest."""
    ceiling = pressure_ceiling(P)
    p = max(ceiling if math.isfinite(ceiling) else 1.0e7, 1.0e6)
    stroke = P[P_STROKE_MAX] - P[P_STROKE_MIN]
    length = stroke if math.isfinite(stroke) and stroke > 0 else 1.0
    if int(P[P_LOAD]) == LOAD_CRANK:
        length = 1.0  # the crank's angle [rad]
    spool = P[P_SPOOL_MAX] if math.isfinite(P[P_SPOOL_MAX]) and P[P_SPOOL_MAX] > 0 else 1e-3
    sc = np.ones(N_STATES)
    sc[[S_PA, S_PB, S_PS]] = p
    sc[S_Q] = length
    sc[S_V] = length
    sc[S_XV] = spool
    sc[S_VV] = spool * max(P[P_SPOOL_OMEGA], 1.0)
    sc[S_INT] = spool / abs(P[P_KI]) if P[P_KI] != 0.0 else 1.0
    sc[S_XR] = P[P_RELIEF_XMAX] if P[P_RELIEF_XMAX] > 0 else 1e-9
    return sc


def rhs(r: float, s: np.ndarray, P: np.ndarray) -> np.ndarray:
    """ṡ at state s and reference r: the servo kernel's right-hand side."""
    d = np.zeros(N_STATES)
    servo_rhs(r, s, P, d)
    return d


def measured(s, P) -> float:
    """The fed-back signal: the jack (mechanical) or the sensor's output (electronic)."""
    x, _, _ = actuator_motion(s[S_Q], s[S_V], P)
    if P[P_FEEDBACK] == FEEDBACK_MECHANICAL:
        return float(x)
    return float(P[P_SENSOR_GAIN] * (x if P[P_SENSE_ACT] != 0.0 else s[S_Q]))


def zero_lap(P) -> np.ndarray:
    """P with every metering edge's overlap set to zero (underlaps kept)."""
    out = P.copy()
    for k in LAPS:
        out[k] = min(out[k], 0.0)
    return out


def overlapped(P) -> bool:
    """Whether the servo's spool valve has an overlapped edge."""
    return P[P_VALVE] == VALVE_SPOOL and any(P[k] > 0.0 for k in LAPS)


def in_overlap(x_v: float, P) -> bool:
    """Whether a spool valve's spool at x_v [m] sits inside its overlap: every edge closed
    (no flow through any), with at least one edge overlapped."""
    if not overlapped(P):
        return False
    openings = (x_v - P[P_LAP_PA], -x_v - P[P_LAP_AT], -x_v - P[P_LAP_PB], x_v - P[P_LAP_BT])
    return all(o <= 0.0 for o in openings)


def pump_pressure(P) -> tuple[float, float]:
    """(p_s, relief opening) where the pump's flow is balanced by its leakage and the relief
    valve with the servo's valve closed (the first guess of a pump-fed servo)."""
    from scipy.optimize import brentq

    p_t = P[P_P_TANK]
    has_relief = P[P_RELIEF_P] < np.inf

    def opening(p):
        if not has_relief:
            return 0.0
        return relief_static_opening(
            p, p_t, P[P_RELIEF_P], P[P_RELIEF_CS], P[P_RELIEF_CF], P[P_RELIEF_XMAX]
        )

    def balance(p):
        return (
            P[P_PUMP_Q] - P[P_PUMP_LEAK] * (p - p_t) - relief_flow(opening(p), p, p_t, P[P_P_TRANS])
        )

    hi = (P[P_RELIEF_P] if has_relief else p_t) + 1e5
    while balance(hi) > 0 and hi < 1e12:
        hi *= 2
    if balance(hi) > 0:
        raise HydroarmError(
            "supply", "the pump's pressure has no steady state (no relief valve, no leakage)"
        )
    p = float(brentq(balance, p_t, hi, xtol=1e-6, rtol=1e-15, maxiter=500))
    return p, float(opening(p))


def _guess(P, s_init, position) -> tuple[np.ndarray, float]:
    """The first guess (module doc, step 2)."""
    s = np.asarray(s_init, float).copy()
    s[S_Q] = position
    s[S_V] = 0.0
    p_t = P[P_P_TANK]
    p_s = P[P_P_SUPPLY]
    if P[P_SUPPLY] == SUPPLY_PUMP:
        p_s, s[S_XR] = pump_pressure(P)
    s[S_PS] = p_s
    _, _, lever = actuator_motion(position, 0.0, P)
    f_need = load_force(position, 0.0, P) / lever if lever != 0 else 0.0
    mid = 0.5 * (p_s + p_t)
    # A_A·p_A − A_B·p_B = f_need with p_A, p_B about mid, each within its bounds
    s[S_PA] = mid + 0.5 * f_need / P[P_AREA_A]
    s[S_PB] = mid - 0.5 * f_need / P[P_AREA_B]
    s[S_PB] += (P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB] - f_need) / P[P_AREA_B]
    s[S_XV] = 0.0
    s[S_VV] = 0.0
    s[S_INT] = 0.0
    return s, measured(s, P)


def _solve(P, s0, r0, unknown, rows, scale, floor) -> tuple[np.ndarray, float, float]:
    """Least squares of the scaled rows from (s0, r0) (module doc, step 3): (s, r, residual)."""
    gain = 1.0 if P[P_FEEDBACK] == FEEDBACK_MECHANICAL else abs(P[P_SENSOR_GAIN])
    r_scale = max(abs(r0), gain * scale[S_Q], 1e-12)

    def unpack(z):
        s = s0.copy()
        s[unknown] = s0[unknown] + z[:-1] * scale[unknown]
        return s, r0 + z[-1] * r_scale

    def raw(z):
        s, r = unpack(z)
        return rhs(r, s, P)[rows]

    z0 = np.zeros(len(unknown) + 1)
    J0 = jacobian(raw, z0, np.ones(z0.size))
    norm = np.sum(np.abs(J0), axis=1)
    norm = np.maximum(norm, 1e-12 * max(float(np.max(norm, initial=0.0)), 1e-300))

    def res(z):
        return raw(z) / norm

    def jac(z):
        return jacobian(raw, z, np.ones(z.size)) / norm[:, None]

    z = z0
    if np.max(np.abs(res(z0))) > RESIDUAL_TOL * 1e-3:
        lower = np.full(z0.size, -np.inf)
        for j, i in enumerate(unknown):
            if i in (S_PA, S_PB, S_PS):
                lower[j] = min((floor - s0[i]) / scale[i], 0.0)
        z = bounded_least_squares(res, z0, jac, lower).x
    s, r = unpack(z)
    out = res(z)
    return s, r, float(np.max(np.abs(out))) if out.size and np.all(np.isfinite(out)) else math.inf


def servo_steady_state(
    P: np.ndarray, s_init: np.ndarray, position: float, field_name: str = "at"
) -> ServoSteadyState:
    """The servo (parameter vector P, initial state ``s_init`` for the states not solved
    for) at rest at ``position`` [m or rad, the load's coordinate] and the reference that
    holds it there (module doc)."""
    _check_position(P, position, field_name)
    idx = dynamic_states(P)
    unknown = [i for i in idx if i not in (S_Q, S_V)]
    rows = [i for i in idx if i != S_Q]
    scale = state_scales(P)
    floor = max(P[P_P_CAV], 1.0)
    s, r = _guess(P, s_init, position)
    # step 3: zero-lap first, then the servo's own overlaps
    if overlapped(P):
        s, r, res = _solve(zero_lap(P), s, r, unknown, rows, scale, floor)
        s_zl, r_zl = s, r
        s, r, res = _solve(P, s_zl, r_zl, unknown, rows, scale, floor)
        if res > RESIDUAL_TOL and s_zl[S_XV] != 0.0:
            shifted = s_zl.copy()
            side = 1.0 if s_zl[S_XV] > 0 else -1.0
            lap = max(P[P_LAP_PA], P[P_LAP_BT]) if side > 0 else max(P[P_LAP_PB], P[P_LAP_AT])
            shifted[S_XV] += side * lap
            s, r, res = _solve(P, shifted, r_zl, unknown, rows, scale, floor)
    else:
        s, r, res = _solve(P, s, r, unknown, rows, scale, floor)
    # step 4: floating levels, a pressure level at mid-pressure
    levels: list[tuple[str, np.ndarray]] = []
    if math.isfinite(res):
        levels = floating_levels(P, r, s, unknown, rows)
        s = centre_levels(s, [S_PA, S_PB], 0.5 * (s[S_PS] + P[P_P_TANK]), levels)
    result = ServoSteadyState(s, float(r), P, idx, levels, res)
    _check(result, field_name)
    return result


def floating_levels(P, r, s, unknown=None, rows=None) -> list[tuple[str, np.ndarray]]:
    """The floating levels (module doc, step 4) among the states ``unknown`` (default: the
    dynamic states) with the rows ``rows`` (default the same) at reference r and state s:
    `null_levels` of the servo's right-hand side, each
    row divided by the norm of its Jacobian row in scaled states."""
    idx = dynamic_states(P)
    unknown = list(idx if unknown is None else unknown)
    rows = list(unknown if rows is None else rows)
    scale = state_scales(P)
    J = jacobian(lambda x: rhs(r, x, P)[rows], s, scale, unknown) * scale[unknown][None, :]
    norm = np.sum(np.abs(J), axis=1)
    norm = np.maximum(norm, 1e-12 * max(float(np.max(norm, initial=0.0)), 1e-300))
    pressure = np.array([i in (S_PA, S_PB, S_PS) for i in unknown])
    return null_levels(
        lambda x: rhs(r, x, P)[rows] / norm,
        s,
        J / norm[:, None],
        np.array(unknown, np.int64),
        scale,
        STATE_NAMES,
        pressure,
    )


def _check_position(P, position: float, field_name: str) -> None:
    if not math.isfinite(position):
        raise HydroarmError(field_name, "is not a finite number")
    lo, hi = P[P_Q_MIN], P[P_Q_MAX]
    if not lo <= position <= hi:
        raise HydroarmError(
            field_name, f"{position:g} is outside the load's end stops ({lo:g} … {hi:g})"
        )
    x, _, _ = actuator_motion(position, 0.0, P)
    if not P[P_STROKE_MIN] - 1e-12 <= x <= P[P_STROKE_MAX] + 1e-12:
        raise HydroarmError(
            field_name,
            f"{position:g} puts the actuator at {x:g}, outside its stroke "
            f"({P[P_STROKE_MIN]:g} … {P[P_STROKE_MAX]:g})",
        )


def _check(r: ServoSteadyState, field_name: str) -> None:
    s, P = r.state, r.P
    if not np.all(np.isfinite(s)) or not math.isfinite(r.residual):
        raise HydroarmError(field_name, "no static state found (the solve left finite numbers)")
    if r.residual > RESIDUAL_TOL:
        raise HydroarmError(
            field_name,
            f"no static state at position {s[S_Q]:.6g}: the servo cannot hold its load there "
            f"(the residual {r.residual:.2g} stays above {RESIDUAL_TOL:g}: a load beyond the "
            "actuator's force, or the valve saturated)",
        )
    floor = P[P_P_CAV]
    ceiling = pressure_ceiling(P)
    names = {S_PA: "pressure_a", S_PB: "pressure_b", S_PS: "supply_pressure"}
    for i, name in names.items():
        check_pressure(field_name, name, s[i], floor, ceiling)
