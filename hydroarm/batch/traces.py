"""Many runs of the paper's joint side by side, sampled at given times (the fit's engine).

`run_traces` runs N scenarios in parallel (numba ``prange``), each with the single
run's step kernel `step_once` at the times and with the
bounds check of `integrate` (one physics: the same
arithmetic, so that a run here equals [`hydroarm.simulate`][hydroarm.simulate] of the same scenario
bit for bit), and samples each run's angle, jack position and load pressure at that run's query
times by linear interpolation between the two steps around each (``np.interp``'s arithmetic
on a single run's result), keeping no trajectory. Each run stops at its last query time.

Every run has its own row of the batch table (`pack`), start
state, lever table (``lever_t``/``lever_y`` sliced by ``lever_at``), sine and query times
(``query_t`` sliced by ``query_at``). `scenario_traces` builds these arrays from
[`Scenario`][hydroarm.Scenario] objects.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..core.equations import crank_reach, jack_position, pressure_bound
from ..core.params import joint_at, load_at
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import in_bounds, step_once
from ..model.scenario import Scenario, simulate

# columns of run_traces' output
THETA, X, P = 0, 1, 2
N_OUT = 3


@njit(cache=True, parallel=True, error_model="numpy")
def run_traces(
    method, table, th0, p0, t0, h, nsteps, lever_at, lever_t, lever_y, sine, query_at, query_t
):
    """θ₂ [rad], x [m] and p [Pa] of N runs at their query times, and each run's bad step.

    Run i: row i of ``table``, start (``th0[i]``, ω = 0, ``p0[i]``) at ``t0[i]`` [s], ``nsteps[i]``
    steps of ``h`` [s], lever table ``lever_t[lever_at[i]:lever_at[i+1]]`` [s] /
    ``lever_y[...]`` [m] with ``sine[i]``, queries ``query_t[query_at[i]:query_at[i+1]]`` [s]
    (increasing). The steps are `integrate`'s: its step
    kernel ``step_once`` at its times t0 + (k − 1)·h, its bounds check, only the two states
    around each query kept. A query before ``t0[i]`` gets the start state, one after the
    run's end its last state. Returns (out (len(query_t), 3): θ₂, x, p; bad (N,): −1 or the
    first step that left the physical bounds, as ``integrate``).
    """
    n = table.shape[0]
    out = np.empty((query_t.size, N_OUT))
    bad = np.full(n, -1, dtype=np.int64)
    for i in prange(n):
        J = joint_at(table, i)
        L = load_at(table, i)
        tab_t = lever_t[lever_at[i] : lever_at[i + 1]].copy()
        tab_y = lever_y[lever_at[i] : lever_at[i + 1]].copy()
        sn = sine[i].copy()
        theta, omega, p = th0[i], 0.0, p0[i]
        p_max = pressure_bound(p, J, L)
        th_max = crank_reach(J)
        t_a, th_a, p_a = t0[i], theta, p  # the state before the step
        x_a = jack_position(th_a, J)
        q, q_end = query_at[i], query_at[i + 1]
        while q < q_end and query_t[q] <= t_a:  # at or before the start
            out[q, THETA], out[q, X], out[q, P] = th_a, x_a, p_a
            q += 1
        for k in range(1, nsteps[i] + 1):
            if q == q_end:
                break
            t = t0[i] + (k - 1) * h
            theta, omega, p = step_once(method, t, h, theta, omega, p, tab_t, tab_y, sn, J, L)
            if not in_bounds(theta, omega, p, th_max, p_max):
                bad[i] = k
                break
            t_b = t0[i] + k * h
            x_b = jack_position(theta, J)
            while q < q_end and query_t[q] < t_b:
                # np.interp's arithmetic between the states at t_a ≤ t_q < t_b
                dt, dq = t_b - t_a, query_t[q] - t_a
                out[q, THETA] = (theta - th_a) / dt * dq + th_a
                out[q, X] = (x_b - x_a) / dt * dq + x_a
                out[q, P] = (p - p_a) / dt * dq + p_a
                q += 1
            t_a, th_a, x_a, p_a = t_b, theta, x_b, p
        while q < q_end:  # after the run's end: its last state
            out[q, THETA], out[q, X], out[q, P] = th_a, x_a, p_a
            q += 1
    return out, bad


def scenario_traces(
    scenarios: list[Scenario], queries: list[np.ndarray], *, strict: bool = True
) -> np.ndarray:
    """θ₂ [rad], x [m], p [Pa] (columns `THETA`, `X`, `P`) of each scenario
    at its query times [s] (each increasing), all run together by `run_traces`; the rows
    of the result follow the scenarios and their queries in order.

    Each scenario runs from its start to one step past its last query (at most its duration).
    The scenarios must share one fixed-step method and step. A run that leaves the physical
    bounds raises the error [`hydroarm.simulate`][hydroarm.simulate] gives for that scenario
    (``strict``), or (not ``strict``) gets NaN in all its rows.
    """
    if not scenarios:
        return np.empty((0, N_OUT))
    first = scenarios[0]
    m = registry.method(first.method)
    if not m.fixed_step or any(s.method != first.method or s.step != first.step for s in scenarios):
        raise HydroarmError("solver.method", "runs together need one fixed-step method and step")
    h = first.step
    n = len(scenarios)
    table = np.empty((n, len(first.row)))
    th0, p0, t0 = np.empty(n), np.empty(n), np.empty(n)
    nsteps = np.empty(n, dtype=np.int64)
    sine = np.empty((n, 3))
    lever_at = np.zeros(n + 1, dtype=np.int64)
    query_at = np.zeros(n + 1, dtype=np.int64)
    for i, (s, q) in enumerate(zip(scenarios, queries, strict=True)):
        table[i] = s.row
        th0[i], p0[i], t0[i] = s.initial_angle, s.start_pressure(), s.t0
        need = math.ceil((float(q[-1]) - s.t0) / h) + 1 if len(q) else 0
        nsteps[i] = max(1, min(s.nsteps, need))
        sine[i] = s.lever.sine
        lever_at[i + 1] = lever_at[i] + len(s.lever.times)
        query_at[i + 1] = query_at[i] + len(q)
    lever_t = np.concatenate([s.lever.times for s in scenarios])
    lever_y = np.concatenate([s.lever.positions for s in scenarios])
    query_t = np.concatenate([np.asarray(q, float) for q in queries])
    out, bad = run_traces(
        m.code, table, th0, p0, t0, h, nsteps, lever_at, lever_t, lever_y, sine, query_at, query_t
    )
    if not strict:
        for k in np.flatnonzero(bad >= 0):
            out[query_at[k] : query_at[k + 1]] = np.nan
        return out
    for k in np.flatnonzero(bad >= 0):
        simulate(scenarios[int(k)], check_stability=False)  # raises the single run's error
        raise HydroarmError("solver", f"run {k} left the physical bounds")  # (not reached)
    return out
