"""On-the-fly step metrics: step-input scenarios advanced in lanes, the paper's metrics
observed at every step (the batch engine, and the metrics of a single run).

One physics: each scenario is advanced by the single-scenario step kernel
(`hydroarm.integrators.fixed.advance`, which ``step_once`` calls), so the batch and
single paths give the same states bit for bit. Scenarios go in blocks of ``LANES`` that one
thread advances in lock step (`run_block`); the blocks are spread over the cores by a
numba ``prange`` (``parallel=True``, ``nogil=True``, ``cache=True``). For the paper's
physics the loop over the lanes of a block compiles to AVX2 vector instructions, four
scenarios per instruction (the inlined, branch-free sin/cos of `hydroarm.core.trig`
make that possible); vector arithmetic is the same IEEE arithmetic per lane, so the results
do not change. Memory does not grow with the number of steps: per scenario only the running
metrics are kept. Because they are observed at every step, the metrics do not depend on how
many values a run prints
([`hydroarm.model.result.SimulationResult.metrics`][hydroarm.SimulationResult.metrics] runs its
scenario through here).

Metrics per scenario (``METRICS``), the definitions of
[`hydroarm.metrics.step.step_metrics`][hydroarm.step_metrics] with the end of motion at the target
(or, for a motion that stalls, the furthest point reached — such scenarios are run a second time
with that window):

- ``saturation_velocity`` [m/s] over the middle 80 % of the travel (linear interpolation of
  the crossing times, as in ``crossing_time``);
- ``time_constant_start`` [s]: from the lever step until the jack has moved 63 % of the full
  valve opening, 0.63·e_o, from where it started (the paper's "time to move 63 % of full
  valve opening" at the start of travel);
- ``time_constant_start_velocity`` [s]: from the lever step until the velocity (central
  differences, as ``numpy.gradient``) first reaches 63 % of the full-opening velocity
  K_q·e_o/A (an alternative reading, docs/model.md);
- ``time_constant_end`` [s]: time to move from e_o to 0.37·e_o short of the target;
- ``stalled`` (reach short of the target by more than 5 % of the command), ``reach`` [m],
  ``peak_pressure`` [Pa], ``final_x`` [m], ``failed``: 0, or why the run left the physical
  bounds (`FAILURES`: 1 ``unstable``, a non-finite state;
  2 ``out_of_bounds``, a pressure beyond `pressure_bound`;
  3 ``past_dead_centre``, |θ₂| ≥ n·90°). A failed row's other metrics are NaN (``stalled``
  0): nothing measured on such a run means anything.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..core.equations import crank_reach, flow_gain, jack_position, pressure_bound
from ..core.kinematics import crank_angle
from ..core.params import (
    J_AREA,
    J_BETA,
    J_CRANK,
    J_E_SAT,
    J_F_COULOMB,
    J_F_STATIC,
    J_FLOW_COEFF,
    J_GB_EXP,
    J_GB_LOSS,
    J_GB_T0,
    J_HORIZ,
    J_LEAK,
    J_NULL_LEAK,
    J_P_ATM,
    J_P_TRANS,
    J_RATED,
    J_RATIO,
    J_STOP,
    J_SUPPLY,
    J_TORQUE_ARM,
    J_VALVE,
    J_VISCOUS,
    J_VOLUME,
    L_ARM,
    L_INERTIA,
    L_TORQUE,
    L_WEIGHT,
    N_ROW,
    OPTION_COLUMNS,
    LoadParams,
    joint_at,
    joint_from_columns,
    load_at,
)
from ..errors import HydroarmError
from ..integrators import registry
from ..integrators.fixed import EULER, FAILURES, RK4, advance, failure_code, in_bounds
from .step import DEFAULT_METRIC_OPTIONS, MetricOptions

METRICS = (
    "saturation_velocity",
    "time_constant_start",
    "time_constant_start_velocity",
    "time_constant_end",
    "stalled",
    "reach",
    "peak_pressure",
    "final_x",
    "failed",
)
# the kernels also write the averaging window (t_a, t_b) of the saturation velocity into two
# more columns: a single run reports it (``t_middle``), sweeps do not
OUTPUTS = (*METRICS, "t_middle_start", "t_middle_end")
_SAT, _TC0, _TCV, _TC1, _STALL, _REACH, _PEAK, _XF, _FAIL, _TA, _TB = range(11)
N_METRICS = len(METRICS)
N_OUTPUTS = len(OUTPUTS)


@njit(cache=True, nogil=True, error_model="numpy")
def _cross(level, sign, x_prev, x, t_prev, t):
    """Interpolated time at which sign·(x − level) reaches 0 between two samples."""
    g0 = sign * (x_prev - level)
    g1 = sign * (x - level)
    if g0 >= 0.0:
        return t
    return t_prev + (-g0 / (g1 - g0)) * (t - t_prev)


@njit(cache=True, nogil=True, error_model="numpy")
def _confirm(level, sign, th, x, th_p, x_p, have_xp, t_p, t, J):
    """Confirm on x that the angle th has passed a level: (x at th, the interpolated crossing
    time, or NaN when x has not reached the level yet). x may be NaN (not yet computed);
    x_p is the previous x when ``have_xp``, else it is computed from th_p."""
    if math.isnan(x):
        x = jack_position(th, J)
    if sign * (x - level) < 0.0:
        return x, math.nan
    xp = x_p if have_xp else jack_position(th_p, J)
    return x, _cross(level, sign, xp, x, t_p, t)


@njit(cache=True, nogil=True, error_model="numpy")
def _next_level(stage, tc, t_first, t_second, second, sign, J):
    """A pair of levels (a, b or c1, c2) after a confirmed crossing at tc: its new stage
    (1: first passed, 2: both), crossing times, and pending level with its angle."""
    if stage == 0:
        return 1, tc, t_second, second, _angle_of(second, J) - sign * 1e-9
    return 2, t_first, tc, second, sign * math.inf


@njit(cache=True, nogil=True, error_model="numpy")
def _angle_of(x, J):
    """θ₂ of a jack position (eq. 4 inverted), clipped to the crank's reach."""
    return crank_angle(x, J.crank_radius, J.gear_ratio, 1.0)


