"""Batch engine: many step-input scenarios advanced at once, metrics computed on the fly.

One physics: each scenario is advanced by the single-scenario step kernel
(:func:`hydroarm.integrators.fixed.advance`, which ``step_once`` calls) in a numba
``prange`` loop over scenarios (``parallel=True``, ``nogil=True``, ``cache=True``), so the
batch and single paths give the same states bit for bit. Memory does not grow with the
number of steps: per scenario only the running metrics are kept (full traces: run the
scenario with :func:`hydroarm.simulate`).

Metrics per scenario (``METRICS``), following :func:`hydroarm.analysis.metrics.step_metrics`
with ``x_end`` = the target (or, for a motion that stalls, the furthest point reached —
such scenarios are run a second time with that window):

- ``saturation_velocity`` [m/s] over the middle 80 % of the travel (linear interpolation of
  the crossing times, as in ``crossing_time``);
- ``time_constant_start`` [s]: from the lever step until the velocity (central differences,
  as ``numpy.gradient``) first reaches 63 % of the full-opening velocity K_q·e_o/A;
- ``time_constant_end`` [s]: time to move from e_o to 0.37·e_o short of the target;
- ``stalled`` (reach short of the target by more than 5 % of the command), ``reach`` [m],
  ``peak_pressure`` [Pa], ``final_x`` [m], ``failed`` (a non-finite state).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..core.equations import jack_position
from ..core.joint import P_CRANK, P_RATIO
from ..errors import HydroarmError
from ..integrators.fixed import advance

METRICS = ("saturation_velocity", "time_constant_start", "time_constant_end", "stalled",
           "reach", "peak_pressure", "final_x", "failed")
_SAT, _TC0, _TC1, _STALL, _REACH, _PEAK, _XF, _FAIL = range(8)


@njit(cache=True, nogil=True, error_model="numpy")
def _cross(level, sign, x_prev, x, t_prev, t):
    """Interpolated time at which sign·(x − level) reaches 0 between two samples."""
    g0 = sign * (x_prev - level)
    g1 = sign * (x - level)
    if g0 >= 0.0:
        return t
    return t_prev + (-g0 / (g1 - g0)) * (t - t_prev)


@njit(cache=True, nogil=True, error_model="numpy")
def _confirm(level, sign, th, x, th_p, x_p, have_xp, t_p, t, P):
    """Confirm on x that the angle th has passed a level: (x at th, the interpolated crossing
    time, or NaN when x has not reached the level yet). x may be NaN (not yet computed);
    x_p is the previous x when ``have_xp``, else it is computed from th_p."""
    if math.isnan(x):
        x = jack_position(th, P)
    if sign * (x - level) < 0.0:
        return x, math.nan
    xp = x_p if have_xp else jack_position(th_p, P)
    return x, _cross(level, sign, xp, x, t_p, t)


@njit(cache=True, nogil=True, error_model="numpy")
def _next_level(stage, tc, t_first, t_second, second, sign, P):
    """A pair of levels (a, b or c1, c2) after a confirmed crossing at tc: its new stage
    (1: first passed, 2: both), crossing times, and pending level with its angle."""
    if stage == 0:
        return 1, tc, t_second, second, _angle_of(second, P) - sign * 1e-9
    return 2, t_first, tc, second, sign * math.inf


@njit(cache=True, nogil=True, error_model="numpy")
def _angle_of(x, P):
    """θ₂ of a jack position (eq. 4 inverted), clipped to the crank's reach."""
    r = P[P_CRANK]
    return P[P_RATIO] * math.asin(min(max(x / r, -1.0), 1.0))


