"""Observers on the system kernel: statistics of named outputs computed while a run steps
(issue 28; docs/batch.md "Studies of a circuit").

`observe` runs one row on the one loop's step (`take_step`, the body of `advance_steps`),
to each sample (every step, or every ``every``-th: the states `integrate` records at
``record_every = every``), and at each
evaluates the outputs the metrics read (`outputs_at`, what
`record_outputs` gives at each record, on a work tuple of
its own, so that observing never touches the run's) and updates each metric's running
statistic: memory per row is the metrics' accumulators, whatever the number of steps.
`observe_many` does it for every row of a parameter table in parallel, a row's values
those of `observe` alone, bit for bit.

An output is a quantity of the kernel times a factor (its display unit): a row of
``sources`` (what, i, k) and ``factors``: a state ``s[i]``, a signal, a mechanical quantity
(``mech[i]`` of `outputs_at`), a port's flow ``flows[i, k]``, a component's power.
A metric is a row of ``metrics`` (output, statistic) and of ``windows`` (after, before [s],
target, scale; the last two for `TARGET_STATISTICS` only):
the samples t_k = t0 + k·h (k = 0, every, 2·every … ≤ nsteps, the start state included)
with after ≤ t_k ≤ before, as `hydroarm.metrics.trace.trace_statistic` selects a trace's.

The statistics an observer computes (`ONLINE_STATISTICS`) are those of
`hydroarm.metrics.trace` that one pass can give, each as the trace statistic defines it
over the same samples:

* ``max``, ``min``, ``final``, ``initial``, ``peak_to_peak``, ``max_abs``, ``time_of_max``,
  ``time_of_min`` (the first sample of the extreme, as ``argmax``), ``overshoot`` and
  ``peak_time`` (python-control's definitions from the window's first value, its last and
  the extremes): equal to the trace statistic of the same samples bit for bit;
* ``integral``, ``mean``, ``rms``: the same trapezoid terms, summed as they come (Neumaier's
  compensated sum) where numpy sums a trace's pairwise: equal up to the sums' rounding,
  a few ε·Σ|terms|.

``settling_time`` and ``rise_time`` have no one-pass definition: both are measured against
the window's final value, unknown until the run ends (the last sample outside a band around
it; the first to reach a fraction of it), so they stay statistics of recorded traces.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..core.circuit.dispatch import follows_components
from ..core.circuit.laws import inlined_kernel, kernel
from ..core.circuit.system import (
    MAX_PORTS,
    evaluate_signals,
    make_work,
    outputs_at,
    system_project,
    with_derived,
)
from .system import step_buffers, take_step

#: what an output reads (a row of ``sources``: (what, i, k))
SOURCE_STATE, SOURCE_SIGNAL, SOURCE_MECHANICAL, SOURCE_FLOW, SOURCE_POWER = range(5)

#: the statistics of `hydroarm.metrics.trace` an observer computes, by code
ONLINE_STATISTICS: dict[str, int] = {
    name: code
    for code, name in enumerate(
        (
            "max",
            "min",
            "final",
            "initial",
            "peak_to_peak",
            "max_abs",
            "integral",
            "mean",
            "rms",
            "time_of_max",
            "time_of_min",
            "overshoot",
            "peak_time",
        )
    )
}
#: statistics against a target known before the run (``windows[m, 2:4]``: target, scale), no
#: trace statistic's: ``settled_at``, the time after the window's start from which the output
#: stays within ± scale of the target (NaN: outside at the end); ``overshoot_past``, the
#: largest excursion past the target in the direction of sign(scale), over |scale| (0 when it
#: never passes). A component servo's settling time and overshoot (metrics/servo.py) are
#: these of its measurement (`hydroarm.model.servo_observers`).
TARGET_STATISTICS = {
    "settled_at": len(ONLINE_STATISTICS),
    "overshoot_past": len(ONLINE_STATISTICS) + 1,
}
#: the trace statistics no observer computes, and why (module doc)
TRACE_ONLY = {
    "settling_time": "the last sample outside a band around the final value, unknown until the end",
    "rise_time": "the first samples to reach fractions of the final value, unknown until the end",
}
(
    ST_MAX,
    ST_MIN,
    ST_FINAL,
    ST_INITIAL,
    ST_PEAK_TO_PEAK,
    ST_MAX_ABS,
    ST_INTEGRAL,
    ST_MEAN,
    ST_RMS,
    ST_TIME_OF_MAX,
    ST_TIME_OF_MIN,
    ST_OVERSHOOT,
    ST_PEAK_TIME,
) = range(len(ONLINE_STATISTICS))
ST_SETTLED_AT, ST_OVERSHOOT_PAST = TARGET_STATISTICS.values()
#: ``last[m]`` of a metric updated at every sample in its window, and of one whose window
#: holds no sample (`last_samples`)
EVERY_SAMPLE, NO_SAMPLE = -1, -2

# a metric's accumulator: samples, first (y, t), last (y, t), max and its time, min and its
# time, max |y|, ∫y dt and its compensation, ∫y² dt and its, max |y − y_first| and its time,
# a non-finite sample seen, the start of the last stretch near the target (NaN: away), the
# largest excursion past it
(N, Y0, T0, YL, TL, MX, TMX, MN, TMN, MA, I1, C1, I2, C2, PK, TPK, BAD, IN, OV) = range(19)
SLOTS = 19
#: bytes an observed row holds per metric (its accumulator), whatever the run's length
BYTES_PER_METRIC = SLOTS * 8


@inlined_kernel
def _add(acc, m, i, x):
    """Neumaier's compensated sum: acc[m, i] += x, the lost low part kept in acc[m, i + 1]."""
    s = acc[m, i]
    t = s + x
    if abs(s) >= abs(x):
        acc[m, i + 1] += (s - t) + x
    else:
        acc[m, i + 1] += (x - t) + s
    acc[m, i] = t