# One thread advances LANES scenarios together. Their states and parameters (the columns of
# their batch-table rows, J_* and L_*) lie in one flat array, field f of lane j at
# S[f·LANES + j]: with a constant lane count and constant field
# offsets the compiler can prove that the lanes do not overlap and turns the loop over lanes
# into vector instructions (4 scenarios per AVX2 instruction). The step itself is
# fixed.advance, the single-scenario kernel, called once per lane.
LANES = 16
_F_Y0 = N_ROW  # lever before / after the step [m]
_F_Y1 = N_ROW + 1
_F_TH = N_ROW + 2  # state θ₂, ω, p
_F_OM = N_ROW + 3
_F_P = N_ROW + 4
_F_X = N_ROW + 5  # jack position of the state
_F_THP = N_ROW + 6  # θ₂ one step earlier
_F_PEAK = N_ROW + 7  # largest |p| so far
_F_THX = N_ROW + 8  # furthest angle so far (in the direction of motion)
_F_ALIVE = N_ROW + 9  # 1 until the state stops being finite
_F_GM = N_ROW + 10  # angle of the pending middle level (a or b)
_F_GC = N_ROW + 11  # angle of the pending end level (c1 or c2)
_F_SIGN = N_ROW + 12  # direction of motion, ±1
_F_T63 = N_ROW + 13  # time the velocity reached 63 % (NaN: not yet)
_F_EVENT = N_ROW + 14  # 1: this lane needs the metric bookkeeping after this step
# the velocity by central differences, until the 63 % level is reached
_F_LVL = N_ROW + 15  # the 63 % level [m/s]
_F_XP = N_ROW + 16  # x one and two steps earlier
_F_XPP = N_ROW + 17
_F_XPOLD = N_ROW + 18  # x one step earlier, as it was before this step (for crossings)
_F_V = N_ROW + 19  # velocity at the previous sample
_F_VOLD = N_ROW + 20  # the same one step earlier
_F_PB = N_ROW + 21  # pressure bound [Pa] (core.equations.pressure_bound)
_F_GS = N_ROW + 22  # angle of the start level x₀ ± 0.63·e_o (±inf once passed)
N_FIELDS = N_ROW + 23
# per-lane bookkeeping that only the (rarely run) scalar pass touches
(
    _M_STAGE_M,
    _M_STAGE_C,
    _M_LEV_M,
    _M_LEV_C,
    _M_TA,
    _M_TB,
    _M_TC1,
    _M_TC2,
    _M_THF,
    _M_X0,
    _M_LA,
    _M_LB,
    _M_LC2,
    _M_FAIL,
    _M_LS,
    _M_TS,
) = range(16)
N_BOOK = 16

