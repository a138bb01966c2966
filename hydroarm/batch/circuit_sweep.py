"""Sweeps and tolerance studies of any circuit (docs/batch.md "Studies of a circuit"):
``hydroarm sweep --config study.toml --out results.csv`` where ``[system] file`` names a
circuit file.

.. code-block:: toml

    [system]
    file = "counterbalance.toml"          # the circuit, relative to this file
    duration = "3 s"                      # fields beside it override the file's: the
    "load.mass" = "300 kg"                # solver's and any parameter by its name
    [grid]                                # parameters by <component>.<parameter>, with units
    "cbv.pilot_ratio" = [2, 3, 4]
    [monte_carlo]
    n = 100
    seed = 1
    "load.mass" = { distribution = "normal", relative_sd = 0.1 }
    [metrics]                             # any statistic of any named output
    peak_pressure = { output = "A_pressure_bar", statistic = "max" }
    lowest_speed = { output = "load_velocity_m_s", statistic = "min", after = "1 s" }

The names a study may vary are the circuit's sweepable parameters
(`sweepable`), read with the units their
components declare and checked against their rules, every row; the outputs are the run's
named columns (`columns`) and the statistics
those of `hydroarm.metrics.trace`. Every row runs the same kernel and stepper as
`simulate`, on the observer loop
(`probe_many`): when every statistic can be computed as the
run steps, each seeing every step (those of the same circuit run alone and recorded at
every step: equal bit for bit, the trapezoid sums to their rounding), else at the samples
`simulate` records, a settling or rise time read from a probe of its output there (those of
the same circuit run alone, bit for bit); tests hold both. Rows × metrics are at most
`MAX_OBSERVED`, checked before any run. The rows' reading and
draws, the chunks, ``--resume``, Dask and the output file are the joint's sweeps'
(`hydroarm.batch.rows`, `hydroarm.batch.sweep.run_sweep`).
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from ..errors import HydroarmError
from ..integrators.observers import ONLINE_STATISTICS
from ..io.circuit import parameter_of, parameter_value, value_in
from ..io.sections import as_table, optional_table, reject_unknown_keys, time_value
from ..io.system import study_circuit
from ..metrics.trace import (
    DEFAULT_BAND,
    DEFAULT_RISE,
    STATISTICS,
    statistic_unit,
    trace_statistic,
)
from ..model.circuit import (
    MAX_OBSERVED,
    Circuit,
    CircuitResult,
    CompiledCircuit,
    build,
    column_unit,
    probe_many,
    row_initial_states,
    simulate_many,
)
from .rows import varied_rows

MAX_BLOCK_BYTES = 64 * 2**20  # recorded states held at once while a chunk runs
METRIC_KEYS = {"output", "statistic", "after", "before", "band", "rise"}
MAX_METRICS = 100


@dataclass(frozen=True)
class TraceMetric:
    """One metric of a study: a ``statistic`` of the named ``output`` over the window
    ``[after, before]`` [s], with its thresholds; ``column``: its results column (the
    metric's name and its unit)."""

    name: str
    output: str
    statistic: str
    after: float = -math.inf
    before: float = math.inf
    band: float = DEFAULT_BAND
    rise: tuple[float, float] = DEFAULT_RISE
    column: str = ""

    @property
    def online(self) -> bool:
        """Whether an observer measures it while the run steps
        (`ONLINE_STATISTICS`)."""
        return self.statistic in ONLINE_STATISTICS

    def of(self, result_columns: dict[str, np.ndarray]) -> float:
        """The metric of one run's columns (`CircuitResult.columns`)."""
        return trace_statistic(
            result_columns["t_s"],
            result_columns[self.output],
            self.statistic,
            after=self.after,
            before=self.before,
            band=self.band,
            rise=self.rise,
        )


def read_metrics(field: str, table, outputs: dict[str, str]) -> tuple[TraceMetric, ...]:
    """The ``[metrics]`` of a study of a circuit; ``outputs``: the circuit's output names
    and their units (`CircuitResult.units`)."""
    table = as_table(field, table)
    if not table:
        raise HydroarmError(field, "names no metric (e.g. peak = {output = ..., statistic = ...})")
    if len(table) > MAX_METRICS:
        raise HydroarmError(field, f"more than {MAX_METRICS} metrics")
    out = []
    for name, spec in table.items():
        f = f"{field}.{name}"
        if not name.isidentifier():
            raise HydroarmError(f, "a metric's name is letters, digits and _")
        spec = as_table(f, spec)
        reject_unknown_keys(f, spec, METRIC_KEYS)
        for key in ("output", "statistic"):
            if key not in spec:
                raise HydroarmError(f"{f}.{key}", "is missing")
        output = spec["output"]
        if output not in outputs:
            close = [k for k in outputs if isinstance(output, str) and output in k][:3]
            raise HydroarmError(
                f"{f}.output",
                f"{output!r}: no such output"
                + (f" (did you mean {', '.join(close)}?)" if close else "")
                + " (the outputs are the columns of `hydroarm simulate --out`)",
            )
        stat = spec["statistic"]
        if stat not in STATISTICS:
            raise HydroarmError(f"{f}.statistic", f"{stat!r}: one of {', '.join(STATISTICS)}")
        after = time_value(f"{f}.after", spec["after"]) if "after" in spec else -math.inf
        before = time_value(f"{f}.before", spec["before"]) if "before" in spec else math.inf
        if not before > after:
            raise HydroarmError(f"{f}.before", "must be after 'after'")
        band = DEFAULT_BAND
        if "band" in spec:
            band = spec["band"]
            if isinstance(band, bool) or not isinstance(band, int | float) or not 0 < band < 1:
                raise HydroarmError(f"{f}.band", f"must be a number in (0, 1), got {band!r}")
        rise = DEFAULT_RISE
        if "rise" in spec:
            r = spec["rise"]
            ok = isinstance(r, list) and len(r) == 2
            ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) for x in r)
            if not (ok and 0 <= r[0] < r[1] <= 1):
                raise HydroarmError(f"{f}.rise", f"must be [low, high] in [0, 1], got {r!r}")
            rise = (float(r[0]), float(r[1]))
        if stat not in ("settling_time",) and "band" in spec:
            raise HydroarmError(f"{f}.band", "is for statistic = 'settling_time'")
        if stat != "rise_time" and "rise" in spec:
            raise HydroarmError(f"{f}.rise", "is for statistic = 'rise_time'")
        unit = statistic_unit(stat, outputs[output])
        column = f"{name}_{unit}" if unit and not name.endswith(f"_{unit}") else name
        out.append(TraceMetric(name, output, stat, after, before, band, rise, column))
    columns = [m.column for m in out]
    for c in columns:
        if columns.count(c) > 1:
            raise HydroarmError(field, f"two metrics make the column {c!r}")
    return tuple(out)