@njit(cache=True, nogil=True, error_model="numpy")
def run_one(method, P, theta0, p0, y0, y1, t_step, h, nsteps, x_end, v_full, e_open,
            middle, threshold, stall_tolerance, out):
    """Run one step-input scenario; write its metrics into ``out`` (length len(METRICS)).

    Crossings are detected on the angle (x = r·sin(θ/n) is monotone in θ) and confirmed
    and interpolated on x, so the jack position is only evaluated where a metric needs it.
    The running state is kept in scalars only: with no store to memory inside the step
    loop, the compiler can keep the parameters in registers.
    """
    th, om, p = theta0, 0.0, p0
    x0 = jack_position(theta0, P)
    sign = 1.0 if y1 >= x0 else -1.0
    travel = x_end - x0
    # levels: a, b bound the middle of the travel; c1, c2 the end (e_o and 0.37·e_o short)
    la = x0 + 0.5 * (1.0 - middle) * travel
    lb = x0 + 0.5 * (1.0 + middle) * travel
    lc1 = y1 - sign * e_open
    lc2 = y1 - sign * (1.0 - threshold) * e_open
    ta = tb = tc1 = tc2 = math.nan
    # the pending level of each pair and its angle (detected early, confirmed on x)
    lev_m, lev_c = la, lc1
    g_m = _angle_of(la, P) - sign * 1e-9
    g_c = _angle_of(lc1, P) - sign * 1e-9
    stage_m = 0  # 0: waiting for a, 1: for b, 2: done
    stage_c = 0  # 0: waiting for c1, 1: for c2, 2: done (only after a)
    t63 = math.nan
    peak = abs(p0)
    th_ext = theta0
    th_p = theta0
    x_pp = x_p = x0
    t_p = 0.0
    v_prev = 0.0
    failed = 0.0
    lvl = threshold * v_full
    for k in range(1, nsteps + 1):
        t = (k - 1) * h
        # the step input, as hydroarm.core.inputs.evaluate gives it for the table
        # (t_step, t_step) -> (y0, y1)
        ya = y1 if t >= t_step else y0
        if method == 0:
            th, om, p = advance(method, h, th, om, p, ya, ya, ya, P)
        else:
            ym = y1 if t + 0.5 * h >= t_step else y0
            yb = y1 if t + h >= t_step else y0
            th, om, p = advance(method, h, th, om, p, ya, ym, yb, P)
        if not (np.isfinite(th) and np.isfinite(om) and np.isfinite(p)):
            failed = 1.0
            break
        tk = k * h
        ap = abs(p)
        if ap > peak:
            peak = ap
        if sign * th > sign * th_ext:
            th_ext = th
        need_v = math.isnan(t63)
        x = math.nan
        if need_v:
            x = jack_position(th, P)
        if stage_m < 2 and sign * (th - g_m) >= 0.0:
            x, tc = _confirm(lev_m, sign, th, x, th_p, x_p, need_v, t_p, tk, P)
            if not math.isnan(tc):
                stage_m, ta, tb, lev_m, g_m = _next_level(stage_m, tc, ta, tb, lb, sign, P)
        if stage_m >= 1 and stage_c < 2 and sign * (th - g_c) >= 0.0:
            x, tc = _confirm(lev_c, sign, th, x, th_p, x_p, need_v, t_p, tk, P)
            if not math.isnan(tc):
                stage_c, tc1, tc2, lev_c, g_c = _next_level(stage_c, tc, tc1, tc2, lc2, sign, P)
        if need_v:
            # velocity at the previous sample by central differences (numpy.gradient)
            if k >= 2:
                v = sign * (x - x_pp) / (2.0 * h)
                if t_p >= t_step:
                    if v >= lvl:
                        if k == 2 or v_prev >= lvl or t_p - h < t_step:
                            t63 = t_p
                        else:
                            t63 = t_p - h + (lvl - v_prev) / (v - v_prev) * h
                v_prev = v
            x_pp = x_p
            x_p = x
        th_p = th
        t_p = tk
    reach = sign * (jack_position(th_ext, P) - x0)
    commanded = abs(y1 - x0)
    stalled = sign * (y1 - (x0 + sign * reach)) > stall_tolerance * commanded
    out[_SAT] = abs(lb - la) / (tb - ta) if tb > ta else math.nan
    out[_TC0] = t63 - t_step
    out[_TC1] = math.nan if stalled else tc2 - tc1
    out[_STALL] = 1.0 if stalled else 0.0
    out[_REACH] = reach
    out[_PEAK] = peak
    out[_XF] = jack_position(th, P)
    out[_FAIL] = failed


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def run_many(method, PARAMS, TH0, P0, Y0, Y1, XEND, VFULL, EOPEN, t_step, h, nsteps, middle,
             threshold, stall_tolerance, OUT):
    """:func:`run_one` for every row of PARAMS, in parallel over scenarios."""
    for i in prange(PARAMS.shape[0]):
        run_one(method, PARAMS[i], TH0[i], P0[i], Y0[i], Y1[i], t_step, h, nsteps, XEND[i],
                VFULL[i], EOPEN[i], middle, threshold, stall_tolerance, OUT[i])