# The table columns that switch physics options on (OPTION_COLUMNS: torque arm, valve model,
# dry and viscous friction, a direct load torque). A block whose scenarios all have them at
# 0 runs the paper's physics with these fields as constants: the option branches compile
# away and the loop over lanes is vectorised. Other blocks run the same code with the fields
# read per lane (not vectorised: the power laws and stick/slip logic of the options are
# calls and jumps).


@njit(inline="always", error_model="numpy")
def _lane_params(S, j, paper):
    """(JointParams, LoadParams) of lane j, built from its fields (no array view, no
    reference counting); with ``paper`` the option fields (OPTION_COLUMNS) are constants:
    paper torque arm and valve, no friction, no direct load torque."""
    B = LANES
    joint = joint_from_columns(
        S[J_AREA * B + j],
        S[J_FLOW_COEFF * B + j],
        S[J_E_SAT * B + j],
        S[J_LEAK * B + j],
        S[J_VOLUME * B + j],
        S[J_BETA * B + j],
        S[J_SUPPLY * B + j],
        S[J_CRANK * B + j],
        S[J_RATIO * B + j],
        S[J_HORIZ * B + j],
        (0.0 if paper else S[J_TORQUE_ARM * B + j]),
        (0.0 if paper else S[J_VALVE * B + j]),
        S[J_P_TRANS * B + j],
        S[J_P_ATM * B + j],
        (0.0 if paper else S[J_F_COULOMB * B + j]),
        (0.0 if paper else S[J_F_STATIC * B + j]),
        (0.0 if paper else S[J_VISCOUS * B + j]),
        (0.0 if paper else S[J_GB_T0 * B + j]),
        (0.0 if paper else S[J_GB_LOSS * B + j]),
        S[J_GB_EXP * B + j],
        S[J_STOP * B + j],
        S[J_RATED * B + j],
        (0.0 if paper else S[J_NULL_LEAK * B + j]),
    )
    load = LoadParams(
        S[L_WEIGHT * B + j],
        S[L_ARM * B + j],
        S[L_INERTIA * B + j],
        (0.0 if paper else S[L_TORQUE * B + j]),
    )
    return joint, load