@inlined_kernel
def update(acc, m, t, y, target, scale, code):
    """One sample (t, y) into metric m's accumulator (a row of ``acc``) (module doc);
    ``target``, ``scale``: those of `TARGET_STATISTICS` (a servo's, metrics/servo.py);
    ``code``: the metric's statistic. Only the slots that statistic reads (`statistic_of`)
    are kept up to date, each as it would be with all of them (the others are never read):
    a servo's study observes some thirty metrics a step, most of them a ``final``, and the
    whole accumulator for each was about a third of a step's time
    (benchmarks/servo_throughput.py)."""
    if not math.isfinite(y):
        acc[m, BAD] = 1.0
    if code == ST_FINAL:  # the last sample, kept below
        acc[m, YL] = y
        acc[m, TL] = t
        acc[m, N] += 1.0
        return
    if code >= ST_SETTLED_AT:  # the target's statistics
        e = y - target
        if abs(e) > abs(scale):
            acc[m, IN] = math.nan
        elif acc[m, N] == 0.0 or math.isnan(acc[m, IN]):
            acc[m, IN] = t
        if scale != 0.0:
            over = (e if scale > 0.0 else -e) / abs(scale)
            if over > acc[m, OV]:
                acc[m, OV] = over
    if acc[m, N] == 0.0:
        acc[m, Y0] = y
        acc[m, T0] = t
        acc[m, MX] = y
        acc[m, TMX] = t
        acc[m, MN] = y
        acc[m, TMN] = t
        acc[m, MA] = abs(y)
        acc[m, PK] = 0.0
        acc[m, TPK] = t
    elif code < ST_SETTLED_AT and code != ST_INITIAL:
        if y > acc[m, MX]:  # the first sample of the largest, as argmax
            acc[m, MX] = y
            acc[m, TMX] = t
        if y < acc[m, MN]:
            acc[m, MN] = y
            acc[m, TMN] = t
        a = abs(y)
        if a > acc[m, MA]:
            acc[m, MA] = a
        if code == ST_INTEGRAL or code == ST_MEAN or code == ST_RMS:
            yl = acc[m, YL]
            d = t - acc[m, TL]  # the trapezoid's term as numpy.trapezoid writes it
            _add(acc, m, I1, d * (y + yl) / 2.0)
            _add(acc, m, I2, d * (y * y + yl * yl) / 2.0)
        p = abs(y - acc[m, Y0])
        if p > acc[m, PK]:
            acc[m, PK] = p
            acc[m, TPK] = t
    acc[m, YL] = y
    acc[m, TL] = t
    acc[m, N] += 1.0


