"""The steppers of the system kernel (`hydroarm.core.circuit.system`; issue 28).

One stepper family over the one right-hand side, with one projection hook:

* ``euler``: the paper's semi-implicit Euler generalised (its eqs. (5)–(7)): every state but
  the mechanical nodes' positions and velocities is advanced first (pressures, spools,
  controllers, lines), then the velocities from the accelerations at the new pressures,
  then the positions from the new velocities; first order, symplectic in the mechanics;
* any explicit Runge–Kutta method from its Butcher tableau (`TABLEAUS`: ``rk4``, the
  classical method; ``heun``; ``midpoint``); one loop serves them all.

After the smooth update every step calls `system_project`
(stops, dry friction, latches, the cavitation floor): for dry friction this is the
time-stepping (Moreau) treatment of the paper's joint, `hydroarm.integrators.fixed.stick_or_slide`
applied to the velocity the smooth step reaches. Friction is set-valued at rest; putting sgn(v)
inside the Runge–Kutta stages would chatter there and never stick, so the projection is the one
consistent place for it, for every method. The friction impulse moves the positions as the stepper
moves them with velocities: by the whole step after Euler (its positions advance with the final
velocity, the paper's eq. (7)), by half of it after a Runge–Kutta step (`POSITION_SHARE_EULER`), the
rules of the paper joint's two steppers (`hydroarm.integrators.fixed`).

`advance_steps` is the one loop (steps from a state); `integrate` runs it from a
state to each record (every ``record_every``-th state), `run_many` for every row of a
parameter table in parallel, `advance` piece by piece for a caller that owns the clock
(a co-simulation master: `hydroarm.model.circuit_stepper`), `advance_records` piece by
piece with `integrate`'s records (`record_steps`, the records of both).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..core.circuit.dispatch import follows_components
from ..core.circuit.laws import (
    POSITION_SHARE_EULER,
    POSITION_SHARE_RUNGE_KUTTA,
    inlined_kernel,
    kernel,
)
from ..core.circuit.system import make_work, system_project, system_rhs, with_derived
from .finite import all_finite

SEMI_IMPLICIT_EULER = 0
RUNGE_KUTTA = 1

#: explicit Runge–Kutta methods: (A, b, c) of the Butcher tableau
TABLEAUS: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {
    "rk4": (
        np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]]),
        np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
        np.array([0.0, 0.5, 0.5, 1.0]),
    ),
    "heun": (np.array([[0, 0], [1.0, 0]]), np.array([0.5, 0.5]), np.array([0.0, 1.0])),
    "midpoint": (np.array([[0, 0], [0.5, 0]]), np.array([0.0, 1.0]), np.array([0.0, 0.5])),
}
#: the stepper names a circuit accepts: the paper's Euler and the tableaus
STEPPERS = ("euler", *TABLEAUS)


def stepper(name: str) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """(code, A, b, c) of a stepper name (Euler's tableau is unused and empty)."""
    if name == "euler":
        z = np.zeros((1, 1))
        return SEMI_IMPLICIT_EULER, z, np.zeros(1), np.zeros(1)
    A, b, c = TABLEAUS[name]
    return RUNGE_KUTTA, np.ascontiguousarray(A, dtype=np.float64), b.copy(), c.copy()


@inlined_kernel
def step(code, A, b, c, t, h, s, out, P, net, work, K, tmp):
    """Advance s from t to t + h into ``out`` (K: stages × states, tmp: a state's size).

    One call of the right-hand side in the code, in a loop over its evaluations (Euler's
    two, a tableau's stages), and one of the projection: both are compiled into the step
    (`inlined_kernel`), once each."""
    n = s.shape[0]
    dims = net[9]
    nh, nm = dims[0], dims[1]
    # the states a stage reads: all but the energy account's, which no rate reads
    # (`hydroarm.core.circuit.system`; net[31]: its rows, the first's first state the
    # first of the account's): their stages' values are never formed
    read = net[31][0, 5] if net[31].shape[0] > 0 else n
    euler = code == SEMI_IMPLICIT_EULER
    evaluations = 2 if euler else b.shape[0]
    for j in range(evaluations):
        if euler:  # at s, then at s with the new pressures (the mechanics still old)
            x = s if j == 0 else out
            tj = t
            kj = 0
        else:  # the stage's state, s[i] + Σ_l h·a_jl·K_li added in l order, a stage a pass
            for i in range(n):
                tmp[i] = s[i]
            for l in range(j):
                a = A[j, l]
                if a != 0.0:
                    ha = h * a
                    for i in range(read):
                        tmp[i] += ha * K[l, i]
            x = tmp
            tj = t + c[j] * h
            kj = j
        system_rhs(tj, x, P, net, work, K[kj])
        if euler and j == 0:
            for i in range(n):
                out[i] = s[i] + h * K[0, i]
            for m in range(nh, nh + 2 * nm):  # mechanics at the old state for now
                out[m] = s[m]
    if euler:  # the velocities from the accelerations at the new pressures, then positions
        for m in range(nm):
            v = s[nh + nm + m] + h * K[0, nh + nm + m]
            out[nh + nm + m] = v
            out[nh + m] = s[nh + m] + h * v
    else:  # Σ_j b_j·K_ji in j order (in tmp, free now), a stage a pass
        for i in range(n):
            tmp[i] = 0.0
        for j in range(evaluations):
            bj = b[j]
            for i in range(n):
                tmp[i] += bj * K[j, i]
        for i in range(n):
            out[i] = s[i] + h * tmp[i]
    share = POSITION_SHARE_EULER if euler else POSITION_SHARE_RUNGE_KUTTA
    system_project(t + h, h, s, out, P, net, work, share)


@kernel
def advance_steps(code, A, b, c, t0, k0, h, nsteps, s, P, net, work, out, K, tmp):
    """Take ``nsteps`` steps of `step` from step ``k0`` (time t0 + k0·h), ``s`` in
    place: the one loop of the system kernel (`integrate` records between its calls;
    `CircuitStepper` runs it piece by piece). Step k
    starts at t0 + k·h, the same float whatever pieces the run is cut into.

    Returns (taken, bad): bad = 1 when the last state taken is not finite (the run stops
    there), else 0."""
    for i in range(nsteps):
        if not take_step(code, A, b, c, t0, k0 + i, h, s, P, net, work, out, K, tmp):
            return i + 1, 1
    return nsteps, 0


@inlined_kernel
def take_step(code, A, b, c, t0, k, h, s, P, net, work, out, K, tmp):
    """Step ``k`` of a run, from t0 + k·h, ``s`` in place: the body of `advance_steps`'
    loop, compiled into it and into the observers' (`hydroarm.integrators.observers`), so
    that a caller that does something after every step steps without a call a step (a
    call copies the net's and the work's arrays, some 500 words). Returns whether the new
    state is finite."""
    t = t0 + k * h
    step(code, A, b, c, t, h, s, out, P, net, work, K, tmp)
    for j in range(s.shape[0]):  # (s[:] = out would ask for numba's allocator)
        s[j] = out[j]
    return all_finite(s)


@njit(cache=True, nogil=True, error_model="numpy")
def step_buffers(b, n):
    """A step's scratch arrays for ``n`` states (`step`): the new state, the tableau's
    stages (a row a stage of weights ``b``; one for Euler) and a stage's state."""
    return np.empty(n), np.empty((max(b.shape[0], 1), n)), np.empty(n)


@njit(cache=True, nogil=True, error_model="numpy")
def advance(code, A, b, c, t0, k0, h, nsteps, s, P, net):
    """`advance_steps` with its work arrays (a caller stepping piece by piece)."""
    P = with_derived(P, net)
    n = s.shape[0]
    work = make_work(net)
    out, K, tmp = step_buffers(b, n)
    return advance_steps(code, A, b, c, t0, k0, h, nsteps, s, P, net, work, out, K, tmp)


@njit(cache=True, nogil=True, error_model="numpy")
def start_state(t0, s0, P, net):
    """The state a run starts from: s0 with its sources and latches at t0 (the projection
    `integrate` applies before its first step)."""
    s = s0.copy()
    system_project(t0, 0.0, s0, s, with_derived(P, net), net, make_work(net), 1.0)
    return s


@njit(cache=True, nogil=True, error_model="numpy")
def integrate(code, A, b, c, s0, t0, h, nsteps, record_every, P, net):
    """Run ``nsteps`` fixed steps from s0 at t0, keeping every ``record_every``-th state.

    Returns (t, states (records × states), bad_step): bad_step is −1 or the first step whose
    state was not finite; the run stops there (that state is the last record). The
    parameters' derived quantities are computed here, once a run
    (`with_derived`)."""
    P = with_derived(P, net)
    n = s0.shape[0]
    nrec = nsteps // record_every + 2
    T = np.empty(nrec)
    S = np.empty((nrec, n))
    work = make_work(net)
    s = s0.copy()
    out, K, tmp = step_buffers(b, n)
    system_project(t0, 0.0, s0, s, P, net, work, 1.0)  # sources and latches at the start
    T[0] = t0
    S[0] = s
    taken, j, failed = record_steps(
        code, A, b, c, t0, 0, h, nsteps, record_every, s, P, net, work, out, K, tmp, T[1:], S[1:]
    )
    return T[: j + 1], S[: j + 1], taken if failed else -1


@kernel
def record_steps(
    code, A, b, c, t0, k0, h, nsteps, record_every, s, P, net, work, out, K, tmp, T, S
):
    """Take ``nsteps`` steps of `advance_steps` from step ``k0``, ``s`` in place, keeping in
    (T, S) the time and state after every step k (counted from t0) with k a multiple of
    ``record_every``, and the state at which the run stops when it is not finite: the
    records of `integrate` (which calls it) and of `advance_records`. Returns (steps taken
    from k0, records kept, whether the run stopped at a state not finite)."""
    j = 0
    failed = 0
    k = k0
    end = k0 + nsteps
    while k < end:  # to the next record, or to the end
        m = min(record_every - k % record_every, end - k)
        taken, failed = advance_steps(code, A, b, c, t0, k, h, m, s, P, net, work, out, K, tmp)
        k += taken
        if k % record_every == 0 or failed:
            T[j] = t0 + k * h
            for i in range(s.shape[0]):
                S[j, i] = s[i]
            j += 1
        if failed:
            break
    return k - k0, j, failed


@njit(cache=True, nogil=True, error_model="numpy")
def advance_records(code, A, b, c, t0, k0, h, nsteps, record_every, s, P, net):
    """`advance` keeping `integrate`'s records on the way (`record_steps`): a run advanced
    piece by piece whose pieces record as the whole run does (a probe that stops once its
    answer is decided, `hydroarm.model.circuit_stepper.CircuitStepper.record`). Returns
    (steps taken, T, S, bad: 1 when the last state is not finite, else 0)."""
    P = with_derived(P, net)
    n = s.shape[0]
    work = make_work(net)
    out, K, tmp = step_buffers(b, n)
    nrec = (k0 + nsteps) // record_every - k0 // record_every + 1
    T = np.empty(nrec)
    S = np.empty((nrec, n))
    taken, j, failed = record_steps(
        code, A, b, c, t0, k0, h, nsteps, record_every, s, P, net, work, out, K, tmp, T, S
    )
    return taken, T[:j], S[:j], failed


@njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def run_many(code, A, b, c, S0, t0, h, nsteps, record_every, table, net):
    """`integrate` for every row of a parameter table (initial states S0 row by row),
    in parallel: (t, states (rows × records × states), bad_step per row). A row's run is
    the single run's, bit for bit."""
    rows = table.shape[0]
    n = S0.shape[1]
    nrec = nsteps // record_every + 1
    out = np.full((rows, nrec, n), np.nan)
    bad = np.empty(rows, np.int64)
    T = t0 + (np.arange(nrec) * record_every) * h
    for i in prange(rows):
        t, S, bb = integrate(code, A, b, c, S0[i], t0, h, nsteps, record_every, table[i], net)
        m = min(S.shape[0], nrec)
        out[i, :m] = S[:m]
        bad[i] = bb
    return T, out, bad


@kernel
def rhs_into(t, s, P, net, work, d):
    """`system_rhs` as a call, free of numba's reference counting: for the functions that
    have it (`derivatives_at`), into which the right-hand side's parts compiled in
    (`inlined_kernel`) must not be compiled: numba's reference counting of the net's and
    the work's arrays there aborted the process."""
    system_rhs(t, s, P, net, work, d)


@njit(cache=True, nogil=True, error_model="numpy")
def derivatives_at(t, s, P, net):
    """ṡ at (t, s) (for the adaptive reference and the linear view)."""
    P = with_derived(P, net)
    work = make_work(net)
    d = np.empty(s.shape[0])
    rhs_into(t, s, P, net, work, d)
    return d


follows_components(
    step,
    take_step,
    advance_steps,
    advance,
    start_state,
    integrate,
    record_steps,
    advance_records,
    run_many,
    rhs_into,
    derivatives_at,
)