@njit(inline="always", error_model="numpy")
def _advance_lanes(S, method, paper, n, k, h, t_step, on_a, on_m, on_b):
    """Step k of every lane (vectorised): state, jack position, peak pressure, furthest
    angle, the central-difference velocity, and the event flag of the lanes whose metrics
    need the scalar pass (`_observe`). ``on_*``: the lever has stepped at the start,
    middle and end of the step. ``n``: the lanes to advance, LANES for the vectorised paper
    physics (a constant trip count), the block's own scenarios otherwise (the option physics
    is not vectorised: a lane costs its full price, so unused ones are skipped). Returns the
    number of flagged lanes."""
    B = LANES
    nev = 0
    for j in range(n):
        J, L = _lane_params(S, j, paper)
        y0 = S[_F_Y0 * B + j]
        y1 = S[_F_Y1 * B + j]
        ya = y1 if on_a else y0
        th = S[_F_TH * B + j]
        if method == EULER:
            a, b, c = advance(EULER, h, th, S[_F_OM * B + j], S[_F_P * B + j], ya, ya, ya, J, L)
        else:
            a, b, c = advance(
                RK4,
                h,
                th,
                S[_F_OM * B + j],
                S[_F_P * B + j],
                ya,
                y1 if on_m else y0,
                y1 if on_b else y0,
                J,
                L,
            )
        x = jack_position(a, J)
        # finite and within the physical bounds (branch-free: folded into ``alive``)
        fin = in_bounds(a, b, c, crank_reach(J), S[_F_PB * B + j])
        alive = S[_F_ALIVE * B + j] > 0.5
        ok = alive & fin
        sg = S[_F_SIGN * B + j]
        pk = S[_F_PEAK * B + j]
        S[_F_PEAK * B + j] = abs(c) if ok & (abs(c) > pk) else pk
        tx = S[_F_THX * B + j]
        S[_F_THX * B + j] = a if ok & (sg * a > sg * tx) else tx
        S[_F_THP * B + j] = th
        S[_F_TH * B + j] = a
        S[_F_OM * B + j] = b
        S[_F_P * B + j] = c
        S[_F_X * B + j] = x
        # velocity at the previous sample by central differences (numpy.gradient), while
        # the 63 % time is not known; reaching the level is an event
        t63 = S[_F_T63 * B + j]
        need = t63 != t63
        xp = S[_F_XP * B + j]
        xpp = S[_F_XPP * B + j]
        vold = S[_F_V * B + j]
        v = sg * (x - xpp) / (2.0 * h)
        hit = need & (k >= 2) & ((k - 1) * h >= t_step) & (v >= S[_F_LVL * B + j])
        S[_F_XPOLD * B + j] = xp
        S[_F_VOLD * B + j] = vold
        S[_F_V * B + j] = v if need & (k >= 2) else vold
        S[_F_XPP * B + j] = xp if need else xpp
        S[_F_XP * B + j] = x if need else xp
        ev = alive & (
            (not fin)
            | (sg * (a - S[_F_GM * B + j]) >= 0.0)
            | (sg * (a - S[_F_GC * B + j]) >= 0.0)
            | (sg * (a - S[_F_GS * B + j]) >= 0.0)
            | hit
        )
        S[_F_EVENT * B + j] = 1.0 if ev else 0.0
        nev += 1 if ev else 0
    return nev


@njit(cache=True, nogil=True, error_model="numpy")
def _observe(S, M, j, k, h, t_step):
    """Metric bookkeeping of lane j after step k (level crossings, the 63 % time, failure):
    the logic of a scalar run, on the lane's state."""
    B = LANES
    J = _lane_params(S, j, False)[0]
    th = S[_F_TH * B + j]
    code = failure_code(th, S[_F_OM * B + j], S[_F_P * B + j], crank_reach(J), S[_F_PB * B + j])
    if code != 0:
        S[_F_ALIVE * B + j] = 0.0  # the run of this lane stops here
        M[_M_THF, j] = th
        M[_M_FAIL, j] = code
        return
    sign = S[_F_SIGN * B + j]
    tk = k * h
    t_p = (k - 1) * h
    th_p = S[_F_THP * B + j]
    x = S[_F_X * B + j]
    need_v = math.isnan(S[_F_T63 * B + j])
    x_p = S[_F_XPOLD * B + j]
    if sign * (th - S[_F_GS * B + j]) >= 0.0 and t_p >= t_step:
        x, tc = _confirm(M[_M_LS, j], sign, th, x, th_p, x_p, need_v, t_p, tk, J)
        if not math.isnan(tc):  # the jack has moved 0.63·e_o: the start time constant
            M[_M_TS, j] = tc
            S[_F_GS * B + j] = sign * math.inf
    stage_m = int(M[_M_STAGE_M, j])
    if stage_m < 2 and sign * (th - S[_F_GM * B + j]) >= 0.0:
        x, tc = _confirm(M[_M_LEV_M, j], sign, th, x, th_p, x_p, need_v, t_p, tk, J)
        if not math.isnan(tc):
            stage_m, M[_M_TA, j], M[_M_TB, j], M[_M_LEV_M, j], S[_F_GM * B + j] = _next_level(
                stage_m, tc, M[_M_TA, j], M[_M_TB, j], M[_M_LB, j], sign, J
            )
            M[_M_STAGE_M, j] = stage_m
    stage_c = int(M[_M_STAGE_C, j])
    if stage_m >= 1 and stage_c < 2 and sign * (th - S[_F_GC * B + j]) >= 0.0:
        x, tc = _confirm(M[_M_LEV_C, j], sign, th, x, th_p, x_p, need_v, t_p, tk, J)
        if not math.isnan(tc):
            stage_c, M[_M_TC1, j], M[_M_TC2, j], M[_M_LEV_C, j], S[_F_GC * B + j] = _next_level(
                stage_c, tc, M[_M_TC1, j], M[_M_TC2, j], M[_M_LC2, j], sign, J
            )
            M[_M_STAGE_C, j] = stage_c
    if need_v and k >= 2 and t_p >= t_step:
        v = S[_F_V * B + j]
        lvl = S[_F_LVL * B + j]
        if v >= lvl:  # the velocity has reached 63 %: interpolate its time
            v_prev = S[_F_VOLD * B + j]
            if k == 2 or v_prev >= lvl or t_p - h < t_step:
                S[_F_T63 * B + j] = t_p
            else:
                S[_F_T63 * B + j] = t_p - h + (lvl - v_prev) / (v - v_prev) * h


