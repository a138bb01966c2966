"""The circuit's adaptive method (`hydroarm.integrators.adaptive.integrate_circuit_adaptive`,
Radau on the system kernel) on examples/position_servo.toml: its time against the servo
kernel's Radau (`hydroarm.integrators.adaptive.integrate_servo_adaptive`, the reference of the
ratio) in the same run, with 50, 500 and 5000 records over ``--duration``, and its error
against rk4 at 1 µs on the same circuit where chamber A leaves the cavitation floor (0.1 s;
the servo kernel's Radau ignores the floor, so it is timed only). Each time is the best of
``--repeat`` after a warm-up, with the load average before it.

Run: python benchmarks/circuit_adaptive.py [--duration 0.05] [--repeat 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.io.schema import load_scenario  # noqa: E402


def _load() -> str:
    try:
        return Path("/proc/loadavg").read_text().split(" ")[0]
    except OSError:
        return "?"


def _best(run, repeat: int) -> float:
    run()  # warm-up: compiled code loaded
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=0.05)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    base = load_scenario(ROOT / "examples" / "position_servo.toml").replace(duration=a.duration)
    print(f"position_servo, {a.duration * 1e3:g} ms, adaptive (Radau, rtol 1e-8 / 1e-9)")
    for records in (50, 500, 5000):
        every = round(a.duration / base.step / records)
        sc = dataclasses.replace(base, method="adaptive", record_every=every)
        load = _load()
        new = _best(sc.run_on_system_kernel, a.repeat)
        old = _best(sc.run_on_servo_kernel, a.repeat)
        print(
            f"  {records:5d} records: system kernel {new:.3f} s, servo kernel {old:.3f} s, "
            f"ratio {new / old:.2f} (load {load})"
        )
    floor = base.replace(duration=0.1)
    fine = dataclasses.replace(floor, method="rk4", step=1e-6, record_every=100).run().columns()
    for every in (100, 10):
        got = dataclasses.replace(floor, method="adaptive", record_every=every).run().columns()
        errs = []
        for column in ("pressure_a_bar", "pressure_b_bar", "position_m", "spool_m"):
            ref = fine[column][:: every // 10]
            errs.append(f"{column} {np.max(np.abs(got[column] - ref)) / np.ptp(fine[column]):.1e}")
        print(f"  records every {every * base.step * 1e3:g} ms, error / range: " + ", ".join(errs))


if __name__ == "__main__":
    main()
