"""Fixed-step integration of the component servo (`hydroarm.core.servo`).

The same two methods as the paper's joint (`hydroarm.integrators.fixed`), on the
servo's state vector:

* ``euler``: the paper's order of eqs. (5)–(7) generalised: every state but the load's
  position and velocity is advanced first (pressures, spool, controller, supply, energies),
  then the velocity from the new pressures, then the position from the new velocity
  (semi-implicit Euler, first order);
* ``rk4``: classical fourth-order Runge–Kutta.

After the smooth update the step applies the non-smooth parts as projections, as the
paper's kernel does: dry friction (`stick_or_slide`, the
one rule), inelastic end stops of the load and of the actuator's stroke, the spool's stroke
limit, the cavitation floor of the chambers and the supply, and the relief valve's opening
range. One compiled step serves a single run and every row of the batch engine
(`run_many`), so the two are equal bit for bit.

`advance_steps` is the one loop (steps from a state); `integrate` runs it from a
state to each record, `run_many` for every row of a parameter table in parallel,
`advance` piece by piece for a caller that owns the clock (a co-simulation master:
`hydroarm.model.servo_stepper`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..core.components import relief_static_opening
from ..core.equations import friction_capacity
from ..core.lever import evaluate
from ..core.servo import (
    LOAD_CRANK,
    N_STATES,
    P_AREA_A,
    P_AREA_B,
    P_F_COULOMB,
    P_F_STATIC,
    P_GB_EXP,
    P_GB_LOSS,
    P_GB_T0,
    P_LOAD,
    P_MASS,
    P_P_CAV,
    P_P_TANK,
    P_Q_MAX,
    P_Q_MIN,
    P_RATED,
    P_RELIEF_CF,
    P_RELIEF_CS,
    P_RELIEF_P,
    P_RELIEF_TAU,
    P_RELIEF_XMAX,
    P_SPOOL_MAX,
    P_SPOOL_ORDER,
    P_STROKE_MAX,
    P_STROKE_MIN,
    P_SUPPLY,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_VV,
    S_XR,
    S_XV,
    SUPPLY_PUMP,
    acceleration,
    actuator_motion,
    servo_rhs,
    spool_demand,
)
from .finite import all_finite
from .fixed import EULER, stick_or_slide


@njit(cache=True, nogil=True, error_model="numpy")
def dry_friction_capacity(s_old, s, breakaway, P):
    """Dry friction capacity [N or N m] at the load over the step from ``s_old`` to ``s``
    (the smooth update's state): the piston's Coulomb (or breakaway) force through the
    lever, plus for a crank load the gearbox's torque and load-dependent loss
    (`friction_capacity`, the paper joint's law) with γ = |A_A·p_A − A_B·p_B| / (A_A·p_rated).
    The lever (a crank's torque arm) is taken at the step's start and the pressures at its
    end, as the paper joint's rule takes them (`hydroarm.integrators.fixed`, and the
    circuit's ``crank_linkage``): the friction's geometry at the configuration the step
    starts from, not at the smooth update's position, which the projection then moves
    (to the start itself when the load sticks)."""
    x, v_x, lever = actuator_motion(s_old[S_Q], s_old[S_V], P)
    f = P[P_F_STATIC] if breakaway else P[P_F_COULOMB]
    drive = P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB]
    if P[P_LOAD] != LOAD_CRANK:
        return f * abs(lever)
    gamma = min(abs(drive) / (P[P_AREA_A] * P[P_RATED]), 1.0)
    return friction_capacity(f, lever, P[P_GB_T0], P[P_GB_LOSS], P[P_GB_EXP], gamma, drive * lever)


@njit(cache=True, nogil=True, error_model="numpy")
def has_dry_friction(P):
    """Whether any dry friction is on (piston, or a crank load's gearbox)."""
    gearbox = P[P_LOAD] == LOAD_CRANK and (P[P_GB_T0] > 0.0 or P[P_GB_LOSS] > 0.0)
    return P[P_F_COULOMB] > 0.0 or P[P_F_STATIC] > 0.0 or gearbox


@njit(cache=True, nogil=True, error_model="numpy")
def project(method, s_old, s, h, t_ref, P):
    """The non-smooth parts of one step, applied to the new state s in place (module doc)."""
    if has_dry_friction(P) and h > 0.0:
        slide = h * dry_friction_capacity(s_old, s, False, P) / P[P_MASS]
        hold = (
            h * dry_friction_capacity(s_old, s, True, P) / P[P_MASS] if s_old[S_V] == 0.0 else slide
        )
        v = stick_or_slide(s_old[S_V], s[S_V], slide, hold)
        if method == EULER:  # the position from the new velocity, eq. (7)
            s[S_Q] = s_old[S_Q] + h * v
        elif v == 0.0 and s_old[S_V] == 0.0:
            s[S_Q] = s_old[S_Q]
        else:  # the friction impulse grows linearly over the step
            s[S_Q] += 0.5 * h * (v - s[S_V])
        s[S_V] = v
    # load end stops, and the actuator's stroke for a load driven directly
    lo = P[P_Q_MIN]
    hi = P[P_Q_MAX]
    if P[P_LOAD] != LOAD_CRANK:
        lo = max(lo, P[P_STROKE_MIN])
        hi = min(hi, P[P_STROKE_MAX])
    if s[S_Q] < lo:
        s[S_Q] = lo
        s[S_V] = max(s[S_V], 0.0)
    elif s[S_Q] > hi:
        s[S_Q] = hi
        s[S_V] = min(s[S_V], 0.0)
    # spool
    lim = P[P_SPOOL_MAX]
    if P[P_SPOOL_ORDER] == 0:
        x, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
        s[S_XV] = spool_demand(t_ref, s, x, v_x, P)[0]
    elif s[S_XV] > lim:
        s[S_XV] = lim
        s[S_VV] = min(s[S_VV], 0.0)
    elif s[S_XV] < -lim:
        s[S_XV] = -lim
        s[S_VV] = max(s[S_VV], 0.0)
    # cavitation floor, relief opening range
    floor = P[P_P_CAV]
    s[S_PA] = max(s[S_PA], floor)
    s[S_PB] = max(s[S_PB], floor)
    s[S_PS] = max(s[S_PS], min(floor, P[P_P_TANK]))
    if P[P_SUPPLY] == SUPPLY_PUMP and P[P_RELIEF_P] < np.inf and not P[P_RELIEF_TAU] > 0.0:
        # static relief valve: its opening is the static one at the new supply pressure
        s[S_XR] = relief_static_opening(
            s[S_PS], P[P_P_TANK], P[P_RELIEF_P], P[P_RELIEF_CS], P[P_RELIEF_CF], P[P_RELIEF_XMAX]
        )
    else:
        s[S_XR] = min(max(s[S_XR], 0.0), P[P_RELIEF_XMAX])


@njit(cache=True, nogil=True, error_model="numpy")
def step(method, t, h, s, out, tab_t, tab_y, sine, P, k1, k2, k3, k4, tmp):
    """Advance state s from t to t + h into ``out`` (work arrays k1…k4, tmp of the state's
    size). The single step of every fixed-step servo path."""
    r0 = evaluate(t, tab_t, tab_y, sine)
    n = s.shape[0]
    if method == EULER:
        servo_rhs(r0, s, P, k1)
        for i in range(n):
            out[i] = s[i] + h * k1[i]
        # velocity from the new pressures (and spool, supply) at the old position
        out[S_Q] = s[S_Q]
        out[S_V] = s[S_V]
        out[S_V] = s[S_V] + h * acceleration(out, P)
        out[S_Q] = s[S_Q] + h * out[S_V]
    else:
        rm = evaluate(t + 0.5 * h, tab_t, tab_y, sine)
        r1 = evaluate(t + h, tab_t, tab_y, sine)
        servo_rhs(r0, s, P, k1)
        for i in range(n):
            tmp[i] = s[i] + 0.5 * h * k1[i]
        servo_rhs(rm, tmp, P, k2)
        for i in range(n):
            tmp[i] = s[i] + 0.5 * h * k2[i]
        servo_rhs(rm, tmp, P, k3)
        for i in range(n):
            tmp[i] = s[i] + h * k3[i]
        servo_rhs(r1, tmp, P, k4)
        c = h / 6.0
        for i in range(n):
            out[i] = s[i] + c * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    project(method, s, out, h, evaluate(t + h, tab_t, tab_y, sine), P)


@njit(cache=True, nogil=True, error_model="numpy")
def advance_steps(method, t0, k0, h, nsteps, s, tab_t, tab_y, sine, P, out, k1, k2, k3, k4, tmp):
    """Take ``nsteps`` steps of `step` from step ``k0`` (time t0 + k0·h), ``s`` in
    place: the one loop of the servo (`integrate` records between its calls;
    `ServoStepper` runs it piece by piece). Step k
    starts at t0 + k·h, the same float whatever pieces the run is cut into.

    Returns (taken, bad): bad = 1 when the last state taken is not finite (the run stops
    there), else 0."""
    for i in range(nsteps):
        t = t0 + (k0 + i) * h
        step(method, t, h, s, out, tab_t, tab_y, sine, P, k1, k2, k3, k4, tmp)
        s[:] = out
        if not all_finite(s):
            return i + 1, 1
    return nsteps, 0


@njit(cache=True, nogil=True, error_model="numpy")
def advance(method, t0, k0, h, nsteps, s, tab_t, tab_y, sine, P):
    """`advance_steps` with its work arrays (a caller stepping piece by piece)."""
    n = s.shape[0]
    return advance_steps(
        method,
        t0,
        k0,
        h,
        nsteps,
        s,
        tab_t,
        tab_y,
        sine,
        P,
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
    )


@njit(cache=True, nogil=True, error_model="numpy")
def start_state(method, t0, s0, tab_t, tab_y, sine, P):
    """The state a run starts from: s0 projected at t0 (an algebraic spool at its demand;
    what `integrate` applies before its first step)."""
    s = s0.copy()
    project(method, s0, s, 0.0, evaluate(t0, tab_t, tab_y, sine), P)
    return s


@njit(cache=True, nogil=True, error_model="numpy")
def integrate(method, s0, t0, h, nsteps, record_every, tab_t, tab_y, sine, P):
    """Run ``nsteps`` fixed steps from state s0, keeping every ``record_every``-th state
    (`advance_steps` between the records).

    Returns (t, states (records × N_STATES), reference, bad_step): bad_step is −1 or the
    first step whose state was not finite; the run stops there (that state is the last)."""
    nrec = nsteps // record_every + 2
    T = np.empty(nrec)
    S = np.empty((nrec, N_STATES))
    R = np.empty(nrec)
    out = np.empty(N_STATES)
    k1 = np.empty(N_STATES)
    k2 = np.empty(N_STATES)
    k3 = np.empty(N_STATES)
    k4 = np.empty(N_STATES)
    tmp = np.empty(N_STATES)
    s = start_state(method, t0, s0, tab_t, tab_y, sine, P)  # x_v of an algebraic spool
    T[0] = t0
    S[0] = s
    R[0] = evaluate(t0, tab_t, tab_y, sine)
    j = 1
    bad = -1
    k = 0
    while k < nsteps:  # to the next record, or to the end
        m = min(record_every - k % record_every, nsteps - k)
        taken, failed = advance_steps(
            method, t0, k, h, m, s, tab_t, tab_y, sine, P, out, k1, k2, k3, k4, tmp
        )
        k += taken
        if failed:
            bad = k
        if k % record_every == 0 or failed:
            tk = t0 + k * h
            T[j] = tk
            S[j] = s
            R[j] = evaluate(tk, tab_t, tab_y, sine)
            j += 1
        if failed:
            break
    return T[:j], S[:j], R[:j], bad


@njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def run_many(method, S0, t0, h, nsteps, record_every, tab_t, tab_y, sine, table):
    """`integrate` for every row of a parameter table (one scenario a row, initial
    states S0 row by row), in parallel; returns (t, states (rows × records × N_STATES),
    bad_step per row). A row's run is the single run's, bit for bit."""
    n = table.shape[0]
    nrec = nsteps // record_every + 1
    out = np.full((n, nrec, N_STATES), np.nan)
    bad = np.empty(n, np.int64)
    T = t0 + (np.arange(nrec) * record_every) * h  # integrate's t0 + k·h, bit for bit
    for i in prange(n):
        t, S, R, b = integrate(
            method, S0[i], t0, h, nsteps, record_every, tab_t, tab_y, sine, table[i]
        )
        m = min(S.shape[0], nrec)
        out[i, :m] = S[:m]
        bad[i] = b
    return T, out, bad