@kernel
def statistic_of(acc, m, code, after):
    """Metric m's value from its accumulator (NaN: no sample in its window, or one not
    finite, as `hydroarm.metrics.trace.trace_statistic`); ``after``: its window's
    start (a settling time's origin where finite, else its first sample's time)."""
    n = acc[m, N]
    if n == 0.0 or acc[m, BAD] != 0.0:
        return math.nan
    if code == ST_SETTLED_AT:
        return acc[m, IN] - (after if math.isfinite(after) else acc[m, T0])
    if code == ST_OVERSHOOT_PAST:
        return acc[m, OV]
    if code == ST_MAX:
        return acc[m, MX]
    if code == ST_MIN:
        return acc[m, MN]
    if code == ST_FINAL:
        return acc[m, YL]
    if code == ST_INITIAL:
        return acc[m, Y0]
    if code == ST_PEAK_TO_PEAK:
        return acc[m, MX] - acc[m, MN]
    if code == ST_MAX_ABS:
        return acc[m, MA]
    if code == ST_TIME_OF_MAX:
        return acc[m, TMX]
    if code == ST_TIME_OF_MIN:
        return acc[m, TMN]
    span = acc[m, TL] - acc[m, T0]
    if code == ST_INTEGRAL:
        return acc[m, I1] + acc[m, C1] if n > 1.0 else 0.0
    if code == ST_MEAN:
        return (acc[m, I1] + acc[m, C1]) / span if span > 0 else acc[m, Y0]
    if code == ST_RMS:
        return math.sqrt((acc[m, I2] + acc[m, C2]) / span) if span > 0 else abs(acc[m, Y0])
    # python-control's step_info of y − y_first over t − t_first (metrics.trace)
    y0 = acc[m, Y0]
    if n < 3.0 or acc[m, YL] == y0:
        return math.nan
    if code == ST_PEAK_TIME:
        return acc[m, TPK] - acc[m, T0]
    final = acc[m, YL] - y0
    y_os = acc[m, MX] - y0 if final > 0 else -(acc[m, MN] - y0)  # max(sign·(y − y0)), monotone
    dy = abs(y_os) - abs(final)
    return abs(100.0 * dy / final) if dy > 0 else 0.0


@kernel
def output_value(j, s, flows, power, sig, mech, sources, factors):
    """Output ``j`` (module doc) from a state and its `outputs_at`."""
    what, i, k = sources[j, 0], sources[j, 1], sources[j, 2]
    if what == SOURCE_STATE:
        x = s[i]
    elif what == SOURCE_SIGNAL:
        x = sig[i]
    elif what == SOURCE_MECHANICAL:
        x = mech[i]
    elif what == SOURCE_FLOW:
        x = flows[i, k]
    else:
        x = power[i]
    f = factors[j]
    return x if f == 1.0 else x * f


@inlined_kernel
def evaluate_outputs(t, s, P, net, owork, d, flows, power, sig, mech, level):
    """The outputs the observers read at (t, s), on the observers' own work arrays:
    ``level`` 1, the signals (`evaluate_signals`, as the
    right-hand side evaluates them first); 2, every output (`outputs_at`). (Level 0,
    states only, has nothing to evaluate and is never called.)"""
    if level == 2:
        outputs_at(t, s, P, net, owork, d, flows, power, sig, mech)
    else:
        evaluate_signals(t, s, P, net, owork)
        ws = owork[3]
        for i in range(sig.shape[0]):
            sig[i] = ws[i]


