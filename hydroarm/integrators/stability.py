"""Largest stable fixed step of a method for a scenario.

The right-hand side is linearised (finite differences of the compiled equations) along the
range of states a motion passes (`scenario_jacobians`): at the start, middle and end
angle, at rest at the holding pressure with the valve inside its linear band and saturated,
and at the pressures the motion can reach (0, ±0.95·p_s), at rest and moving at the
saturation velocity either way. For each Jacobian J the one-step amplification matrix G(h)
of the method is formed (RK4: the degree-4 Taylor polynomial of hJ; the paper's Euler: the
product of its sequential updates p → ω → θ). A step is stable when the spectral radius of
G(h) does not exceed that of the exact propagator exp(hJ), exp(h·max Re λ(J)) (or 1,
whichever is larger), so that physically growing modes, such as an unloaded jack that is
only integrating, do not count as numerical instability. The radius is computed from the
eigenvalues of G(h) − I and compared with a relative tolerance, so that round-off never
refuses a small step; steps below `SCAN_LOW` are always stable. The largest stable
step is found by a logarithmic scan and bisection, and is itself accepted.

Linearisation is not a proof: the fixed-step kernels also stop a run whose state leaves the
physical bounds (`hydroarm.integrators.fixed.in_bounds`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.equations import derivatives, flow_gain, holding_pressure, jack_position
from .system import derivatives_at


def jacobian(theta, omega, p, y, joint, load):
    """3×3 Jacobian of the smooth right-hand side at a state, by central differences."""
    s0 = np.array([theta, omega, p], float)
    scale = np.array([1e-7, 1e-6, 1.0 + 1e-7 * abs(p)])
    J = np.empty((3, 3))
    for j in range(3):
        sp = s0.copy()
        sm = s0.copy()
        sp[j] += scale[j]
        sm[j] -= scale[j]
        fp = np.array(derivatives(sp[0], sp[1], sp[2], y, joint, load))
        fm = np.array(derivatives(sm[0], sm[1], sm[2], y, joint, load))
        J[:, j] = (fp - fm) / (2 * scale[j])
    return J


# the paper's Euler updates the state's rows in this order: p (eq. 5), ω (eq. 6), θ (eq. 7)
PAPER_EULER_ORDER = ((2,), (1,), (0,))


def amplification_many(method: str, Js: np.ndarray, h: float, order=PAPER_EULER_ORDER):
    """One-step amplification matrices G(h) of ``method`` for a stack of Jacobians
    (n × k × k) of linear systems ẋ = J·x. ``order``: the groups of rows the semi-implicit
    Euler updates one after the other (each group from the state the previous groups left).
    Every Jacobian is treated alone: a stack of one gives the same matrix as a stack of many."""
    eye = np.eye(Js.shape[-1])
    if method == "rk4":
        Z = h * Js
        Z2 = Z @ Z
        return eye + Z + Z2 / 2 + Z2 @ Z / 6 + Z2 @ Z2 / 24
    if method == "euler":
        G = np.broadcast_to(eye, Js.shape).copy()
        for rows in order:
            E = np.broadcast_to(eye, Js.shape).copy()
            E[:, list(rows), :] += h * Js[:, list(rows), :]
            G = E @ G
        return G
    raise ValueError(method)


def amplification(method: str, J: np.ndarray, h: float, order=PAPER_EULER_ORDER) -> np.ndarray:
    """One-step amplification matrix G(h) of ``method`` for the linear system ẋ = J·x
    (`amplification_many` of a stack of one)."""
    return amplification_many(method, J[None], h, order)[0]


def _log_growth_many(method: str, Js: np.ndarray, h: float, order=PAPER_EULER_ORDER):
    """Per Jacobian of a stack: (log of the spectral radius of G(h), the size of hJ's largest
    eigenvalue), as arrays.

    Computed from the eigenvalues μ of G(h) − I (not of G(h)): |1 + μ| = √(1 + 2·Re μ + |μ|²)
    is then accurate to round-off relative to |μ| even for tiny steps, where the eigenvalues
    of G(h) itself are 1 ± round-off and would decide the comparison."""
    mu = np.linalg.eigvals(amplification_many(method, Js, h, order) - np.eye(Js.shape[-1]))
    g = np.max(
        0.5 * np.log1p(np.maximum(2.0 * mu.real + np.abs(mu) ** 2, np.nextafter(-1.0, 0.0))),
        axis=-1,
    )
    return g, np.max(np.abs(mu), axis=-1)


def _log_growth(
    method: str, J: np.ndarray, h: float, order=PAPER_EULER_ORDER
) -> tuple[float, float]:
    """`_log_growth_many` of one Jacobian, as floats."""
    g, size = _log_growth_many(method, J[None], h, order)
    return float(g[0]), float(size[0])


# Relative tolerance of the growth comparison: a step is unstable only when its
# amplification exceeds the exact growth by more than this fraction of |hλ| (round-off in
# the eigenvalues is far smaller; a real instability is of order |hλ|).
GROWTH_TOLERANCE = 1e-6
# A physically growing mode (rate > 0: the load beyond its balance with the valve saturated,
# an inverted pendulum) may grow up to this many times as fast in the method as in the exact
# solution: a first-order method's error in that rate is accuracy, not instability.
GROWTH_ALLOWANCE = 2.0
SCAN_LOW = 1e-9  # [s] lower end of the step scan: a step below it is never refused


def growth_rate(J: np.ndarray) -> float:
    """Largest real part of the eigenvalues of J [1/s]: the exact propagator exp(hJ) has
    eigenvalues exp(hλ), so its spectral radius is exp(h·max Re λ), exactly and cheaply."""
    return float(np.max(np.linalg.eigvals(J).real))


def _stable_many(method, Js, h, rates, order=PAPER_EULER_ORDER) -> np.ndarray:
    """`is_stable` of each Jacobian of a stack (``rates``: their growth rates)."""
    if h <= SCAN_LOW:
        return np.ones(Js.shape[0], dtype=bool)
    g, size = _log_growth_many(method, Js, h, order)
    # the tolerance scales with |μ| up to 2: a stable step has |1 + μ| ≤ 1, so |μ| ≤ 2; beyond,
    # |μ| grows as |hλ|^p while log|1 + μ| grows as its log, and an uncapped tolerance let a
    # step far past the limit through (a servo's "1 s" with rk4, issue 31)
    tol = GROWTH_TOLERANCE * np.minimum(size, 2.0)
    return g <= GROWTH_ALLOWANCE * h * np.maximum(0.0, rates) + tol + 1e-15


def is_stable(method, J, h, rate=None, order=PAPER_EULER_ORDER):
    """Whether step h is stable for Jacobian J: the method's amplification grows no faster
    than the exact solution (log ρ(G(h)) ≤ `GROWTH_ALLOWANCE`·h·max(0, max Re λ)), up
    to a relative tolerance (`GROWTH_TOLERANCE` × |hλ|) that absorbs round-off. Steps
    below `SCAN_LOW` are stable. The same arithmetic as for a stack of Jacobians
    (`largest_stable_step_for` decides on stacks)."""
    rate = growth_rate(J) if rate is None else rate
    return bool(_stable_many(method, J[None], h, np.array([rate]), order)[0])


def all_stable(method: str, jacobians, h: float, order=PAPER_EULER_ORDER) -> bool:
    """Whether step h is stable for every Jacobian in ``jacobians``: the decision
    `largest_stable_step_for` makes on the same stack, so that the step it returns is
    accepted here."""
    Js = np.array(jacobians, dtype=float)
    rates = np.array([growth_rate(J) for J in jacobians])
    return bool(np.all(_stable_many(method, Js, h, rates, order)))


def largest_stable_step_for(
    method: str, jacobians, h_max: float = 1.0, order=PAPER_EULER_ORDER
) -> float:
    """Largest h ≤ h_max stable for every Jacobian in ``jacobians`` (a step that
    `is_stable` accepts for all of them, by construction)."""
    hs = np.logspace(np.log10(SCAN_LOW), np.log10(h_max), 181)
    Js = np.array(jacobians, dtype=float)
    rates = np.array([growth_rate(J) for J in jacobians])

    def ok(h):
        return bool(np.all(_stable_many(method, Js, h, rates, order)))

    lo = SCAN_LOW
    hi = None
    for h in hs:
        if ok(h):
            lo = h
        else:
            hi = h
            break
    if hi is None:
        return h_max
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return lo


def scenario_jacobians(theta_start, theta_end, joint, load, valve_saturation):
    """Jacobians along the range of states a motion θ₂: theta_start → theta_end passes.

    At the start, middle and end angle: at rest at the holding pressure, with the valve in
    its linear band and saturated; and at the pressures the motion can reach (0, ±supply),
    at rest and moving at the no-load saturation velocity either way, valve saturated (the
    orifice valve's flow gain and the friction terms depend on p and ω)."""
    out = []
    v_sat = float(flow_gain(joint)) * valve_saturation / joint.piston_area  # [m/s] of the jack
    ps = joint.supply_pressure
    for th in (theta_start, 0.5 * (theta_start + theta_end), theta_end):
        p = holding_pressure(th, joint, load)
        x = jack_position(th, joint)
        out.append(jacobian(th, 0.0, p, x, joint, load))  # valve in its linear band (e = 0)
        out.append(jacobian(th, 0.0, p, x + 10 * valve_saturation, joint, load))  # saturated
        lever = math.cos(th / joint.gear_ratio) * joint.crank_radius / joint.gear_ratio
        w_sat = v_sat / max(lever, 1e-9 * joint.crank_radius)
        for pp in (0.0, 0.95 * ps, -0.95 * ps):
            for w in (0.0, w_sat, -w_sat):
                for e in (10 * valve_saturation, -10 * valve_saturation):
                    out.append(jacobian(th, w, pp, x + e, joint, load))
    return out


def oscillation_growth_rate(theta_start, theta_end, joint, load) -> float:
    """Largest growth rate [1/s] of an oscillatory mode (a complex eigenvalue pair) of the
    closed loop linearised at rest at the holding pressure, valve in its linear band, at the
    start and the end angle; −inf where no mode oscillates. > 0 where the servo loop itself is
    unstable whatever the step: the paper's loop with no leakage and no friction, where
    nothing damps the oil column. A real positive eigenvalue (a load beyond the top falling
    away from its balance) is not counted: that is the load, not the loop."""
    rate = -math.inf
    for th in (theta_start, theta_end):
        p = holding_pressure(th, joint, load)
        lam = np.linalg.eigvals(jacobian(th, 0.0, p, jack_position(th, joint), joint, load))
        osc = lam[np.abs(lam.imag) > 1e-9 * np.abs(lam)]
        if osc.size:
            rate = max(rate, float(np.max(osc.real)))
    return rate


def rate_estimate(
    piston_area,
    trapped_volume,
    bulk_modulus,
    crank_radius,
    gear_ratio,
    inertia,
    leakage_coefficient=0.0,
    viscous_friction=0.0,
):
    """Cheap estimate [1/s] of the fastest mode of the linearised joint, for arrays of
    scenarios: the oil-column natural frequency √(β·A²·r²/(V·I·n²)) plus the leakage
    (2·L·β/V) and viscous (c·r²/(I·n²)) decay rates. An explicit method's largest stable step
    falls as this rises, so it picks the scenarios that need the smallest step (a screen to
    choose which scenarios get the full check, not a bound)."""
    lever2 = (crank_radius / gear_ratio) ** 2
    omega = np.sqrt(bulk_modulus * piston_area**2 * lever2 / (trapped_volume * inertia))
    return (
        omega
        + 2.0 * leakage_coefficient * bulk_modulus / trapped_volume
        + viscous_friction * lever2 / inertia
    )


def stable_step_limit(method: str, step: float, theta_start, theta_end, joint, load):
    """None if ``step`` [s] is stable for a motion θ₂: theta_start → theta_end [rad] of this
    joint and load (Jacobians of `scenario_jacobians`), else the largest stable step [s]."""
    if step <= SCAN_LOW:
        return None
    jacobians = scenario_jacobians(theta_start, theta_end, joint, load, joint.valve_saturation)
    if all_stable(method, jacobians, step):
        return None
    return largest_stable_step_for(method, jacobians)


# ---------------------------------------------------------------- system kernel ---
def circuit_jacobian(t, s, P, net, pressure):
    """Jacobian of the system kernel's right-hand side
    (`hydroarm.integrators.system.derivatives_at`) at (t, s), by central differences
    with `servo_jacobian`'s steps (``pressure``: which states are pressures)."""
    n = s.size
    J = np.empty((n, n))
    for j in range(n):
        dh = 1e-7 * max(abs(s[j]), 1e3 if pressure[j] else 1e-3)
        sp = s.copy()
        sm = s.copy()
        sp[j] += dh
        sm[j] -= dh
        J[:, j] = (derivatives_at(t, sp, P, net) - derivatives_at(t, sm, P, net)) / (2.0 * dh)
    return J


def circuit_euler_order(n_states: int, n_hydraulic: int, n_mechanical: int):
    """The system kernel's semi-implicit Euler as sequential updates
    (`hydroarm.integrators.system.step`): every state but the mechanical nodes'
    positions and velocities, then the velocities, then the positions."""
    positions = tuple(range(n_hydraulic, n_hydraulic + n_mechanical))
    velocities = tuple(range(n_hydraulic + n_mechanical, n_hydraulic + 2 * n_mechanical))
    rest = tuple(i for i in range(n_states) if i not in positions + velocities)
    return (rest, velocities, positions)


def circuit_step_limit(method: str, step: float, t, states, P, net, pressure, order):
    """None if ``step`` [s] is stable for the system kernel at every row of ``states``
    (Jacobians of `circuit_jacobian` at time t), else the largest stable step [s];
    ``order``: `circuit_euler_order`."""
    if step <= SCAN_LOW:
        return None
    jacobians = [circuit_jacobian(t, s, P, net, pressure) for s in states]
    if all_stable(method, jacobians, step, order):
        return None
    return largest_stable_step_for(method, jacobians, order=order)