@njit(cache=True, nogil=True, error_model="numpy")
def run_block(
    method,
    PARAMS,
    TH0,
    P0,
    Y0,
    Y1,
    XEND,
    VFULL,
    EOPEN,
    i0,
    m,
    t_step,
    h,
    nsteps,
    middle,
    threshold,
    stall_tolerance,
    OUT,
):
    """Run the step-input scenarios i0 … i0+m−1 (m ≤ LANES) together; write their metrics
    into the rows of ``OUT`` (the len(OUTPUTS) columns of `OUTPUTS`).

    The lanes are advanced in lock step by `_advance_lanes`; the metric bookkeeping
    (`_observe`) runs only for lanes that it flags: near a level crossing, until the
    63 % velocity is found, or when a state stops being finite. Crossings are detected on
    the angle (x = r·sin(θ/n) is monotone in θ) and confirmed and interpolated on x.
    Unused lanes of a short block repeat scenario i0 and are ignored.
    """
    B = LANES
    S = np.empty(N_FIELDS * B)
    M = np.empty((N_BOOK, B))
    paper = True
    for j in range(B):
        i = i0 + (j if j < m else 0)
        row = PARAMS[i]
        for f in range(N_ROW):
            S[f * B + j] = row[f]
        for f in OPTION_COLUMNS:
            if row[f] != 0.0:
                paper = False
        J = joint_at(PARAMS, i)
        x0 = jack_position(TH0[i], J)
        sign = 1.0 if Y1[i] >= x0 else -1.0
        travel = XEND[i] - x0
        # levels: a, b bound the middle of the travel; c1, c2 the end (e_o and 0.37·e_o short)
        la = x0 + 0.5 * (1.0 - middle) * travel
        lc1 = Y1[i] - sign * EOPEN[i]
        ls = x0 + sign * threshold * EOPEN[i]
        S[_F_Y0 * B + j] = Y0[i]
        S[_F_Y1 * B + j] = Y1[i]
        S[_F_TH * B + j] = TH0[i]
        S[_F_OM * B + j] = 0.0
        S[_F_P * B + j] = P0[i]
        S[_F_X * B + j] = x0
        S[_F_THP * B + j] = TH0[i]
        S[_F_PEAK * B + j] = abs(P0[i])
        S[_F_THX * B + j] = TH0[i]
        S[_F_ALIVE * B + j] = 1.0
        S[_F_PB * B + j] = pressure_bound(P0[i], J, load_at(PARAMS, i))
        M[_M_FAIL, j] = 0.0
        # the pending level of each pair and its angle (detected early, confirmed on x)
        S[_F_GM * B + j] = _angle_of(la, J) - sign * 1e-9
        S[_F_GC * B + j] = _angle_of(lc1, J) - sign * 1e-9
        S[_F_GS * B + j] = _angle_of(ls, J) - sign * 1e-9
        M[_M_LS, j] = ls
        M[_M_TS, j] = math.nan
        S[_F_SIGN * B + j] = sign
        S[_F_T63 * B + j] = math.nan
        M[_M_STAGE_M, j] = 0.0  # 0: waiting for a, 1: for b, 2: done
        M[_M_STAGE_C, j] = 0.0  # 0: waiting for c1, 1: for c2, 2: done (only after a)
        M[_M_LEV_M, j] = la
        M[_M_LEV_C, j] = lc1
        M[_M_TA, j] = M[_M_TB, j] = M[_M_TC1, j] = M[_M_TC2, j] = math.nan
        S[_F_XP * B + j] = S[_F_XPP * B + j] = S[_F_XPOLD * B + j] = x0
        S[_F_V * B + j] = S[_F_VOLD * B + j] = 0.0
        S[_F_LVL * B + j] = threshold * VFULL[i]
        M[_M_THF, j] = math.nan
        M[_M_X0, j] = x0
        M[_M_LA, j] = la
        M[_M_LB, j] = x0 + 0.5 * (1.0 + middle) * travel
        M[_M_LC2, j] = Y1[i] - sign * (1.0 - threshold) * EOPEN[i]
    for k in range(1, nsteps + 1):
        t = (k - 1) * h
        # the step input, as hydroarm.core.inputs.evaluate gives it for the table
        # (t_step, t_step) -> (y0, y1), at the start, middle and end of the step
        on_a, on_m, on_b = t >= t_step, t + 0.5 * h >= t_step, t + h >= t_step
        # constant method and physics in each loop, so that each compiles to its own
        # branch-free (vectorisable) loop
        if method == EULER:
            if paper:
                nev = _advance_lanes(S, EULER, True, B, k, h, t_step, on_a, on_m, on_b)
            else:
                nev = _advance_lanes(S, EULER, False, m, k, h, t_step, on_a, on_m, on_b)
        elif paper:
            nev = _advance_lanes(S, RK4, True, B, k, h, t_step, on_a, on_m, on_b)
        else:
            nev = _advance_lanes(S, RK4, False, m, k, h, t_step, on_a, on_m, on_b)
        if nev:
            for j in range(m):
                if S[_F_EVENT * B + j] > 0.5:
                    _observe(S, M, j, k, h, t_step)
    for j in range(m):
        J = joint_at(PARAMS, i0 + j)
        out = OUT[i0 + j]
        failed = S[_F_ALIVE * B + j] < 0.5
        th = M[_M_THF, j] if failed else S[_F_TH * B + j]
        sign = S[_F_SIGN * B + j]
        x0 = M[_M_X0, j]
        y1 = Y1[i0 + j]
        la, lb = M[_M_LA, j], M[_M_LB, j]
        ta, tb = M[_M_TA, j], M[_M_TB, j]
        reach = sign * (jack_position(S[_F_THX * B + j], J) - x0)
        commanded = abs(y1 - x0)
        stalled = sign * (y1 - (x0 + sign * reach)) > stall_tolerance * commanded
        out[_SAT] = abs(lb - la) / (tb - ta) if tb > ta else math.nan
        out[_TC0] = M[_M_TS, j] - t_step
        out[_TCV] = S[_F_T63 * B + j] - t_step
        out[_TC1] = math.nan if stalled else M[_M_TC2, j] - M[_M_TC1, j]
        out[_STALL] = 1.0 if stalled else 0.0
        out[_REACH] = reach
        out[_PEAK] = S[_F_PEAK * B + j]
        out[_XF] = jack_position(th, J)
        out[_FAIL] = 0.0
        out[_TA] = ta
        out[_TB] = tb
        if not reach > 0.0:  # held where it started: a stall with nothing to measure
            out[_SAT] = out[_TC0] = out[_TCV] = out[_TC1] = out[_TA] = out[_TB] = math.nan
        if failed:  # no metrics from a run that left the physics; the code says why
            for c in range(N_OUTPUTS):
                out[c] = math.nan
            out[_STALL] = 0.0
            out[_FAIL] = M[_M_FAIL, j]


