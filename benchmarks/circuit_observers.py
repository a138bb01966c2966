"""Throughput and memory of a circuit study's metrics: observers against recorded traces.

Workload: the counterbalance study (examples/counterbalance_study.toml: the counterbalance
circuit, RK4 at 10 µs, its five metrics), ``--rows`` rows with the payload's mass varied
from 400 to 1000 kg, ``--duration`` seconds each. Four ways to the same metrics, each a
whole chunk of a study (the run and the statistics), all rows in parallel on numba's
threads:

* ``observers``: the observer loop (:func:`hydroarm.model.circuit.observe_many`), every step
  observed, a row holding its metrics' accumulators;
* ``traces, every step``: the batch engine (``run_many``) recording every step, statistics
  read from the traces afterwards: the same numbers (tests/test_circuit_observers.py);
* ``traces, every 200th``: recording every 200th step (what a study read before observers):
  cheaper, and its statistics see only the records;
* ``observers, every 200th``: the observer loop sampling what ``traces, every 200th``
  records (a design's and a sensitivity study's rows, `run_circuit_chunk` at the circuit's
  ``record_every``): the same numbers as those traces, the sums to their rounding.

Each is timed ``--repeat`` times after a warm-up; the ratios against the observers are
measured in the same run (the machines are shared: compare the ratios, not the rates), with
the load average and the time of day, and the CPU time a scenario-step summed over the
threads (``time.process_time``, which moves less than the wall clock on a shared machine).
The memory a row holds: the observers' accumulators
(:data:`~hydroarm.integrators.observers.BYTES_PER_METRIC` a metric, and the outputs' values
and work arrays, whatever the steps), the traces' recorded states (records × states) and the
outputs computed from them one row at a time (records × the kernel's output quantities).

Run: python benchmarks/circuit_observers.py [--rows 16] [--duration 0.5] [--repeat 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.batch.circuit_sweep import (  # noqa: E402
    run_circuit_chunk,
    run_study_chunk,
    traced_chunk,
)
from hydroarm.batch.sweep import load_sweep  # noqa: E402
from hydroarm.core.circuit.declare import MAX_PORTS  # noqa: E402
from hydroarm.integrators.observers import BYTES_PER_METRIC  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=16)
    ap.add_argument("--duration", type=float, default=0.5)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    sw = load_sweep(ROOT / "examples" / "counterbalance_study.toml")
    cc = sw.compiled
    base = dataclasses.replace(sw.circuit, duration=a.duration)
    masses = np.linspace(400.0, 1000.0, a.rows)
    table = np.repeat(cc.P[None, :], a.rows, axis=0)
    table[:, cc.parameter_index["payload.mass"]] = masses
    S0 = cc.initial_states(table)
    nsteps = int(round(a.duration / base.step))
    every = dataclasses.replace(base, record_every=1)
    sparse = dataclasses.replace(base, record_every=200)
    ways = {
        "observers": lambda: run_study_chunk(base, table, S0, sw.metrics),
        "traces, every step": lambda: traced_chunk(every, table, S0, sw.metrics),
        "traces, every 200th": lambda: traced_chunk(sparse, table, S0, sw.metrics),
        "observers, every 200th": lambda: run_circuit_chunk(sparse, table, S0, sw.metrics),
    }
    out = {k: f() for k, f in ways.items()}  # warm-up (and compile)
    same = np.array_equal(out["observers"], out["traces, every step"])
    sparse_same = np.array_equal(out["observers, every 200th"], out["traces, every 200th"])
    work = a.rows * nsteps
    print(
        f"{time.strftime('%Y-%m-%d %H:%M %Z')}: {a.rows} rows x {nsteps} steps (rk4, 10 us) = "
        f"{work:.3g} scenario-steps, {len(sw.metrics)} metrics; numba threads: "
        f"{numba.get_num_threads()}; load average {os.getloadavg()[0]:.2f}; observers equal "
        f"to every-step traces: {'bit for bit' if same else 'to the sums rounding'}, every "
        f"200th to those traces: {'bit for bit' if sparse_same else 'to the sums rounding'}"
    )
    n = cc.s0.size
    nc = len(cc.circuit.components)
    quantities = nc * MAX_PORTS + nc + max(len(cc.signals), 1) + len(cc.mechanical) + 1
    outputs = len({m.output for m in sw.metrics})
    for name, c in (("traces, every step", every), ("traces, every 200th", sparse)):
        rec = nsteps // c.record_every + 1
        print(
            f"  memory a row, {name}: {rec * n * 8 / 1e6:.3g} MB of states "
            f"({rec} records x {n} states), {rec * quantities * 8 / 1e6:.3g} MB of output "
            "quantities while its statistics are read"
        )
    print(
        f"  memory a row, observers: {len(sw.metrics) * BYTES_PER_METRIC + outputs * 8} B of "
        f"accumulators and outputs ({len(sw.metrics)} metrics x {BYTES_PER_METRIC} B), and the "
        "state and work arrays of one run: none grows with the steps"
    )
    for r in range(a.repeat):
        rate, cpu = {}, {}
        for k, f in ways.items():
            t0, c0 = time.perf_counter(), time.process_time()
            f()
            rate[k] = work / (time.perf_counter() - t0)
            cpu[k] = (time.process_time() - c0) / work * 1e9
        obs = rate["observers"]
        line = ", ".join(
            f"{k} {v:.3g} scenario-steps/s" + ("" if k == "observers" else f" ({obs / v:.2f}x)")
            for k, v in rate.items()
        )
        print(f"run {r + 1}: {line}; load average {os.getloadavg()[0]:.2f}")
        line = ", ".join(f"{k} {v:.0f} ns" for k, v in cpu.items())
        print(f"  CPU time a scenario-step (all threads): {line}")
    print("(x: the observers' rate over that way's, in the same run)")


if __name__ == "__main__":
    main()
