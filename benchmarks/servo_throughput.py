"""Throughput of the component servo batch (on-the-fly metrics) against a single-row loop.

Workload: the rows of examples/servo_tolerance.toml (the position servo of
examples/position_servo.toml, rk4 at 10 us, Monte Carlo on overlap, bulk modulus and mass),
cut to ``--rows`` rows and ``--duration`` seconds. Both paths call the same compiled
:func:`hydroarm.metrics.servo.row_metrics`: the batch through ``run_many_metrics``
(parallel over rows, all numba threads), the loop one row at a time from Python. Each is
timed ``--repeat`` times after a warm-up (compiled code loaded), and the results are checked
equal bit for bit.

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

from hydroarm.batch.sweep import parse_sweep  # noqa: E402
from hydroarm.io.sections import parse_toml  # noqa: E402
from hydroarm.metrics.servo import N_METRICS, row_metrics  # noqa: E402


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
    fn, args = sw.jobs()(slice(0, sw.size))
    (method, S0, h, nsteps, tab_t, tab_y, sine, table, t_step, step_from, band) = args
    work = sw.size * nsteps

    def batch():
        return fn(*args)

    def loop():
        M = np.empty((sw.size, N_METRICS))
        for i in range(sw.size):
            row_metrics(
                method, S0[i], 0.0, h, nsteps, tab_t, tab_y, sine, table[i],
                t_step, step_from, band, M[i],
            )  # fmt: skip
        return M

    fn(method, S0[:1], h, 10, tab_t, tab_y, sine, table[:1], t_step, step_from, band)  # warm
    loop_small = np.empty(N_METRICS)
    row_metrics(method, S0[0], 0.0, h, 10, tab_t, tab_y, sine, table[0], t_step, step_from, band,
                loop_small)  # fmt: skip
    print(
        f"{sw.size} rows x {nsteps} steps ({sw.base.method}, {h * 1e6:g} us) = {work:.3g} "
        f"scenario-steps; numba threads: {numba.get_num_threads()}"
    )
    for r in range(a.repeat):
        t0 = time.perf_counter()
        Mb = batch()
        tb = time.perf_counter() - t0
        t0 = time.perf_counter()
        Ml = loop()
        tl = time.perf_counter() - t0
        same = Mb.tobytes() == Ml.tobytes()
        print(
            f"run {r + 1}: batch {work / tb:.3g} scenario-steps/s ({tb:.2f} s), single-row loop "
            f"{work / tl:.3g} scenario-steps/s ({tl:.2f} s), batch/loop {tl / tb:.2f}x, "
            f"equal bit for bit: {same}"
        )


if __name__ == "__main__":
    main()
