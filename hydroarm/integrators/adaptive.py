"""Adaptive, stiff-safe reference integrator (scipy's Radau IIA, order 5).

Same right-hand side as the fixed-step methods (`hydroarm.core.equations.derivatives`).
Used as the reference against which the fixed-step results are checked.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..core.circuit.laws import POSITION_SHARE_RUNGE_KUTTA
from ..core.circuit.system import make_work, system_project, system_rhs, with_derived
from ..core.equations import derivatives
from ..core.lever import evaluate


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


def integrate_circuit_adaptive(s0, t_eval, P, net, rtol=1e-8, atol=None):
    """A circuit (`hydroarm.core.circuit.system.system_rhs`) with Radau, sampled at
    ``t_eval`` (t_eval[0]: the start). The non-smooth parts (stops, friction, latches, the
    cavitation floor) are applied by the system's projection at each sample: an operator
    split at the output interval, exact while no projection acts, so keep the samples close
    where one does. Returns the states (len(t_eval) × states)."""
    from scipy.integrate import solve_ivp

    P = with_derived(P, net)
    work = make_work(net)
    d = np.empty(len(s0))

    def rhs(t, s):
        system_rhs(t, s, P, net, work, d)
        return d.copy()

    if atol is None:
        atol = np.maximum(np.abs(np.asarray(s0, dtype=float)), 1.0) * 1e-9
    state = np.array(s0, dtype=float)
    system_project(float(t_eval[0]), 0.0, state.copy(), state, P, net, work, 1.0)
    out = np.empty((t_eval.size, state.size))
    out[0] = state
    for k in range(1, t_eval.size):
        a, b = float(t_eval[k - 1]), float(t_eval[k])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            sol = solve_ivp(rhs, (a, b), state, method="Radau", rtol=rtol, atol=atol)
        if sol.status < 0:
            raise RuntimeError(f"adaptive integration failed: {sol.message}")
        new = sol.y[:, -1].copy()
        system_project(b, b - a, state, new, P, net, work, POSITION_SHARE_RUNGE_KUTTA)
        state = new
        out[k] = state
    return out
