"""Throughput of the circuit kernel's batch engine against the component servo's.

Workload: the position servo (examples/circuit_position_servo.toml as a circuit; the same
servo as examples/position_servo.toml on the component servo's own kernel), RK4 at 10 µs,
``--rows`` scenarios with the load mass varied ±10 %, ``--duration`` seconds each. Both
batches run in parallel over the rows on all numba threads; each is timed ``--repeat``
times after a warm-up, and the ratio circuit/servo is printed with the machine's load
average and the time of day (the machines are shared: compare the ratio, measured in one
run, rather than the rates). Each run also prints the CPU time a scenario-step, summed over
the threads (``time.process_time``): on a machine shared with other work it moves less than
the wall-clock rate.

Run: python benchmarks/circuit_throughput.py [--rows 32] [--duration 0.1] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.core.servo import P_MASS  # noqa: E402
from hydroarm.integrators import registry  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.io.schema import load_scenario_text  # noqa: E402
from hydroarm.model.circuit import build, simulate_many  # noqa: E402
from hydroarm.reference.servo_kernel import run_many as servo_run_many  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=32)
    ap.add_argument("--duration", type=float, default=0.1)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    masses = np.linspace(90.0, 110.0, a.rows)
    circuit = load_circuit(ROOT / "examples" / "circuit_position_servo.toml")
    circuit = circuit.replace(duration=a.duration, record_every=1000)
    compiled = build(circuit)
    table = np.stack([compiled.parameter_vector({"payload.mass": m}) for m in masses])
    nsteps = int(round(a.duration / circuit.step))

    text = (ROOT / "examples" / "position_servo.toml").read_text()
    text = re.sub(r'duration = "[^"]+"', f'duration = "{a.duration} s"', text)
    text = re.sub(r"record_every = \d+", "record_every = 1000", text)
    sc = load_scenario_text(text, "position_servo")
    stable = np.repeat(sc.vector()[None, :], a.rows, axis=0)
    stable[:, P_MASS] = masses
    S0 = np.repeat(sc.initial_state()[None, :], a.rows, axis=0)
    ref = sc.reference
    code = registry.method(sc.method).code

    def circuit_batch():
        return simulate_many(compiled, table)

    def servo():
        return servo_run_many(
            code, S0, 0.0, sc.step, nsteps, 1000, ref.times, ref.positions, ref.sine, stable
        )

    work = a.rows * nsteps
    circuit_batch()
    servo()
    print(
        f"{time.strftime('%Y-%m-%d %H:%M %Z')}: {a.rows} rows x {nsteps} steps (rk4, 10 us) = "
        f"{work:.3g} scenario-steps; numba threads: {numba.get_num_threads()}; load average "
        f"{os.getloadavg()[0]:.2f}"
    )
    for r in range(a.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        circuit_batch()
        tc, cc = time.perf_counter() - t0, time.process_time() - c0
        line = f"run {r + 1}: circuit kernel {work / tc:.3g} scenario-steps/s ({tc:.2f} s)"
        t0, c0 = time.perf_counter(), time.process_time()
        servo()
        ts, cs = time.perf_counter() - t0, time.process_time() - c0
        line += f", component servo {work / ts:.3g} scenario-steps/s, ratio {ts / tc:.2f}x"
        print(line + f"; load average {os.getloadavg()[0]:.2f}")
        print(
            f"  CPU time a scenario-step (all threads): circuit kernel {cc / work * 1e9:.0f} ns,"
            f" component servo {cs / work * 1e9:.0f} ns, ratio {cs / cc:.2f}x"
        )


if __name__ == "__main__":
    main()