@inlined_kernel
def observe_values(
    t, sample, s, flows, power, sig, mech, sources, factors, metrics, windows, y, acc, plan,
    last,
):  # fmt: skip
    """Every metric whose window holds t takes its output at (t, s), the outputs read once,
    as ``plan`` (`last_samples`) orders: the outputs read at every sample, the metrics
    updated at every sample, then those kept at one sample only (``last[m]``) at that one
    (``sample``: this sample's number, the start 0).
    Neither this nor `evaluate_outputs` is compiled into `observe`: there,
    numba's reference counting of the net's and the work's arrays (some 60) cost more than
    a step of the counterbalance circuit (benchmarks/circuit_observers.py); both are
    compiled into `observe_steps`, which has none."""
    read, often, late, first = plan[0], plan[1], plan[2], plan[3]
    for jj in range(read.shape[0]):
        j = read[jj]
        y[j] = output_value(j, s, flows, power, sig, mech, sources, factors)
    for mm in range(often.shape[0]):
        m = often[mm]
        if windows[m, 0] <= t <= windows[m, 1]:
            update(acc, m, t, y[metrics[m, 0]], windows[m, 2], windows[m, 3], metrics[m, 1])
    if sample >= first[0]:
        for mm in range(late.shape[0]):
            m = late[mm]
            if last[m] == sample:
                x = output_value(metrics[m, 0], s, flows, power, sig, mech, sources, factors)
                update(acc, m, t, x, windows[m, 2], windows[m, 3], metrics[m, 1])


@njit(cache=True, nogil=True, error_model="numpy")
def last_samples(t0, h, nsteps, every, sources, metrics, windows, probes):
    """(last, plan): ``last[m]`` the one sample at which metric m is updated, its window's
    last (`NO_SAMPLE`: none), or `EVERY_SAMPLE`; ``plan``: (the outputs read at every
    sample, the metrics updated at every sample in their windows, those updated at one
    sample only, [the first of those samples]), what `observe_values` loops over. A
    ``final`` of a state is its window's last sample's value: every state the run takes is
    finite (the run stops at the first that is not), so no earlier sample can mark it not
    finite, and only the last is read. A servo's study keeps some twenty finals of states
    (its energies, pressures, position), and looping over them and their outputs at every
    sample was some 50 ns a step (benchmarks/servo_throughput.py)."""
    nmet = metrics.shape[0]
    last = np.full(nmet, EVERY_SAMPLE, np.int64)
    need = np.zeros(sources.shape[0], np.bool_)
    samples = nsteps // every + 1
    first = samples
    for m in range(nmet):
        j = metrics[m, 0]
        if metrics[m, 1] != ST_FINAL or sources[j, 0] != SOURCE_STATE:
            need[j] = True
            continue
        last[m] = NO_SAMPLE
        for q in range(samples - 1, -1, -1):  # the samples' times as observe_steps takes them
            t = t0 if q == 0 else t0 + (q * every) * h
            if windows[m, 0] <= t <= windows[m, 1]:
                last[m] = q
                first = min(first, q)
                break
            if t < windows[m, 0]:
                break
    for p in range(probes.shape[0]):
        need[probes[p]] = True
    often = np.nonzero(last == EVERY_SAMPLE)[0]
    late = np.nonzero(last >= 0)[0]
    return last, (np.nonzero(need)[0], often, late, np.array([first], np.int64))


@kernel
def in_a_window(t, windows):
    """Whether some metric's window holds t."""
    for m in range(windows.shape[0]):
        if windows[m, 0] <= t <= windows[m, 1]:
            return True
    return False


@njit(cache=True, nogil=True, error_model="numpy")
def observe(
    code, A, b, c, s0, t0, h, nsteps, P, net, sources, factors, metrics, windows, every,
    probes, trace,
):  # fmt: skip
    """Run ``nsteps`` fixed steps from s0 at t0 (the start projected as
    `integrate` projects it) on
    `advance_steps`, observing the start and every ``every``-th state after it (1: every
    state; a run's ``record_every``: the states `integrate` records, at the same times)
    (module doc). The outputs ``probes`` (rows of ``sources``) are kept at every sample in
    ``trace`` (samples × probes, the start first): a probe's trace is the run's recorded
    column at ``record_every = every``, what a statistic of a trace only (`TRACE_ONLY`) is
    read from.

    Returns (values (metrics,), bad_step): bad_step is −1 or the first step whose state was
    not finite (the run stops there; the values are NaN, ``trace`` filled to the sample
    before it)."""
    n = s0.shape[0]
    P = with_derived(P, net)  # the components' derived quantities, once per row
    work = make_work(net)
    owork = make_work(net)  # the outputs' evaluations: never the run's work arrays
    s = s0.copy()
    out, K, tmp = step_buffers(b, n)
    d = np.empty(n)
    dims = net[9]
    nm, nc = dims[1], dims[3]
    flows = np.zeros((nc, MAX_PORTS))
    power = np.zeros(nc)
    sig = np.zeros(max(dims[2], 1))
    mech = np.zeros(nm + net[23].shape[0] + 1)
    level = 0
    for j in range(sources.shape[0]):
        if sources[j, 0] == SOURCE_SIGNAL:
            level = max(level, 1)
        elif sources[j, 0] != SOURCE_STATE:
            level = 2
    y = np.zeros(max(sources.shape[0], 1))
    nmet = metrics.shape[0]
    acc = np.zeros((nmet, SLOTS))
    values = np.full(nmet, np.nan)
    last, plan = last_samples(t0, h, nsteps, every, sources, metrics, windows, probes)
    system_project(t0, 0.0, s0, s, P, net, work, 1.0)  # sources and latches at the start
    bad = observe_steps(
        code, A, b, c, t0, h, nsteps, every, s, P, net, work, out, K, tmp, owork, d, flows,
        power, sig, mech, level, sources, factors, metrics, windows, y, acc, probes, trace,
        plan, last,
    )  # fmt: skip
    if bad >= 0:
        return values, bad
    for m in range(nmet):
        values[m] = statistic_of(acc, m, metrics[m, 1], windows[m, 0])
    return values, -1


