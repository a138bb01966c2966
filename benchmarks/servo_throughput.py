"""Throughput of a component servo sweep's chunk (on-the-fly metrics): the system kernel's
observers (what a sweep runs) against the servo kernel's batch (the reference held apart in
`hydroarm.reference`, the path sweeps ran before issue 28).

Workload: the rows of examples/servo_tolerance.toml (the position servo of
examples/position_servo.toml, rk4 at 10 us, Monte Carlo on overlap, bulk modulus and mass),
cut to ``--rows`` rows and ``--duration`` seconds. The sweep's chunk
(`hydroarm.batch.servo_sweep.run_servo_chunk`: the rows' circuits on
`hydroarm.integrators.observers.observe_many`, parallel over rows) against
`hydroarm.reference.servo_metrics.run_many_metrics` (the servo kernel's `row_metrics`, parallel over
rows) on the same rows, each timed ``--repeat`` times after a warm-up (compiled code loaded),
with the load average before each and the CPU time a scenario-step summed over the threads
(``time.process_time``: on a machine shared with other work it moves less than the
wall-clock rate); the two agree to the kernels' round-off (the largest
energy difference over the supplied energy is printed).

Run: python benchmarks/servo_throughput.py [--rows 64] [--duration 0.2] [--repeat 2]
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.batch.servo_sweep import run_servo_chunk  # noqa: E402
from hydroarm.batch.sweep import parse_sweep  # noqa: E402
from hydroarm.integrators import registry  # noqa: E402
from hydroarm.io.sections import parse_toml  # noqa: E402
from hydroarm.metrics.servo import METRIC_INDEX  # noqa: E402
from hydroarm.reference.servo_metrics import run_many_metrics  # noqa: E402


def _load() -> str:
    try:
        return Path("/proc/loadavg").read_text().split(" ")[0]
    except OSError:
        return "?"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=64)
    ap.add_argument("--duration", type=float, default=0.2)
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args()
    text = (ROOT / "examples" / "servo_tolerance.toml").read_text()
    text = re.sub(r"(?m)^n = \d+", f"n = {a.rows}", text)
    text = re.sub(r'(?m)^duration = "[^"]+"', f'duration = "{a.duration} s"', text)
    sw = parse_sweep(parse_toml(text, "servo_tolerance"), ROOT / "examples")
    b = sw.base
    ref = b.reference
    t_step, step_from = b.step_reference()
    code = registry.method(b.method).code
    work = sw.size * b.nsteps

    def servo_kernel(n=b.nsteps):
        return run_many_metrics(
            code, sw.initial, 0.0, b.step, n, ref.times, ref.positions, ref.sine, sw.table,
            t_step, step_from, sw.band,
        )  # fmt: skip

    def observers():
        return run_servo_chunk(sw, 0, sw.size)

    servo_kernel(10)  # warm: compiled code loaded
    run_servo_chunk(sw, 0, 1)
    print(
        f"{sw.size} rows x {b.nsteps} steps ({b.method}, {b.step * 1e6:g} us) = {work:.3g} "
        f"scenario-steps; numba threads: {numba.get_num_threads()}"
    )
    for r in range(a.repeat):
        load_o = _load()
        t0, c0 = time.perf_counter(), time.process_time()
        Mo = observers()
        to, co = time.perf_counter() - t0, time.process_time() - c0
        load_s = _load()
        t0, c0 = time.perf_counter(), time.process_time()
        Ms = servo_kernel()
        ts, cs = time.perf_counter() - t0, time.process_time() - c0
        e = slice(METRIC_INDEX["supply_energy"], METRIC_INDEX["actuator_work"] + 1)
        supplied = np.abs(Ms[:, METRIC_INDEX["supply_energy"]])[:, None]
        diff = float(np.nanmax(np.abs(Mo[:, e] - Ms[:, e]) / supplied))
        print(
            f"run {r + 1}: observers (system kernel) {work / to:.3g} scenario-steps/s "
            f"({to:.2f} s, load {load_o}), servo kernel {work / ts:.3g} scenario-steps/s "
            f"({ts:.2f} s, load {load_s}), {to / ts:.2f}x the time; largest energy difference "
            f"{diff:.2g} of the supplied"
        )
        print(
            f"  CPU time a scenario-step (all threads): observers {co / work * 1e9:.0f} ns "
            f"({work / co:.3g} scenario-steps per CPU-second), servo kernel "
            f"{cs / work * 1e9:.0f} ns ({work / cs:.3g}), {co / cs:.2f}x the CPU time"
        )


if __name__ == "__main__":
    main()
