"""The servo kernel's on-the-fly metrics (the oracle of `hydroarm.model.servo_observers`;
`hydroarm.reference`): `row_metrics` advances one servo with the step kernel of
`hydroarm.reference.servo_kernel` (the one its ``integrate`` uses, so the states are that run's bit
for bit) and keeps the summaries of `hydroarm.metrics.servo.METRICS`, observed at every
step; `run_many_metrics` does so for every row of a parameter table, in parallel.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..core.servo import (
    FEEDBACK_MECHANICAL,
    N_STATES,
    P_FEEDBACK,
    P_SENSE_ACT,
    P_SENSOR_GAIN,
    S_E_ACT,
    S_E_COMP,
    S_E_LEAK,
    S_E_RELIEF,
    S_E_SUPPLY,
    S_E_THROTTLE,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_XV,
)
from ..metrics.servo import N_METRICS
from .servo_kernel import actuator_motion, advance_steps, start_state

(
    M_FINAL_Q,
    M_FINAL_V,
    M_FINAL_PA,
    M_FINAL_PB,
    M_FINAL_PS,
    M_FINAL_XV,
    M_E_SUPPLY,
    M_E_RELIEF,
    M_E_THROTTLE,
    M_E_LEAK,
    M_E_COMP,
    M_E_ACT,
    M_PEAK_P,
    M_MIN_P,
    M_PEAK_PS,
    M_PEAK_V,
    M_SETTLING,
    M_OVERSHOOT,
    M_FAILED,
    M_FAILURE_T,
) = range(N_METRICS)

_FINAL = (
    (M_FINAL_Q, S_Q),
    (M_FINAL_V, S_V),
    (M_FINAL_PA, S_PA),
    (M_FINAL_PB, S_PB),
    (M_FINAL_PS, S_PS),
    (M_FINAL_XV, S_XV),
)


_FINAL = (
    (M_FINAL_Q, S_Q),
    (M_FINAL_V, S_V),
    (M_FINAL_PA, S_PA),
    (M_FINAL_PB, S_PB),
    (M_FINAL_PS, S_PS),
    (M_FINAL_XV, S_XV),
)


@njit(cache=True, nogil=True, error_model="numpy")
def measured(s, P):
    """The feedback's measurement in the reference's units: the sensor's output (electronic)
    or the actuator position (mechanical)."""
    x, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
    if P[P_FEEDBACK] == FEEDBACK_MECHANICAL:
        return x
    meas = x if P[P_SENSE_ACT] != 0.0 else s[S_Q]
    return P[P_SENSOR_GAIN] * meas


@njit(cache=True, nogil=True, error_model="numpy")
def _observe(s, P, tk, t_step, target, size, band, M, inside_since):
    """Peaks of state s at time tk into M; returns the new start of the in-band stretch."""
    pa = s[S_PA]
    pb = s[S_PB]
    M[M_PEAK_P] = max(M[M_PEAK_P], max(pa, pb))
    M[M_MIN_P] = min(M[M_MIN_P], min(pa, pb))
    M[M_PEAK_PS] = max(M[M_PEAK_PS], s[S_PS])
    M[M_PEAK_V] = max(M[M_PEAK_V], abs(s[S_V]))
    if tk >= t_step and size != 0.0:
        e = measured(s, P) - target
        over = (e if size > 0.0 else -e) / abs(size)
        if over > M[M_OVERSHOOT]:
            M[M_OVERSHOOT] = over
        if abs(e) > band * abs(size):
            return math.nan
        if math.isnan(inside_since):
            return tk
    return inside_since


@njit(cache=True, nogil=True, error_model="numpy")
def row_metrics(method, s0, t0, h, nsteps, tab_t, tab_y, sine, P, t_step, step_from, band, M):
    """Run one servo as `integrate` does (same steps, same
    projections) and write its `METRICS` into M (module doc). ``t_step``/``step_from``:
    the reference's last step (`step_of`; NaN: not a step reference)."""
    out = np.empty(N_STATES)
    k1 = np.empty(N_STATES)
    k2 = np.empty(N_STATES)
    k3 = np.empty(N_STATES)
    k4 = np.empty(N_STATES)
    tmp = np.empty(N_STATES)
    s = start_state(method, t0, s0, tab_t, tab_y, sine, P)
    for i in range(M.shape[0]):
        M[i] = np.nan
    M[M_PEAK_P] = -np.inf
    M[M_MIN_P] = np.inf
    M[M_PEAK_PS] = -np.inf
    M[M_PEAK_V] = 0.0
    M[M_FAILED] = 0.0
    target = tab_y[tab_y.shape[0] - 1]
    size = 0.0
    if not math.isnan(t_step):
        start = measured(s, P) if math.isnan(step_from) else step_from
        size = target - start
        M[M_OVERSHOOT] = 0.0
    e_supply = s[S_E_SUPPLY]
    e_relief = s[S_E_RELIEF]
    e_throttle = s[S_E_THROTTLE]
    e_leak = s[S_E_LEAK]
    e_comp = s[S_E_COMP]
    e_act = s[S_E_ACT]
    inside = _observe(s, P, t0, t_step, target, size, band, M, math.nan)
    for k in range(1, nsteps + 1):  # the one loop, a step at a time (observed after each)
        _, bad = advance_steps(
            method, t0, k - 1, h, 1, s, tab_t, tab_y, sine, P, out, k1, k2, k3, k4, tmp
        )
        if bad:
            for i in range(M.shape[0]):
                M[i] = np.nan
            M[M_FAILED] = 1.0
            M[M_FAILURE_T] = t0 + k * h
            return
        inside = _observe(s, P, t0 + k * h, t_step, target, size, band, M, inside)
    for m, i in _FINAL:
        M[m] = s[i]
    M[M_E_SUPPLY] = s[S_E_SUPPLY] - e_supply
    M[M_E_RELIEF] = s[S_E_RELIEF] - e_relief
    M[M_E_THROTTLE] = s[S_E_THROTTLE] - e_throttle
    M[M_E_LEAK] = s[S_E_LEAK] - e_leak
    M[M_E_COMP] = s[S_E_COMP] - e_comp
    M[M_E_ACT] = s[S_E_ACT] - e_act
    if size != 0.0:
        M[M_SETTLING] = inside - t_step
    else:
        M[M_OVERSHOOT] = np.nan


@njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def run_many_metrics(method, S0, t0, h, nsteps, tab_t, tab_y, sine, table, t_step, step_from, band):
    """`row_metrics` for every row of a parameter table (initial states S0 row by
    row), in parallel: (rows × `N_METRICS`). A row's metrics are the single run's,
    bit for bit."""
    n = table.shape[0]
    M = np.empty((n, N_METRICS))
    for i in prange(n):
        row_metrics(
            method,
            S0[i],
            t0,
            h,
            nsteps,
            tab_t,
            tab_y,
            sine,
            table[i],
            t_step,
            step_from,
            band,
            M[i],
        )
    return M