@kernel
def observe_steps(
    code, A, b, c, t0, h, nsteps, every, s, P, net, work, out, K, tmp, owork, d, flows, power,
    sig, mech, level, sources, factors, metrics, windows, y, acc, probes, trace, plan, last,
):  # fmt: skip
    """The observed run of `observe` from its projected start ``s`` (in place): the start
    observed, then each step (`take_step`, the body of the one loop `advance_steps`,
    compiled in) and every ``every``-th state observed, the probes kept in ``trace``. One
    call a run, free of numba's reference counting: a call of the loop a step copied the
    net's and the work's arrays (some 500 words), about a fifth of a step of the position
    servo (benchmarks/servo_throughput.py). Returns −1, or the first step whose state was
    not finite (the run stops there)."""
    probing = probes.shape[0] > 0
    if probing or in_a_window(t0, windows):
        if level > 0:
            evaluate_outputs(t0, s, P, net, owork, d, flows, power, sig, mech, level)
        observe_values(
            t0, 0, s, flows, power, sig, mech, sources, factors, metrics, windows, y, acc,
            plan, last,
        )  # fmt: skip
        for p in range(probes.shape[0]):
            trace[0, p] = y[probes[p]]
    sample = 1
    for k in range(nsteps):
        if not take_step(code, A, b, c, t0, k, h, s, P, net, work, out, K, tmp):
            return k + 1
        if (k + 1) % every != 0:
            continue
        t = t0 + (k + 1) * h  # the record's time in integrate(), the same float
        if probing or in_a_window(t, windows):
            if level > 0:
                evaluate_outputs(t, s, P, net, owork, d, flows, power, sig, mech, level)
            observe_values(
                t, sample, s, flows, power, sig, mech, sources, factors, metrics, windows,
                y, acc, plan, last,
            )  # fmt: skip
            for p in range(probes.shape[0]):
                trace[sample, p] = y[probes[p]]
        sample += 1
    return -1


@njit(cache=True, nogil=True, error_model="numpy", parallel=True)
def observe_many(
    code, A, b, c, S0, t0, h, nsteps, table, net, sources, factors, metrics, windows, every,
    probes, traces,
):  # fmt: skip
    """`observe` for every row of a parameter table (initial states S0 row by row), in
    parallel: (values (rows × metrics), bad_step per row), the probes' samples of row i in
    ``traces[i]``. A row's values and trace are the single row's, bit for bit."""
    rows = table.shape[0]
    values = np.full((rows, metrics.shape[0]), np.nan)
    bad = np.empty(rows, np.int64)
    for i in prange(rows):
        v, bb = observe(
            code, A, b, c, S0[i], t0, h, nsteps, table[i], net, sources, factors, metrics,
            windows, every, probes, traces[i],
        )  # fmt: skip
        values[i, :] = v
        bad[i] = bb
    return values, bad


follows_components(
    _add,
    update,
    statistic_of,
    output_value,
    evaluate_outputs,
    observe_values,
    last_samples,
    in_a_window,
    observe_steps,
    observe,
    observe_many,
)