def output_units(compiled: CompiledCircuit) -> dict[str, str]:
    """The circuit's output names and their units, from its initial state (no run)."""
    res = CircuitResult(compiled, np.zeros(1), compiled.s0[None, :], -1, compiled.P)
    return res.units()


@dataclass
class _Run:
    """What the sweep machinery reads of a sweep's base run."""

    method: str
    step: float
    nsteps: int


@dataclass
class CircuitSweep:
    """A parsed sweep of a circuit: the circuit, one parameter vector per row, the rows'
    initial states and the metrics."""

    circuit: Circuit
    compiled: CompiledCircuit
    names: list  # varied parameters <component>.<parameter>
    values: np.ndarray  # (n, len(names)) SI values
    table: np.ndarray  # (n, len(P)) the kernel's parameter vectors
    initial: np.ndarray  # (n, states) initial states
    metrics: tuple[TraceMetric, ...]
    digest: str

    @property
    def size(self) -> int:
        return self.table.shape[0]

    @property
    def base(self) -> _Run:
        c = self.circuit
        return _Run(c.method, c.step, int(round(c.duration / c.step)))

    def row_circuit(self, row: int) -> Circuit:
        """Row ``row`` as a circuit of its own (for re-runs and checks)."""
        return self.circuit.with_values(
            {k: float(self.values[row, i]) for i, k in enumerate(self.names)}
        )

    def jobs(self):
        """``job(rows)`` -> (function, arguments): the metrics of a slice of rows."""

        def job(s: slice):
            return run_study_chunk, (self.circuit, self.table[s], self.initial[s], self.metrics)

        return job

    def columns(self, metrics: np.ndarray) -> dict:
        """scenario, the varied parameters (display units in their names), ``failed``, then
        the metrics (their units in their names)."""
        cols: dict = {"scenario": np.arange(self.size)}
        for i, k in enumerate(self.names):
            unit = parameter_of(k, self.circuit, k).unit
            suffix, f = column_unit(unit)
            cols[f"{k}_{suffix}" if suffix else k] = self.values[:, i] * f
        cols["failed"] = metrics[:, 0] > 0.5
        for j, m in enumerate(self.metrics):
            cols[m.column] = metrics[:, 1 + j]
        return cols


