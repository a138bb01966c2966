"""Observers on the system kernel (hydroarm.integrators.observers): statistics of named
outputs updated at every step of the one loop, against the same statistics of a trace
recorded at every step (record_every = 1), and the circuit studies that use them."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.analysis import systems as S
from hydroarm.analysis.sensitivity import CircuitModel, circuit_study_from_doc
from hydroarm.batch.circuit_sweep import (
    circuit_chunk_columns,
    run_circuit_chunk,
    run_study_chunk,
    traced_chunk,
)
from hydroarm.batch.sweep import load_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.core.servo import PARAMETER_INDEX
from hydroarm.integrators import observers
from hydroarm.integrators.observers import ONLINE_STATISTICS, TARGET_STATISTICS, TRACE_ONLY
from hydroarm.integrators.system import stepper
from hydroarm.io.circuit import load_circuit
from hydroarm.io.schema import load_scenario
from hydroarm.io.sections import parse_toml
from hydroarm.metrics.servo import METRIC_INDEX, METRICS
from hydroarm.metrics.trace import STATISTICS, trace_statistic
from hydroarm.model.circuit import (
    build,
    observe_many,
    output_sources,
    probe_many,
    row_initial_states,
    simulate,
    simulate_many,
)
from hydroarm.model.servo_observers import servo_circuit_metrics
from hydroarm.reference import metrics_on_servo_kernel

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
CBV = EXAMPLES / "counterbalance.toml"
EPS = np.finfo(float).eps

# every kind of output the kernel gives: a state (a pressure in bar: a factor), a position,
# a signal, a port's flow (L/min: a factor), a force on a mechanical port, a power
OUTPUTS = (
    "cap_pressure_bar",
    "load_position_m",
    "load_velocity_m_s",
    "spool_demand_signal",
    "cbv_flow_lpm",
    "jack_force_n",
    "cbv_power_w",
)
EXACT = ("max", "min", "final", "initial", "peak_to_peak", "max_abs", "time_of_max",
         "time_of_min", "overshoot", "peak_time")  # fmt: skip
SUMS = ("integral", "mean", "rms")
WINDOWS = ((-math.inf, math.inf), (0.05, 0.35))  # the whole run; a window inside it


@pytest.fixture(scope="module")
def every_step():
    """The counterbalance circuit for 0.45 s (45 000 steps: the spool starts to open at
    0.3 s) recorded at every step, and two rows of its parameter table (the file's, a
    heavier load)."""
    circuit = dataclasses.replace(load_circuit(CBV), duration=0.45, record_every=1)
    cc = build(circuit)
    table = np.repeat(cc.P[None, :], 2, axis=0)
    table[1, cc.parameter_index["payload.mass"]] *= 1.5
    S0 = cc.initial_states(table)
    return circuit, cc, table, S0


def test_the_statistics_split_into_online_and_trace_only():
    assert set(ONLINE_STATISTICS) | set(TRACE_ONLY) == set(STATISTICS)
    assert not set(ONLINE_STATISTICS) & set(TRACE_ONLY)
    assert set(ONLINE_STATISTICS) == set(EXACT) | set(SUMS)
    assert not set(TARGET_STATISTICS) & set(STATISTICS)  # the servo's, no trace statistic


@pytest.fixture(scope="module")
def every_step_columns(every_step):
    """The columns of each row of `every_step` run alone, recorded at every step."""
    circuit, cc, table, _ = every_step
    out = []
    for r in range(2):
        row = circuit.with_values(
            {"payload.mass": float(table[r, cc.parameter_index["payload.mass"]])}
        )
        out.append(simulate(dataclasses.replace(row, record_every=1)).columns())
    return out


def assert_observed(got, t, y, st, a, b):
    """An observed statistic against trace_statistic of the samples (t, y): equal bit for
    bit but for the trapezoid sums, which differ only by the order of summation (below)."""
    ref = trace_statistic(t, y, st, after=a, before=b)
    if st in EXACT:
        assert got == ref or (math.isnan(got) and math.isnan(ref)), (st, a, b, got, ref)
        return
    # numpy.trapezoid adds the same terms pairwise (blocks of up to 128 in order,
    # error <= 127 eps sum|terms|, then log2 n pairwise levels), the observer in
    # order with Neumaier's compensation (error <= 2 eps sum|terms|): they differ by
    # at most (129 + log2 n) eps sum|terms| (Higham, Accuracy and Stability of
    # Numerical Algorithms, 4.2 and 4.3)
    keep = (t >= a) & (t <= b)
    tt, y = t[keep], y[keep]
    y = y * y if st == "rms" else y
    terms = np.abs(np.diff(tt) * (y[1:] + y[:-1]) / 2.0)
    tol = (129 + math.log2(len(tt))) * EPS * float(np.sum(terms))
    span = tt[-1] - tt[0]
    if st == "integral":
        assert abs(got - ref) <= tol, (st, a, b, got, ref)
    elif st == "mean":  # the sums over span, the quotients each rounded (ε)
        assert abs(got - ref) <= tol / span + 2 * EPS * abs(ref), (st, got, ref)
    else:  # sqrt(sum / span): got² − ref² = (got − ref)(got + ref), and the roundings
        bound = tol / span / (got + ref) if got + ref > 0 else 0.0
        assert abs(got - ref) <= bound + 3 * EPS * ref, (st, a, b, got, ref)


def test_observed_statistics_equal_every_step_traces(every_step, every_step_columns):
    """Each online statistic of each kind of output, observed while the run steps, against
    trace_statistic of the same run recorded at every step (`assert_observed`)."""
    circuit, cc, table, S0 = every_step
    assert all(o in output_sources(cc) for o in OUTPUTS)
    specs = [(o, st, a, b) for o in OUTPUTS for st in ONLINE_STATISTICS for a, b in WINDOWS]
    values, bad = observe_many(cc, table, S0, specs)
    assert list(bad) == [-1, -1]
    for r in range(2):
        cols = every_step_columns[r]
        t = cols["t_s"]
        assert len(t) == 45_001  # every step and the start
        for j, (o, st, a, b) in enumerate(specs):
            assert_observed(values[r, j], t, cols[o], st, a, b)
        # the observers saw more than a sweep's records would (every 200th step): its
        # extremes are at least as far out, and some further
        far, further = True, 0
        for j, (o, st, a, b) in enumerate(specs):
            if st in ("max", "min"):
                sparse = trace_statistic(t[::200], cols[o][::200], st, after=a, before=b)
                sign = 1.0 if st == "max" else -1.0
                far = far and sign * (values[r, j] - sparse) >= 0.0
                further += sign * (values[r, j] - sparse) > 0.0
        assert far and further >= 4, further


@pytest.mark.parametrize("every", [100, 160])
def test_observed_at_the_records_equal_the_records_traces(every_step, every_step_columns, every):
    """Observing every ``every``-th step (a design's and a sensitivity study's rows, at the
    circuit's record_every): the statistics of the records simulate keeps at record_every =
    every (the start and the steps k·every; 45 000 is no multiple of 160: the last step is
    not a record, as integrate() leaves it), bit for bit but for the trapezoid sums."""
    circuit, cc, table, S0 = every_step
    specs = [(o, st, a, b) for o in OUTPUTS for st in ONLINE_STATISTICS for a, b in WINDOWS]
    values, bad = observe_many(cc, table, S0, specs, every)
    assert list(bad) == [-1, -1]
    records = simulate(dataclasses.replace(circuit, record_every=every)).columns()
    for r in range(2):
        cols = every_step_columns[r]
        t = cols["t_s"][::every]
        if r == 0:  # the records of the same run at record_every = every: these samples
            assert np.array_equal(records["t_s"], t)
            assert np.array_equal(records["cap_pressure_bar"], cols["cap_pressure_bar"][::every])
        for j, (o, st, a, b) in enumerate(specs):
            assert_observed(values[r, j], t, cols[o][::every], st, a, b)


def test_probes_are_the_recorded_columns(every_step, every_step_columns):
    """A probe's trace at every 160th step: the column simulate records at record_every =
    160, bit for bit (45 000 is no multiple of 160: the last step is no sample); a row that
    fails: NaN from its bad step."""
    circuit, cc, table, S0 = every_step
    values, bad, t, traces = probe_many(cc, table, S0, [], 160, OUTPUTS)
    assert values.shape == (2, 0) and list(bad) == [-1, -1]
    assert np.array_equal(t, every_step_columns[0]["t_s"][::160])
    for r in range(2):
        for k, o in enumerate(OUTPUTS):
            assert np.array_equal(traces[r, :, k], every_step_columns[r][o][::160]), o
    S0 = S0.copy()
    S0[1, cc.state_names.index(("cap.pressure", "Pa"))] = math.nan
    _, bad, _, traces = probe_many(cc, table, S0, [], 160, OUTPUTS[:1])
    assert list(bad) == [-1, 1] and np.isnan(traces[1]).all()


def test_a_row_observed_alone_equals_its_row_in_the_batch(every_step):
    """observe() of one row and its row of observe_many() (prange): compared with ==."""
    circuit, cc, table, S0 = every_step
    specs = [(o, st, -math.inf, math.inf) for o in OUTPUTS[:3] for st in ("max", "integral")]
    values, _ = observe_many(cc, table, S0, specs)
    known = output_sources(cc)
    names = list(dict.fromkeys(o for o, *_ in specs))
    sources = np.array([known[o][:3] for o in names], np.int64)
    factors = np.array([known[o][3] for o in names])
    metrics = np.array([(names.index(o), ONLINE_STATISTICS[st]) for o, st, *_ in specs])
    windows = np.array([(a, b, 0.0, 0.0) for *_, a, b in specs])
    code, A, b, c = stepper(circuit.method)
    n = int(round(circuit.duration / circuit.step))
    for r in range(2):
        alone, bad = observers.observe(code, A, b, c, S0[r], 0.0, circuit.step, n, table[r],
                                       cc.net, sources, factors, metrics, windows, 1,
                                       np.zeros(0, np.int64), np.zeros((0, 0)))  # fmt: skip
        assert bad == -1
        assert np.array_equal(alone, values[r])


def test_a_failing_row_is_failed_with_no_values(every_step):
    """A row whose state stops being finite: its bad step as the batch engine's, NaN values."""
    circuit, cc, table, S0 = every_step
    S0 = S0.copy()
    S0[1, cc.state_names.index(("cap.pressure", "Pa"))] = math.nan
    values, bad = observe_many(cc, table, S0, [("cap_pressure_bar", "max", -math.inf, math.inf)])
    assert bad[0] == -1 and bad[1] == 1
    assert list(simulate_many(cc, table, S0)[2]) == list(bad)
    assert math.isfinite(values[0, 0]) and math.isnan(values[1, 0])


STUDY = f"""
[system]
file = "{CBV.as_posix()}"
duration = "0.3 s"
record_every = 200
[grid]
"payload.mass" = ["500 kg", "900 kg"]
[metrics]
peak = {{ output = "cap_pressure_bar", statistic = "max" }}
drop = {{ output = "load_position_m", statistic = "peak_to_peak", after = "0.05 s" }}
"""


def test_a_study_observes_every_step(tmp_path, monkeypatch):
    """A study whose statistics are all online runs on the observers: its file holds the
    statistics of every step (those of the same rows recorded at every step, bit for bit),
    whatever the study's record_every; with a trace-only statistic it falls back to the
    records (its numbers those of traced_chunk)."""
    path = tmp_path / "s.toml"
    path.write_text(STUDY)
    sw = load_sweep(path)
    observed = run_study_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    out = run_sweep(sw, tmp_path / "r.csv", progress=lambda *a: None)
    rows = [line.split(",") for line in out.read_text().splitlines()[1:]]
    for r in range(sw.size):
        cols = simulate(dataclasses.replace(sw.row_circuit(r), record_every=1)).columns()
        assert list(observed[r, 1:]) == [m.of(cols) for m in sw.metrics]
        assert float(rows[r][3]) == pytest.approx(observed[r, 1], rel=1e-9)  # 10 digits
    traced = traced_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    assert not np.array_equal(traced, observed)  # the records miss the steps between them
    # observed at the records (a design's rows), the same numbers as the traces'
    at_records = run_circuit_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    assert np.array_equal(at_records, traced)
    path.write_text(
        STUDY + 'settle = { output = "load_position_m", statistic = "settling_time" }\n'
    )
    sw = load_sweep(path)
    assert not sw.metrics[-1].online
    traced = traced_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    with monkeypatch.context() as m:  # observed, the settling time from its output's probe
        m.setattr("hydroarm.batch.circuit_sweep.simulate_many", _no_records)
        probed = run_study_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
        m.setattr("hydroarm.batch.circuit_sweep.MAX_BLOCK_BYTES", 1)  # a row a block
        one_by_one = run_study_chunk(sw.circuit, sw.table, sw.initial, sw.metrics)
    assert np.array_equal(probed, traced, equal_nan=True)
    assert np.array_equal(one_by_one, traced, equal_nan=True)


def test_rows_times_metrics_over_the_budget_is_one_line(tmp_path, monkeypatch, capsys):
    """The study's rows × metrics against the budget, before any run."""
    (tmp_path / "s.toml").write_text(STUDY)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("hydroarm.batch.circuit_sweep.MAX_OBSERVED", 3)
    assert main(["sweep", "--config", "s.toml", "--out", "r.csv"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "hydroarm: error: metrics: 2 rows × 2 metrics are above the budget of 3 values "
        "(the results a study holds)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


SERVOS = {  # file, duration [s]: past each one's last step, with time to settle
    "position_servo": (EXAMPLES / "position_servo.toml", 1.5),
    "rotary_joint": (EXAMPLES / "rotary_joint.toml", 1.2),
    "linear_mechanical": (ROOT / "tests" / "data" / "servo_circuit" / "linear_mechanical.toml",
                          0.5),
    # a PID derivative gain (the pid takes the sensor's rate)
    "single_rod_pid": (ROOT / "tests" / "data" / "servo_circuit" / "single_rod_pid.toml", 1.0),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(SERVOS))
def test_servo_metrics_as_observers_over_its_circuit(name):
    """A component servo's on-the-fly metrics (its own kernel, metrics/servo.py) against the
    same metrics observed over the circuit it stands for (model/servo_observers.py). The two
    kernels are two codings of the same equations, equal to 1e-9 of a trace's range
    (tests/test_servo_circuit.py): the values are held to that, each against its
    quantity's scale in this run, the energies to 1e-9 of the supplied energy (the energy
    account's round-off, tests/test_servo_system_kernel.py); a settling time to one step (the
    measurement crosses the band's edge at the same step unless it is within that round-off
    of the edge there)."""
    path, duration = SERVOS[name]
    sc = load_scenario(path).replace(duration=duration)
    old = metrics_on_servo_kernel(sc)
    new = servo_circuit_metrics(sc)
    # what metrics() and a sweep's row give, bit for bit
    assert sc.metrics_vector().tobytes() == new.tobytes()
    i = METRIC_INDEX
    assert old[i["failed"]] == new[i["failed"]] == 0.0
    pressure = old[i["peak_pressure"]]
    t_step, step_from = sc.step_reference()
    size = abs(sc.reference.positions[-1] - step_from) if math.isfinite(t_step) else 0.0
    position = max(abs(old[i["final_position"]]), size)
    scales = {
        "final_position": position,
        "final_velocity": old[i["peak_speed"]],
        "peak_speed": old[i["peak_speed"]],
        "overshoot": 1.0,  # a fraction of the step
    }
    checked = []
    for name_, _ in METRICS:
        a, b = old[i[name_]], new[i[name_]]
        if name_ in ("failed", "failure_time"):
            continue  # the failure flags above
        if name_.endswith("energy") or name_ == "actuator_work":
            # the energy account to 1e-9 of the supplied energy, as the single run's
            # (tests/test_servo_system_kernel.py)
            supplied = abs(old[i["supply_energy"]])
            assert abs(a - b) <= 1e-9 * supplied, (name_, a, b, supplied)
            checked.append(name_)
            continue
        if name_ == "settling_time":
            if math.isnan(t_step):  # a ramp (linear_mechanical): no step to settle from
                assert math.isnan(a) and math.isnan(b)
                continue
            assert math.isfinite(a) and abs(a - b) <= sc.step * (1 + 1e-9), (name_, a, b)
            checked.append(name_)
            continue
        if name_ == "overshoot" and math.isnan(t_step):
            assert math.isnan(a) and math.isnan(b)
            continue
        if name_ == "final_spool":
            # the spool is no trace tests/test_servo_circuit.py holds to 1e-9: at its stop the
            # servo clamps it, the circuit's valve stops it by its projection, and they part
            # by 5.7e-7 of the spool's travel (2 spool_max) on linear_mechanical (measured)
            travel = 2 * sc.vector()[PARAMETER_INDEX["spool_max"]]
            assert abs(a - b) <= 1e-6 * travel, (name_, a, b, travel)
            checked.append(name_)
            continue
        scale = pressure if "pressure" in name_ else scales[name_]
        assert abs(a - b) <= 1e-9 * scale, (name_, a, b, scale)
        checked.append(name_)
    assert len(checked) == (18 if math.isfinite(t_step) else 16)


def test_signals_alone_are_evaluated_as_the_right_hand_side_evaluates_them(every_step):
    """Outputs that are states and signals only: the observer evaluates the signals alone
    (not every port's flow), and they are the recorded columns' bit for bit."""
    circuit, cc, table, S0 = every_step
    specs = [(o, st, 0.01, math.inf) for o in ("spool_demand_signal", "float_opening_signal",
             "cap_pressure_bar") for st in ("max", "min", "time_of_max", "final")]  # fmt: skip
    values, _ = observe_many(cc, table[:1], S0[:1], specs)
    cols = simulate(circuit).columns()
    ref = [trace_statistic(cols["t_s"], cols[o], st, after=a, before=b) for o, st, a, b in specs]
    assert list(values[0]) == ref
    assert values[0, 0] != values[0, 1]  # the demand moves in the window (from 0.3 s)


def test_a_mechanism_s_outputs_are_observed_as_recorded():
    """The mechanical outputs (a joint's torque from the components, a linkage's ratio) and
    a power of a mechanism (examples/boom.toml, 0.1 s): the observers' against the every-step
    trace's, bit for bit."""
    circuit = load_circuit(EXAMPLES / "boom.toml").replace(duration=0.1, record_every=1)
    cc = build(circuit)
    outputs = ("lift_torque_n_m", "lift_linkage_ratio", "lift_cylinder_power_w")
    specs = [(o, st, -math.inf, math.inf) for o in outputs for st in ("max", "min", "final")]
    S0 = row_initial_states(cc, [], np.zeros((1, 0)), cc.P[None, :])  # at rest, as simulate()
    values, bad = observe_many(cc, cc.P[None, :], S0, specs)
    cols = simulate(circuit).columns()
    assert bad[0] == -1
    assert list(values[0]) == [trace_statistic(cols["t_s"], cols[o], st) for o, st, *_ in specs]
    assert all(values[0, 3 * k] > values[0, 3 * k + 1] for k in range(3))  # each one moves


def assert_rows_are_their_traces(observed, compiled, table, S0, metrics):
    """``[failed, metric…]`` rows of a study (observed) against the statistics of the same
    rows' recorded traces (circuit_chunk_columns: traced_chunk's, today's path of the trace
    statistics), by `assert_observed`."""
    n = 0
    for r, cols in circuit_chunk_columns(compiled, table, S0):
        assert cols is not None and observed[r, 0] == 0.0
        for j, m in enumerate(metrics):
            if not m.online:  # read from its probe: the recorded column, bit for bit
                assert observed[r, 1 + j] == m.of(cols), m.name
                continue
            assert_observed(observed[r, 1 + j], cols["t_s"], cols[m.output], m.statistic,
                            m.after, m.before)  # fmt: skip
        n += 1
    assert n == len(table)


def _no_records(*args, **kwargs):
    raise AssertionError("a study whose statistics are all online recorded traces")


# the statistics that only the sums give, beside the examples' extremes and overshoots
SUMMED = {
    "mean_a": {"output": "A_pressure_bar", "statistic": "mean", "after": "1 s"},
    "rms_speed": {"output": "load_velocity_m_s", "statistic": "rms"},
    "travel": {"output": "load_velocity_m_s", "statistic": "integral", "after": "0.5 s"},
    "when": {"output": "A_pressure_bar", "statistic": "time_of_max"},
}


def test_a_design_of_a_circuit_observes_its_rows_at_the_records(monkeypatch):
    """examples/design_circuit_servo_cases.toml and sums: every candidate in every load
    case on the observers at the samples simulate records, its settling time (a trace's
    statistic) read from a probe of its output, no states recorded; each row's metrics
    those of its recorded traces (today's path), the sums to their rounding."""
    doc = parse_toml((EXAMPLES / "design_circuit_servo_cases.toml").read_text(), "study")
    doc["system"]["duration"] = "1.3 s"  # 0.3 s after the step: enough to compare
    doc["metrics"] |= SUMMED
    study = S.read_system_design(doc, "study", EXAMPLES)
    metrics = study.metrics
    assert [m.online for m in metrics] == [False, *[True] * 6]
    x = np.array([[v.low for v in study.variables], [v.high for v in study.variables]])
    with monkeypatch.context() as m:
        m.setattr("hydroarm.batch.circuit_sweep.simulate_many", _no_records)
        per_case = study.case_metrics(x)
    for case in study.run_cases:
        runner = study.runner.for_case(case)
        keys = [*study.keys, *case.keys]
        rows = np.array([[*xi, *case.row] for xi in x])
        cc = runner.compiled
        table = np.repeat(cc.P[None, :], len(rows), axis=0)
        for i, k in enumerate(keys):
            table[:, cc.parameter_index[k]] = rows[:, i]
        S0 = row_initial_states(cc, keys, rows, table)
        observed = run_circuit_chunk(runner.system, table, S0, metrics)
        assert_rows_are_their_traces(observed, cc, table, S0, metrics)
        for i in range(len(x)):  # the design's values are these rows'
            got = per_case[i][case.name]
            assert [got[m.name] for m in metrics] == list(observed[i, 1:])


def test_a_sensitivity_study_of_a_circuit_observes_its_rows_at_the_records(monkeypatch):
    """examples/circuit_servo_sensitivity.toml and sums: its samples on the observers at
    the records (the settling time, with its band, from a probe), their metrics those of
    the traces."""
    doc = parse_toml((EXAMPLES / "circuit_servo_sensitivity.toml").read_text(), "sens")
    doc["system"]["duration"] = "1.3 s"
    doc["metrics"] |= SUMMED
    st = circuit_study_from_doc(doc, "sens", EXAMPLES)
    assert [m.online for m in st.metrics] == [False, *[True] * 6]
    cc = st.compiled
    base = np.array([cc.P[cc.parameter_index[k]] for k in st.plan.names])
    X = np.array([base, base * 1.1, base * 0.9])
    model = CircuitModel(st, progress=lambda label: None)
    with monkeypatch.context() as m:
        m.setattr("hydroarm.batch.circuit_sweep.simulate_many", _no_records)
        out = model(X)
    T = model.table(X)
    S0 = row_initial_states(cc, st.plan.names, X, T)
    observed = np.column_stack([np.zeros(len(X)), *(out[m.column] for m in st.metrics)])
    assert_rows_are_their_traces(observed, cc, T, S0, st.metrics)


def test_observed_rows_over_the_budget_are_one_line(tmp_path, monkeypatch, capsys):
    """A sensitivity study's runs × metrics against the budget, before any run."""
    text = (EXAMPLES / "circuit_servo_sensitivity.toml").read_text()
    text = text.replace(
        '"circuit_position_servo.toml"', f'"{EXAMPLES.as_posix()}/circuit_position_servo.toml"'
    )
    (tmp_path / "s.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("hydroarm.batch.circuit_sweep.MAX_OBSERVED", 200)
    assert main(["sensitivity", "--config", "s.toml", "--out", "o"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "hydroarm: error: metrics: 80 rows × 3 metrics are above the budget of 200 values "
        "(the results a study holds)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