@njit(parallel=True, cache=True, nogil=True, error_model="numpy")
def run_many(
    method,
    PARAMS,
    TH0,
    P0,
    Y0,
    Y1,
    XEND,
    VFULL,
    EOPEN,
    t_step,
    h,
    nsteps,
    middle,
    threshold,
    stall_tolerance,
    OUT,
):
    """`run_block` for every block of LANES rows of PARAMS, in parallel over blocks."""
    n = PARAMS.shape[0]
    for b in prange((n + LANES - 1) // LANES):
        i0 = b * LANES
        run_block(
            method,
            PARAMS,
            TH0,
            P0,
            Y0,
            Y1,
            XEND,
            VFULL,
            EOPEN,
            i0,
            min(LANES, n - i0),
            t_step,
            h,
            nsteps,
            middle,
            threshold,
            stall_tolerance,
            OUT,
        )


@njit(cache=True, nogil=True, error_model="numpy")
def _full_opening_velocity(table):
    """K_q·e_o/A [m/s] of every row of a batch table."""
    out = np.empty(table.shape[0])
    for i in range(table.shape[0]):
        J = joint_at(table, i)
        out[i] = flow_gain(J) * J.valve_saturation / J.piston_area
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _jack_positions(table, theta):
    """Jack position [m] of each row of a batch table at its angle ``theta[i]``."""
    out = np.empty(table.shape[0])
    for i in range(table.shape[0]):
        out[i] = jack_position(theta[i], joint_at(table, i))
    return out


def run_batch(
    method: int,
    params: np.ndarray,  # (n, N_ROW) batch table, one row per scenario
    theta0,
    p0,
    y0,
    y1,
    *,
    t_step: float,
    h: float,
    nsteps: int,
    middle: float = DEFAULT_METRIC_OPTIONS.middle,
    threshold: float = DEFAULT_METRIC_OPTIONS.threshold,
    stall_tolerance: float = DEFAULT_METRIC_OPTIONS.stall_tolerance,
    metric_options: MetricOptions | None = None,
) -> np.ndarray:
    """Metrics (n, len(OUTPUTS)): the columns of `METRICS` and the averaging window of
    the saturation velocity, of n step-input scenarios; stalled ones re-run up to stall.

    ``metric_options`` (a [`MetricOptions`][hydroarm.MetricOptions]), when given, sets
    ``middle``, ``threshold`` and ``stall_tolerance``.
    """
    if metric_options is not None:
        middle = metric_options.middle
        threshold = metric_options.threshold
        stall_tolerance = metric_options.stall_tolerance
    params = np.ascontiguousarray(params, dtype=float)
    n = params.shape[0]
    th0 = np.asarray(theta0, float)
    y0 = np.asarray(y0, float)
    y1 = np.asarray(y1, float)
    p0 = np.asarray(p0, float)
    vfull = _full_opening_velocity(params)
    eopen = params[:, J_E_SAT].copy()
    out = np.empty((n, N_OUTPUTS))
    xend = y1.copy()
    run_many(
        method,
        params,
        th0,
        p0,
        y0,
        y1,
        xend,
        vfull,
        eopen,
        t_step,
        h,
        nsteps,
        middle,
        threshold,
        stall_tolerance,
        out,
    )
    st = np.nonzero(out[:, _STALL] > 0.5)[0]
    if st.size:  # velocity up to the stall: the window of the travel actually made
        x0 = _jack_positions(params[st], th0[st])
        sign = np.where(y1[st] >= x0, 1.0, -1.0)
        xend2 = x0 + sign * out[st, _REACH]
        out2 = np.empty((st.size, N_OUTPUTS))
        run_many(
            method,
            params[st],
            th0[st],
            p0[st],
            y0[st],
            y1[st],
            xend2,
            vfull[st],
            eopen[st],
            t_step,
            h,
            nsteps,
            middle,
            threshold,
            stall_tolerance,
            out2,
        )
        out[st] = out2
    return out


def run_scenarios(scenarios) -> list[dict]:
    """Metrics of a list of step-input [`Scenario`][hydroarm.Scenario] s, run as one
    batch (they must share method, step, duration and step time)."""
    scs = list(scenarios)
    if not scs:
        return []
    s0 = scs[0]
    for sc in scs:
        if sc.lever.description != "step":
            raise HydroarmError("input", "the batch engine runs step inputs")
        if (sc.method, sc.step, sc.nsteps, float(sc.lever.times[0])) != (
            s0.method,
            s0.step,
            s0.nsteps,
            float(s0.lever.times[0]),
        ):
            raise HydroarmError("solver", "a batch needs one method, step, duration and step time")
        if sc.metric_options != s0.metric_options:
            raise HydroarmError("metrics", "a batch needs one set of metric options")
        if not registry.method(sc.method).fixed_step:
            raise HydroarmError(
                "solver.method",
                f"the batch engine runs {' or '.join(registry.fixed_step_methods())}",
            )
    params = np.array([sc.row for sc in scs])
    out = run_batch(
        registry.method(s0.method).code,
        params,
        [sc.initial_angle for sc in scs],
        [sc.start_pressure() for sc in scs],
        [float(sc.lever.positions[0]) for sc in scs],
        [sc.target for sc in scs],
        t_step=float(s0.lever.times[0]),
        h=s0.step,
        nsteps=s0.nsteps,
        metric_options=s0.metric_options,
    )
    return [
        {**dict(zip(METRICS, row, strict=False)), "failure": failure_reason(row[_FAIL])}
        for row in out
    ]


def on_the_fly(sc) -> bool:
    """Whether a [`Scenario`][hydroarm.Scenario] 's metrics can be observed by the
    kernels here: a step lever, a fixed-step method, time starting at 0."""
    return sc.lever.description == "step" and registry.method(sc.method).fixed_step and sc.t0 == 0.0


def scenario_metrics(sc) -> dict:
    """The step metrics of one scenario (`on_the_fly`), observed at every step, with the
    keys of [`hydroarm.metrics.step.step_metrics`][hydroarm.step_metrics] plus ``peak_pressure``
    [Pa] and ``final_x`` [m]."""
    return scenarios_metrics([sc])[0]


def scenarios_metrics(scenarios, *, keep_failures: bool = False) -> list[dict]:
    """`scenario_metrics` of several scenarios run as one batch (they must share
    method, step, duration, step time and metric options, as for `run_scenarios`);
    the same kernel, so the same numbers as one by one.

    A run that left the physical bounds is an error, or with ``keep_failures`` a dictionary
    ``{"failure": reason}`` in its place (every other entry has a ``failure`` of None)."""
    scs = list(scenarios)
    if not scs:
        return []
    sc0 = scs[0]
    for sc in scs:
        if (sc.method, sc.step, sc.nsteps, float(sc.lever.times[0]), sc.metric_options) != (
            sc0.method,
            sc0.step,
            sc0.nsteps,
            float(sc0.lever.times[0]),
            sc0.metric_options,
        ):
            raise HydroarmError(
                "solver", "a batch needs one method, step, duration, step time and metrics"
            )
    params = np.array([sc.row for sc in scs])
    th0 = np.array([sc.initial_angle for sc in scs])
    out = run_batch(
        registry.method(sc0.method).code,
        params,
        th0,
        [sc.start_pressure() for sc in scs],
        [float(sc.lever.positions[0]) for sc in scs],
        [sc.target for sc in scs],
        t_step=float(sc0.lever.times[0]),
        h=sc0.step,
        nsteps=sc0.nsteps,
        metric_options=sc0.metric_options,
    )
    x0s = _jack_positions(params, th0)
    return [
        _metric_dict(sc, row, float(x0), keep_failures)
        for sc, row, x0 in zip(scs, out, x0s, strict=True)
    ]


def _metric_dict(sc, row, x0: float, keep_failures: bool = False) -> dict:
    if row[_FAIL] > 0.5:
        if keep_failures:
            return {"failure": failure_reason(row[_FAIL])}
        raise HydroarmError("metrics", f"the run failed ({failure_reason(row[_FAIL])})")
    sign = 1.0 if sc.target >= x0 else -1.0
    stalled = bool(row[_STALL] > 0.5)
    reach = float(row[_REACH])
    moved = reach > 0.0
    reason = None
    if stalled:
        reason = (
            "stopped short of the target"
            if moved
            else "the joint does not move toward the target (held by friction or the load)"
        )
    return {
        "saturation_velocity": float(row[_SAT]),
        "direction": int(sign),
        "time_constant_start": float(row[_TC0]),
        "time_constant_start_velocity": float(row[_TCV]),
        "time_constant_end": float(row[_TC1]),
        "stalled": stalled,
        "stall_position": x0 + sign * reach if stalled else math.nan,
        "t_middle": (float(row[_TA]), float(row[_TB])),
        "travel": sign * max(reach, 0.0) if stalled else sc.target - x0,
        "stall_reason": reason,
        "peak_pressure": float(row[_PEAK]),
        "final_x": float(row[_XF]),
        **({"failure": None} if keep_failures else {}),
    }


def failure_reason(code: float) -> str | None:
    """The name of a ``failed`` metric's code (None: the run did not fail)."""
    return FAILURES.get(int(code)) if code > 0.5 else None
