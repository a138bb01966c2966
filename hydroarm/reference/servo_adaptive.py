"""The component servo's right-hand side (`hydroarm.reference.servo_kernel.servo_rhs`) with scipy's
Radau: the oracle of the adaptive servo run (its circuit's Radau,
`hydroarm.integrators.adaptive.integrate_circuit_adaptive`; `hydroarm.reference`)."""

from __future__ import annotations

import warnings

import numpy as np

from ..core.lever import evaluate
from ..core.servo import STATES
from .servo_kernel import servo_rhs


def integrate_servo_adaptive(s0, t0, t_end, t_eval, tab_t, tab_y, sine, P, rtol=1e-9):
    """The component servo (`hydroarm.reference.servo_kernel.servo_rhs`) with Radau from t0 to
    t_end, sampled at ``t_eval``; breakpoints of the reference integrated as separate
    segments. The smooth right-hand side only: the caller refuses runs that need the step
    kernel's projections (dry friction, a stop, the cavitation floor). Returns the states
    (len(t_eval) × N_STATES)."""
    from scipy.integrate import solve_ivp

    # absolute tolerances per state: positions, velocities, pressures, spool, energies
    scale = {"m": 1e-10, "m/s": 1e-8, "Pa": 1e-3, "J": 1e-6}
    atol = np.array([scale.get(unit, 1e-10) for _, unit, _ in STATES])
    d = np.empty(len(STATES))

    def rhs(t, s):
        servo_rhs(evaluate(t, tab_t, tab_y, sine), s, P, d)
        return d.copy()

    breaks = sorted({float(b) for b in tab_t if t0 < b < t_end})
    edges = [t0, *breaks, t_end]
    state = np.array(s0, dtype=float)
    out = np.empty((t_eval.size, state.size))
    out[0] = state
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        mask = (t_eval > a) & (t_eval <= b)
        seg = t_eval[mask]
        ask = seg if seg.size and seg[-1] == b else np.append(seg, b)
        with warnings.catch_warnings():
            # scipy's finite-difference Jacobian grows its increments past overflow on the
            # energy states (they feed nothing back); harmless, and not the user's concern
            warnings.simplefilter("ignore", RuntimeWarning)
            sol = solve_ivp(rhs, (a, b), state, method="Radau", t_eval=ask, rtol=rtol, atol=atol)
        if sol.status < 0:
            raise RuntimeError(f"adaptive integration failed: {sol.message}")
        out[mask] = sol.y[:, : seg.size].T
        state = sol.y[:, -1]
    return out