def run_batch(method: int, params: np.ndarray, theta0, p0, y0, y1, *, t_step: float, h: float,
              nsteps: int, middle: float = 0.8, threshold: float = 0.63,
              stall_tolerance: float = 0.05) -> np.ndarray:
    """Metrics (n, len(METRICS)) of n step-input scenarios; stalled ones re-run up to stall."""
    from ..core.joint import P_AREA, P_E_SAT

    params = np.ascontiguousarray(params, dtype=float)
    n = params.shape[0]
    th0 = np.asarray(theta0, float)
    y0 = np.asarray(y0, float)
    y1 = np.asarray(y1, float)
    p0 = np.asarray(p0, float)
    from ..core.equations import flow_gain

    vfull = np.array([flow_gain(P) * P[P_E_SAT] / P[P_AREA] for P in params])
    eopen = params[:, P_E_SAT].copy()
    out = np.empty((n, len(METRICS)))
    xend = y1.copy()
    run_many(method, params, th0, p0, y0, y1, xend, vfull, eopen, t_step, h, nsteps, middle,
             threshold, stall_tolerance, out)
    st = np.nonzero(out[:, _STALL] > 0.5)[0]
    if st.size:  # velocity up to the stall: the window of the travel actually made
        x0 = np.array([jack_position(th0[i], params[i]) for i in st])
        sign = np.where(y1[st] >= x0, 1.0, -1.0)
        xend2 = x0 + sign * out[st, _REACH]
        out2 = np.empty((st.size, len(METRICS)))
        run_many(method, params[st], th0[st], p0[st], y0[st], y1[st], xend2, vfull[st],
                 eopen[st], t_step, h, nsteps, middle, threshold, stall_tolerance, out2)
        out[st] = out2
    return out


def run_scenarios(scenarios) -> list[dict]:
    """Metrics of a list of step-input :class:`~hydroarm.simulation.Scenario` s, run as one
    batch (they must share method, step, duration and step time)."""
    scs = list(scenarios)
    if not scs:
        return []
    s0 = scs[0]
    for sc in scs:
        if sc.lever.description != "step":
            raise HydroarmError("input", "the batch engine runs step inputs")
        if (sc.method, sc.step, sc.nsteps, float(sc.lever.times[0])) != (
                s0.method, s0.step, s0.nsteps, float(s0.lever.times[0])):
            raise HydroarmError("solver", "a batch needs one method, step, duration and "
                                "step time")
        if sc.method == "adaptive":
            raise HydroarmError("solver.method", "the batch engine runs euler or rk4")
    params = np.array([sc.params for sc in scs])
    out = run_batch(0 if s0.method == "euler" else 1, params,
                    [sc.initial_angle for sc in scs], [sc.start_pressure() for sc in scs],
                    [float(sc.lever.positions[0]) for sc in scs], [sc.target for sc in scs],
                    t_step=float(s0.lever.times[0]), h=s0.step, nsteps=s0.nsteps)
    return [dict(zip(METRICS, row, strict=True)) for row in out]
