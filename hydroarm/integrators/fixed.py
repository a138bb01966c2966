"""Fixed-step integrators sharing one step kernel.

``euler`` is the paper's rectangular scheme, eqs. (5)–(7) of Appendix I, applied in the
order the paper prints it: the pressure is advanced first (eq. 5, ``p_K = p_{K-1} + T·ṗ_K``),
the angular velocity from the new pressure (eq. 6) and the angle from the new velocity
(eq. 7). That is a semi-implicit (symplectic) Euler method, first order. ``rk4`` is the
classical fourth-order Runge–Kutta method on the same right-hand side.

Non-smooth physics options are applied by the same kernel after the smooth update, as a
projection of the velocity (a time-stepping, Moreau-type treatment; docs/physics.md):

* dry friction (piston Coulomb/stiction, gearbox loss): with v* the velocity the step
  reaches without dry friction and ΔV = h·T_f/I the velocity the friction torque T_f can
  remove in one step, the joint sticks (ω = 0 exactly) if |v*| ≤ ΔV (stiction capacity
  when it was at rest), and otherwise slides with ω = v* − sgn(v*)·ΔV (Coulomb);
* end stops: an inelastic stop at |θ₂| = θ_stop;
* the cavitation floor of the orifice valve: |p| ≤ p_s + 2·p_atm.

For ``euler`` the projection is exact for the semi-implicit scheme; for ``rk4`` it is an
operator split (first order in the friction impulse, fourth order elsewhere).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..core.equations import (
    angular_acceleration,
    crank_reach,
    derivatives,
    dry_friction_torque,
    pressure_bound,
    pressure_limit,
    pressure_rate,
    stick_or_slide,
)
from ..core.lever import evaluate
from ..core.params import VALVE_ORIFICE

EULER = 0
RK4 = 1


@njit(cache=True, nogil=True, error_model="numpy")
def step_once(method, t, h, theta, omega, p, tab_t, tab_y, sine, J, L):
    """Advance (θ₂, ω, p) from t to t + h. The single step kernel of every fixed-step path."""
    y0 = evaluate(t, tab_t, tab_y, sine)
    if method == EULER:
        return advance(method, h, theta, omega, p, y0, y0, y0, J, L)
    return advance(
        method,
        h,
        theta,
        omega,
        p,
        y0,
        evaluate(t + 0.5 * h, tab_t, tab_y, sine),
        evaluate(t + h, tab_t, tab_y, sine),
        J,
        L,
    )


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def advance(method, h, theta, omega, p, y0, ym, y1, J, L):
    """One step given the lever at the start, middle and end of the step (`step_once`;
    the batch engine calls it directly with its step input)."""
    if method == EULER:
        p1 = p + h * pressure_rate(theta, omega, p, y0, J)  # eq. (5)
        if J.valve_model == VALVE_ORIFICE:
            p1 = _floor_pressure(p1, J)
        omega1 = omega + h * angular_acceleration(theta, omega, p1, J, L)  # eq. (6)
        if J.dry_friction:
            omega1 = _dry_friction(omega, omega1, theta, p1, h, J, L)
        theta1 = theta + h * omega1  # eq. (7)
        if theta1 > J.end_stop_angle or theta1 < -J.end_stop_angle:
            theta1, omega1 = _end_stop(theta1, omega1, J)
        return theta1, omega1, p1
    # classical RK4
    k1a, k1b, k1c = derivatives(theta, omega, p, y0, J, L)
    k2a, k2b, k2c = derivatives(
        theta + 0.5 * h * k1a, omega + 0.5 * h * k1b, p + 0.5 * h * k1c, ym, J, L
    )
    k3a, k3b, k3c = derivatives(
        theta + 0.5 * h * k2a, omega + 0.5 * h * k2b, p + 0.5 * h * k2c, ym, J, L
    )
    k4a, k4b, k4c = derivatives(theta + h * k3a, omega + h * k3b, p + h * k3c, y1, J, L)
    s = h / 6.0
    theta1 = theta + s * (k1a + 2.0 * k2a + 2.0 * k3a + k4a)
    omega1 = omega + s * (k1b + 2.0 * k2b + 2.0 * k3b + k4b)
    p1 = p + s * (k1c + 2.0 * k2c + 2.0 * k3c + k4c)
    return rk4_projections(h, theta, omega, theta1, omega1, p1, J, L)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def rk4_projections(h, theta, omega, theta1, omega1, p1, J, L):
    """The non-smooth physics applied after a smooth RK4 update (θ, ω) → (θ₁, ω₁, p₁) (module
    doc): cavitation floor, dry friction, end stops. Shared with the whole arm's coupled RK4
    (`hydroarm.reference.arm_decoupled.arm_integrate`), so that a joint alone in the arm is
    the single joint, friction included."""
    if J.valve_model == VALVE_ORIFICE:
        p1 = _floor_pressure(p1, J)
    if J.dry_friction:
        w = _dry_friction(omega, omega1, theta, p1, h, J, L)
        # the friction impulse grows linearly over the step: the angle loses h·Δω/2
        theta1 = theta if (w == 0.0 and omega == 0.0) else theta1 + 0.5 * h * (w - omega1)
        omega1 = w
    if theta1 > J.end_stop_angle or theta1 < -J.end_stop_angle:
        theta1, omega1 = _end_stop(theta1, omega1, J)
    return theta1, omega1, p1


@njit(cache=True, nogil=True, error_model="numpy")
def _dry_friction(omega, v_star, theta, p, h, J, L):
    """Velocity after one step of dry friction (stick or Coulomb slide), see module doc."""
    slide = h * dry_friction_torque(theta, p, False, J) / L.inertia
    hold = h * dry_friction_torque(theta, p, True, J) / L.inertia if omega == 0.0 else slide
    return stick_or_slide(omega, v_star, slide, hold)


@njit(cache=True, nogil=True, error_model="numpy")
def _end_stop(theta, omega, J):
    """Inelastic end stop at |θ₂| = θ_stop."""
    lim = J.end_stop_angle
    if theta > lim:
        return lim, min(omega, 0.0)
    return -lim, max(omega, 0.0)


@njit(cache=True, nogil=True, error_model="numpy")
def _floor_pressure(p, J):
    """Cavitation floor of the orifice valve: no chamber below zero absolute pressure."""
    lim = pressure_limit(J)
    return min(max(p, -lim), lim)


@njit(cache=True, nogil=True, error_model="numpy")
def integrate(method, theta0, omega0, p0, t0, h, nsteps, record_every, tab_t, tab_y, sine, J, L):
    """Run ``nsteps`` fixed steps, keeping every ``record_every``-th state.

    Returns (t, θ₂, ω, p, y, bad_step) where bad_step is −1 or the first step whose state
    left the physical bounds (`in_bounds`); the run stops there and that state is the
    last one returned, so that the caller can tell what went wrong.
    """
    nrec = nsteps // record_every + 2
    T = np.empty(nrec)
    TH = np.empty(nrec)
    OM = np.empty(nrec)
    PP = np.empty(nrec)
    Y = np.empty(nrec)
    theta, omega, p = theta0, omega0, p0
    p_max = pressure_bound(p0, J, L)
    th_max = crank_reach(J)
    T[0] = t0
    TH[0] = theta
    OM[0] = omega
    PP[0] = p
    Y[0] = evaluate(t0, tab_t, tab_y, sine)
    j = 1
    bad = -1
    for k in range(1, nsteps + 1):
        t = t0 + (k - 1) * h
        theta, omega, p = step_once(method, t, h, theta, omega, p, tab_t, tab_y, sine, J, L)
        if not in_bounds(theta, omega, p, th_max, p_max):
            bad = k
        if k % record_every == 0 or bad >= 0:
            tk = t0 + k * h
            T[j] = tk
            TH[j] = theta
            OM[j] = omega
            PP[j] = p
            Y[j] = evaluate(tk, tab_t, tab_y, sine)
            j += 1
        if bad >= 0:
            break
    return T[:j], TH[:j], OM[:j], PP[:j], Y[:j], bad


@njit(cache=True, nogil=True, error_model="numpy")
def advance_steps(method, t0, k0, h, nsteps, theta, omega, p, p_max, tab_t, tab_y, sine, J, L):
    """Take ``nsteps`` steps of `step_once` from step ``k0`` (time t0 + k0·h [s]) and
    state (θ₂ [rad], ω [rad/s], p [Pa]), recording nothing: the loop of `integrate`
    without its records, for a run advanced piece by piece (the steppers of
    `hydroarm.model.stepper`). ``p_max`` [Pa] is the pressure bound of the run's start.

    Returns (θ₂, ω, p, taken, bad): the state after ``taken`` steps and bad = 1 when the last
    step left the physical bounds (`in_bounds`; the run stops there), else 0.
    """
    th_max = crank_reach(J)
    for i in range(nsteps):
        t = t0 + (k0 + i) * h
        theta, omega, p = step_once(method, t, h, theta, omega, p, tab_t, tab_y, sine, J, L)
        if not in_bounds(theta, omega, p, th_max, p_max):
            return theta, omega, p, i + 1, 1
    return theta, omega, p, nsteps, 0


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def in_bounds(theta, omega, p, th_max, p_max):
    """Whether a state is finite, short of the crank's dead centre (|θ₂| < n·90°) and below the
    pressure bound (`pressure_bound`). Branch-free (the batch
    engine folds it into its ``alive`` flag)."""
    return (abs(theta) < th_max) & (abs(omega) < np.inf) & (abs(p) < p_max)


# why a run left the physical bounds (the batch engine's ``failed`` metric holds the code)
OK = 0
UNSTABLE = 1  # a non-finite state
OUT_OF_BOUNDS = 2  # |p| above the pressure bound
PAST_DEAD_CENTRE = 3  # |θ₂| at or beyond the crank's reach n·90°
FAILURES = {
    UNSTABLE: "unstable",
    OUT_OF_BOUNDS: "out_of_bounds",
    PAST_DEAD_CENTRE: "past_dead_centre",
}


@njit(cache=True, nogil=True, error_model="numpy")
def failure_code(theta, omega, p, th_max, p_max):
    """`OK` or why a state is out of bounds (first match: non-finite, past the dead
    centre, pressure)."""
    if not (np.isfinite(theta) and np.isfinite(omega) and np.isfinite(p)):
        return UNSTABLE
    if abs(theta) >= th_max:
        return PAST_DEAD_CENTRE
    if abs(p) >= p_max:
        return OUT_OF_BOUNDS
    return OK