def run_circuit_chunk(
    circuit: Circuit, table, S0, metrics, threads=None, every: int | None = None
) -> np.ndarray:
    """Rows of a chunk: ``[failed, metric…]`` per row; ``threads`` limits numba's threads (1
    inside a Dask worker). The one path of every study's rows on a circuit: a sweep's
    (`run_study_chunk`), a design's and a load case's
    (`hydroarm.analysis.systems.SystemRunner.run`), a sensitivity study's
    (`hydroarm.analysis.sensitivity.CircuitModel`).

    The rows run on the observer loop (`probe_many`), each statistic seeing the start and
    every ``every``-th step: None, the circuit's ``record_every``, the samples ``hydroarm
    simulate`` records (a design's and a sensitivity study's rows: their statistics those
    of the traces, bit for bit, the trapezoid sums to their rounding); 1, every step (a
    sweep's). An `online` statistic is measured as the run steps (a row holds its
    accumulators); a statistic of a trace only (``settling_time``, ``rise_time``:
    `TRACE_ONLY`) is read from its output's probe, the output kept at the samples
    ``simulate`` records (whatever ``every``: then every statistic is), in blocks of rows
    whose probes fit `MAX_BLOCK_BYTES`: a row holds the outputs those statistics read, not
    its states."""
    if threads is not None:
        most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
        numba.set_num_threads(max(1, min(threads, most)))
    compiled = build(circuit)
    online = [j for j, m in enumerate(metrics) if m.online]
    traced = [j for j, m in enumerate(metrics) if not m.online]
    if traced or every is None:  # a trace's statistics: the records simulate keeps
        every = circuit.record_every
    probes = tuple(dict.fromkeys(metrics[j].output for j in traced))
    specs = [(m.output, m.statistic, m.after, m.before) for m in (metrics[j] for j in online)]
    n = table.shape[0]
    samples = int(round(circuit.duration / circuit.step)) // every + 1
    block = max(1, min(n, MAX_BLOCK_BYTES // max(1, samples * len(probes) * 8)))
    out = np.full((n, 1 + len(metrics)), math.nan)
    for lo in range(0, n, block):
        hi = min(n, lo + block)
        values, bad, t, traces = probe_many(compiled, table[lo:hi], S0[lo:hi], specs, every, probes)
        out[lo:hi, 0] = bad >= 0
        out[lo:hi, [1 + j for j in online]] = values
        for r in np.flatnonzero(bad < 0):
            cols = {"t_s": t} | {o: traces[r, :, k] for k, o in enumerate(probes)}
            for j in traced:
                out[lo + r, 1 + j] = metrics[j].of(cols)
    return out


def traced_chunk(circuit: Circuit, table, S0, metrics) -> np.ndarray:
    """`run_circuit_chunk`'s rows from recorded traces: ``[failed, metric…]`` per row, each
    metric the trace statistic of the row's records (`circuit_chunk_columns`), those of
    the same circuit run alone by `simulate`, bit for bit (the fallback of a trace-only
    statistic, and the observers' oracle in the tests)."""
    out = np.full((table.shape[0], 1 + len(metrics)), math.nan)
    for r, cols in circuit_chunk_columns(build(circuit), table, S0):
        out[r, 0] = float(cols is None)
        if cols is None:
            continue
        for j, m in enumerate(metrics):
            out[r, 1 + j] = m.of(cols)
    return out


def run_study_chunk(circuit: Circuit, table, S0, metrics, threads=None) -> np.ndarray:
    """A sweep's chunk: `run_circuit_chunk` observing every step where every metric is
    online (the job of `CircuitSweep.jobs`, on a Dask worker too)."""
    return run_circuit_chunk(circuit, table, S0, metrics, threads, every=1)


def circuit_chunk_columns(compiled: CompiledCircuit, table, S0):
    """``(row, columns)`` of every row of a parameter table run on the batch engine (the
    outputs ``hydroarm simulate --out`` writes; None: the run failed), in blocks whose
    recorded states fit `MAX_BLOCK_BYTES`: what a sweep's metrics and a fit's traces
    are read from."""
    circuit = compiled.circuit
    n = table.shape[0]
    records = int(round(circuit.duration / circuit.step)) // circuit.record_every + 1
    per_row = max(1, records * compiled.s0.size * 8)
    block = max(1, min(n, MAX_BLOCK_BYTES // per_row))
    for lo in range(0, n, block):
        hi = min(n, lo + block)
        t, S, bad = simulate_many(compiled, table[lo:hi], S0[lo:hi])
        for r in range(hi - lo):
            if bad[r] >= 0:
                yield lo + r, None
                continue
            yield lo + r, CircuitResult(compiled, t, S[r], -1, table[lo + r]).columns()


def check_observed(rows: int, metrics) -> None:
    """A study's rows × metrics against `MAX_OBSERVED` (the values it holds, its rows run
    observed or not), before any run: a sweep's, a sensitivity study's."""
    if rows * len(metrics) > MAX_OBSERVED:
        raise HydroarmError(
            "metrics",
            f"{rows} rows × {len(metrics)} metrics are above the budget of {MAX_OBSERVED} "
            "values (the results a study holds)",
        )


def is_circuit_study(doc: dict) -> bool:
    """Whether a study file runs a system file (``[system] file = …``)."""
    return isinstance(doc.get("system"), dict) and "file" in doc["system"]


def _check_rows(sw_names, values, circuit: Circuit, v) -> None:
    """Every row's value of every varied parameter against its declared rule (the first
    bad row named: ``monte_carlo.load.mass: row 17: must be > 0, got -3``)."""
    for i, k in enumerate(sw_names):
        p = parameter_of(v.field(k), circuit, k)
        col = values[:, i]
        bad = ~np.isfinite(col)
        if np.any(bad):
            row = int(np.argmax(bad))
            raise HydroarmError(v.field(k), f"row {row}: must be finite, got {col[row]}")
        for row in np.unique(col, return_index=True)[1]:  # each distinct value once
            problem = p.check(float(col[row]))
            if problem:
                raise HydroarmError(v.field(k), f"row {int(row)}: {problem}")


def parse_circuit_sweep(doc: dict, base_dir: Path, source: str) -> CircuitSweep:
    """A `CircuitSweep` from a parsed sweep file with ``[system] file`` (module doc)."""
    reject_unknown_keys("", doc, {"name", "description", "system", "grid", "monte_carlo",
                                  "metrics", "chunk"})  # fmt: skip
    circuit = study_circuit("system", doc["system"], base_dir)
    if circuit.method == "adaptive":
        raise HydroarmError("system.method", "a sweep runs the fixed-step methods")
    compiled = build(circuit)
    if "metrics" not in doc:
        raise HydroarmError("metrics", "is missing: name what each row measures (docs/batch.md)")
    metrics = read_metrics("metrics", doc["metrics"], output_units(compiled))
    known = compiled.sweepable

    def read(k):
        return lambda field, value: parameter_value(field, circuit, k, value)

    def dimension(k):
        unit = parameter_of(f"monte_carlo.{k}", circuit, k).unit
        return lambda field, value: value_in(field, value, unit)

    grid = optional_table(doc, "grid")
    mc = dict(optional_table(doc, "monte_carlo"))
    for sec, section in (("grid", grid), ("monte_carlo", mc)):
        for k in section:
            if k not in ("n", "seed") and k not in known:
                parameter_of(f"{sec}.{k}", circuit, k)  # an unknown name: its own error
                raise HydroarmError(f"{sec}.{k}", "is not a parameter a study may vary")
    v = varied_rows(
        grid,
        mc,
        known,
        "circuit parameter",
        read=read,
        dimension=dimension,
        base_value=lambda k: float(compiled.P[compiled.parameter_index[k]]),
    )
    _check_rows(v.names, v.values, circuit, v)
    n = v.values.shape[0]
    table = np.repeat(compiled.P[None, :], n, axis=0)
    for i, k in enumerate(v.names):
        table[:, compiled.parameter_index[k]] = v.values[:, i]
    check_observed(n, metrics)
    initial = row_initial_states(compiled, v.names, v.values, table)
    h = hashlib.sha256()
    h.update(json.dumps(doc, sort_keys=True, default=str).encode())
    h.update(table.tobytes())
    h.update(initial.tobytes())
    h.update(repr(circuit).encode())
    return CircuitSweep(
        circuit=circuit,
        compiled=compiled,
        names=v.names,
        values=v.values,
        table=table,
        initial=initial,
        metrics=metrics,
        digest=h.hexdigest()[:16],
    )


def circuit_summary(path, columns: list[str]) -> dict:
    """Quick statistics of a finished circuit sweep file (for the CLI): rows, failed rows,
    and each metric column's mean and spread over the rows where it is finite."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        n = len(rows)
        failed = sum(r["failed"] == "True" for r in rows)
        data = {
            k: np.array([float(r[k]) if r[k] and r["failed"] != "True" else math.nan for r in rows])
            for k in columns
        }
    else:
        import pandas as pd

        df = pd.read_parquet(path)
        bad = df["failed"].to_numpy(bool)
        failed = int(bad.sum())
        n = len(df)
        data = {k: np.where(bad, math.nan, df[k].to_numpy(float)) for k in columns}
    out: dict = {"scenarios": n, "failed": failed, "metrics": {}}
    for k, x in data.items():
        x = x[np.isfinite(x)]
        out["metrics"][k] = (
            len(x),
            float(np.mean(x)) if len(x) else math.nan,
            float(np.std(x, ddof=1)) if len(x) > 1 else math.nan,
        )
    return out
