"""Adaptive, stiff-safe reference integrator (scipy's Radau IIA, order 5).

Same right-hand side as the fixed-step methods (`hydroarm.core.equations.derivatives`).
Used as the reference against which the fixed-step results are checked.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..core.circuit.components import KIND
from ..core.circuit.components.signal_source import corners as signal_corners
from ..core.circuit.laws import POSITION_SHARE_RUNGE_KUTTA
from ..core.circuit.system import make_work, system_project, system_rhs, with_derived
from ..core.equations import derivatives
from ..core.lever import evaluate
from ..errors import HydroarmError

SIGNAL_SOURCE_KIND = KIND["signal_source"]


def integrate_adaptive(
    theta0, omega0, p0, t0, t_end, t_eval, tab_t, tab_y, sine, J, L, rtol=1e-10, atol=None
):
    """Integrate with Radau from t0 to t_end, sampled at ``t_eval``.

    Breakpoints of the input table (steps, ramp corners) are integrated as separate
    segments so the solver never steps across a discontinuity.
    """
    from scipy.integrate import solve_ivp  # imported here: keeps the fixed-step start fast

    if atol is None:
        # θ [rad], ω [rad/s], p [Pa]
        atol = np.array([1e-12, 1e-10, 1e-4])

    def rhs(t, s):
        y = evaluate(t, tab_t, tab_y, sine)
        a, b, c = derivatives(s[0], s[1], s[2], y, J, L)
        return np.array([a, b, c])

    breaks = sorted({float(b) for b in tab_t if t0 < b < t_end})
    edges = [t0, *breaks, t_end]
    state = np.array([theta0, omega0, p0], dtype=float)
    out = np.empty((3, t_eval.size))
    out[:, 0] = state
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        mask = (t_eval > a) & (t_eval <= b)
        seg = t_eval[mask]
        ask = seg if seg.size and seg[-1] == b else np.append(seg, b)
        sol = solve_ivp(rhs, (a, b), state, method="Radau", t_eval=ask, rtol=rtol, atol=atol)
        if sol.status < 0:
            raise RuntimeError(f"adaptive integration failed: {sol.message}")
        out[:, mask] = sol.y[:, : seg.size]
        state = sol.y[:, -1]
    return out[0], out[1], out[2]


#: absolute tolerances of the circuit's adaptive method by a state's unit (positions,
#: velocities, pressures, energies, angles): far below any physical resolution, and
#: above the round-off of a state of that unit's usual size
STATE_ATOL = {"m": 1e-10, "m/s": 1e-8, "rad": 1e-10, "rad/s": 1e-8, "Pa": 1e-3, "J": 1e-6}
#: a projection that moves the state by more than this many of the solver's tolerances
#: (atol + rtol·|s|) is an event (a stop hit, a latch, friction's impulse): the solver
#: goes on from the projected state with no stages extrapolated across it and its step
#: size predicted afresh; a smaller move (the cavitation floor holding a node that Radau's
#: stages took below it, a linkage's slave back on its master) only replaces its state
EVENT_TOLERANCES = 1.0
#: an event of the mechanical states (an end stop's hit, friction's stick) is located
#: within the step where it starts, by bisection on the dense output, to this fraction of
#: the step
LOCATE_TO = 1e-6


def state_atol(units, s0):
    """The absolute tolerance [the state's unit] of each state of a circuit for
    `integrate_circuit_adaptive`, from its unit (``STATE_ATOL``); a state of another unit
    (a spool's, a filter's, a signal's): 1e-9 of its start's size, at least 1e-9."""
    s0 = np.asarray(s0, dtype=float)
    out = np.maximum(np.abs(s0), 1.0) * 1e-9
    for i, unit in enumerate(units):
        if unit in STATE_ATOL:
            out[i] = STATE_ATOL[unit]
    return out


def last_factor(lu):
    """``lu`` remembering its last factorisation of each kind (real, complex): scipy's
    Radau factorises its iteration matrices afresh after a step that wanted to grow past
    ``max_step``, the same matrices again."""
    last: dict[str, tuple[bytes, object]] = {}

    def factor(A):
        key = A.tobytes()
        hit = last.get(A.dtype.char)
        if hit is not None and hit[0] == key:
            return hit[1]
        out = lu(A)
        last[A.dtype.char] = (key, out)
        return out

    return factor


def signal_breakpoints(P, net, t0, t1):
    """The instants in (t0, t1) where a signal source's value or slope jumps (its steps,
    its table's corners, its ramp's ends, its sine's start), sorted: the adaptive method
    integrates between them, never across one."""
    found = set()
    for row in net[29]:
        if int(row[1]) == SIGNAL_SOURCE_KIND:
            for b in signal_corners(P, int(row[2])):
                if t0 < b < t1:
                    found.add(float(b))
    return sorted(found)


def integrate_circuit_adaptive(
    s0, t_eval, P, net, rtol=1e-8, atol=None, max_step=np.inf, held=(), held_step=np.inf
):
    """A circuit (`hydroarm.core.circuit.system.system_rhs`) with Radau, sampled at
    ``t_eval`` (t_eval[0]: the start). Returns the states (len(t_eval) × states).

    Scipy's Radau is stepped step by step, between the signal sources' breakpoints
    (`signal_breakpoints`), with the records filled from each step's dense output: the
    result does not depend on the record spacing. After every accepted step the system's
    projection (`hydroarm.core.circuit.system.system_project`: the cavitation floor, stops,
    dry friction, latches, a spool's stroke, linkages' slaves, a line's wave history) acts
    on the step's end state, over that step, and the solver goes on from the projected
    state (an event where it moved by more than the tolerance, ``EVENT_TOLERANCES``): a
    non-smooth part is resolved at the solver's own, error-controlled step, not at the
    records. Where the projection starts to move a mechanical node's position or velocity
    (an end stop's hit, friction's stick) by more than the tolerance after a step where it
    did not, the instant is located by bisection on the step's dense output (to
    ``LOCATE_TO`` of the step), the step ends there and the solver starts afresh from the
    projected state; a node's floor (the right-hand side's own kink) and a component's
    projected states (a static relief valve's opening, which follows its pressure) are not
    located. A record inside a step is the dense output projected as if the step ended
    there. The ``held`` states (indices: a line's wave history, `declare.State`), whose
    derivative is always 0 and which only the projection writes, are not the solver's:
    they are held over each step and updated by its projection, which is then no event
    (the line's history is written at every step; as solver states it reset Radau's step
    predictor and stage extrapolation at every step, and its hundreds of constant states
    filled the Jacobian and its factorisations and diluted the error norm). The Jacobian
    is taken by one-sided differences, the smaller slope of the two (``jac`` below): on a
    node held at the cavitation floor scipy's forward difference sees the floor's jump as
    a huge stiffness, which damps Radau's error estimate until it steps over the node's
    release. ``atol``: per state (`state_atol`), default 1e-9 of each state's start size,
    at least 1e-9; ``max_step`` [s]: the longest step; ``held_step`` [s]: within a longer
    step, the held states are also projected along the dense output at most this far apart
    (a line's history then holds the waves as finely as a fixed step of ``held_step``
    writes them, not only at Radau's step ends)."""
    from scipy.integrate import Radau

    P = with_derived(P, net)
    work = make_work(net)
    d = np.empty(len(s0))
    hold = np.zeros(len(s0), dtype=bool)
    hold[np.asarray(held, dtype=np.int64)] = True
    free = np.flatnonzero(~hold)  # the solver's states
    full = np.array(s0, dtype=float)  # the state the right-hand side sees: held, then y

    def rhs(t, y):
        full[free] = y
        system_rhs(t, full, P, net, work, d)
        return d[free]

    if atol is None:
        atol = state_atol((), s0)
    atol = np.broadcast_to(np.asarray(atol, dtype=float), (len(s0),))[free].copy()
    # the finite-difference increment of each state: √ε of its size, or of the size at
    # which its relative tolerance takes over from its absolute one
    floor_size = atol / rtol
    e = np.eye(free.size)

    def jac(t, s):
        """The Jacobian by one-sided differences both ways, the smaller of the two slopes
        where they agree in sign and none where they do not (minmod): the slope of the
        branch the right-hand side is on where it has a kink or a jump (a node held at the
        cavitation floor, whose pressure cannot fall, has none), the derivative elsewhere."""
        f = rhs(t, s)
        out = np.empty((len(s), len(s)))
        step = np.sqrt(np.finfo(float).eps) * np.maximum(np.abs(s), floor_size)
        for j in range(len(s)):
            up = (rhs(t, s + step[j] * e[j]) - f) / step[j]
            down = (f - rhs(t, s - step[j] * e[j])) / step[j]
            out[:, j] = np.where(
                up * down > 0.0, np.where(np.abs(up) < np.abs(down), up, down), 0.0
            )
        return out

    t_eval = np.asarray(t_eval, dtype=float)
    state = np.array(s0, dtype=float)
    system_project(float(t_eval[0]), 0.0, state.copy(), state, P, net, work, 1.0)
    out = np.empty((t_eval.size, state.size))
    out[0] = state
    t0, t_end = float(t_eval[0]), float(t_eval[-1])
    edges = [t0, *signal_breakpoints(P, net, t0, t_end), t_end]
    share = POSITION_SHARE_RUNGE_KUTTA
    k = 1  # the next record
    after_event = False  # whether the last step's projection was a mechanical event
    # the mechanical nodes' positions and velocities: an end stop's hit, friction's stick
    nh, nm = int(net[9][0]), int(net[9][1])
    located = (free >= nh) & (free < nh + 2 * nm)

    def acts(t, start, tm, y):
        """Whether the projection over (t, tm] of the state y at tm (the held states as at
        the start) is an event: moves a state by more than ``EVENT_TOLERANCES``."""
        sub = start.copy()
        sub[free] = y
        system_project(tm, tm - t, start, sub, P, net, work, share)
        moved = np.abs(sub[free] - y) / (atol + rtol * np.abs(sub[free]))
        return np.max(moved[located], initial=0.0) > EVENT_TOLERANCES

    with warnings.catch_warnings():
        # scipy's finite-difference Jacobian grows its increments past overflow on the
        # energy states (they feed nothing back); harmless, and not the user's concern
        warnings.simplefilter("ignore", RuntimeWarning)
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            t = a
            full[:] = state
            solver = None
            while t < b:
                if solver is None:  # the segment's start, or a located event
                    solver = Radau(
                        rhs, t, state[free], b, rtol=rtol, atol=atol, jac=jac, max_step=max_step
                    )
                    solver.lu = last_factor(solver.lu)
                solver.step()
                if solver.status == "failed":
                    raise HydroarmError(
                        "solver.method",
                        f"the adaptive method failed at t = {t:.6g} s ({solver.message}): "
                        "use a fixed-step method (rk4) at a small step",
                    )
                t_new, reached = solver.t, solver.y
                dense = solver.dense_output()
                restart = False
                if not after_event and acts(t, state, t_new, reached):
                    # the projection starts to act on a mechanical node within the step (a
                    # stop hit, friction's stick): its instant, by bisection on the dense
                    # output, ends the step there
                    lo, hi = t, t_new
                    while hi - lo > LOCATE_TO * (t_new - t):
                        mid = 0.5 * (lo + hi)
                        if acts(t, state, mid, dense(mid)):
                            hi = mid
                        else:
                            lo = mid
                    if hi < t_new:
                        t_new, reached, restart = hi, dense(hi), True
                new = state.copy()  # the held states as over the step
                # the held states projected along the dense output at most held_step
                # apart (a line's history written as finely as a fixed step writes it):
                # (time, held states) from the step's start
                marks = [(t, state[hold])]
                if marks[0][1].size and t_new - t > held_step:
                    m = math.ceil((t_new - t) / held_step)
                    for i in range(1, m):
                        tc = t + (t_new - t) * i / m
                        new[free] = dense(tc)
                        system_project(tc, tc - t, state, new, P, net, work, share)
                        new[free] = state[free]
                        marks.append((tc, new[hold]))
                new[free] = reached
                system_project(t_new, t_new - t, state, new, P, net, work, share)
                while k < t_eval.size and t_eval[k] < t_new:
                    # projected as if the step ended there, from the held states' last
                    # mark before it
                    rec = state.copy()
                    rec[hold] = next(h for tm, h in reversed(marks) if tm <= t_eval[k])
                    rec[free] = dense(t_eval[k])
                    system_project(t_eval[k], t_eval[k] - t, state, rec, P, net, work, share)
                    out[k] = rec
                    k += 1
                while k < t_eval.size and t_eval[k] == t_new:
                    out[k] = new
                    k += 1
                moved = np.abs(new[free] - reached)
                renewed = np.any(new[hold] != state[hold])
                full[:] = new
                moves = moved / (atol + rtol * np.abs(new[free]))
                event = np.max(moves, initial=0.0) > EVENT_TOLERANCES
                # a mechanical node held by its projection (at rest on a stop, stuck): no
                # new instant to locate until it is left free over a step
                after_event = np.max(moves[located], initial=0.0) > EVENT_TOLERANCES
                if restart:
                    solver = None  # a fresh start from the event: step size, Jacobian
                elif renewed or np.any(moved > 0.0):
                    # the solver goes on from the projected state, its slope there
                    solver.y = new[free]
                    solver.f = rhs(t_new, solver.y)
                    if event:
                        # an event (a stop hit, a latch, friction's impulse): no stages
                        # extrapolated across it, and the step size predicted afresh
                        solver.sol = None
                        solver.h_abs_old = None
                        solver.error_norm_old = None
                state, t = new, t_new
    return out
