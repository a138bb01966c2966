"""The circuit's adaptive method (`hydroarm.integrators.adaptive.integrate_circuit_adaptive`,
Radau on the system kernel) on examples/position_servo.toml: its time against the servo
kernel's Radau (`hydroarm.reference.run_on_servo_kernel`, the reference of the
ratio) in the same run, with 50, 500 and 5000 records over ``--duration``, and its error
against rk4 at 1 µs on the same circuit where chamber A leaves the cavitation floor (0.1 s;
the servo kernel's Radau ignores the floor, so it is timed only). Then
examples/water_hammer.toml (a line: 512 states of wave history) over ``--duration``: the
adaptive method against rk4 at the file's 10 µs step (the reference of the ratio) and
against the same Radau with the line's history among the solver's states (``held=()``, the
method before the history was held out of them; ``--skip-old`` leaves it out: 20–35 s), each
with its error against rk4 at 1 µs over 0.1 s. Each time is the best of ``--repeat`` after a
warm-up (the old method: one run), with the load average before it.

Run: python benchmarks/circuit_adaptive.py [--duration 0.05] [--repeat 3] [--skip-old]
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

from hydroarm.integrators.adaptive import integrate_circuit_adaptive  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.io.schema import load_scenario  # noqa: E402
from hydroarm.model.circuit import ADAPTIVE_MAX_STEPS, build, simulate, state_atol  # noqa: E402
from hydroarm.reference import run_on_servo_kernel  # noqa: E402


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
    ap.add_argument("--skip-old", action="store_true")
    a = ap.parse_args()
    water_hammer(a)
    base = load_scenario(ROOT / "examples" / "position_servo.toml").replace(duration=a.duration)
    print(f"position_servo, {a.duration * 1e3:g} ms, adaptive (Radau, rtol 1e-8 / 1e-9)")
    for records in (50, 500, 5000):
        every = round(a.duration / base.step / records)
        sc = dataclasses.replace(base, method="adaptive", record_every=every)
        load = _load()
        new = _best(sc.run_on_system_kernel, a.repeat)
        old = _best(lambda sc=sc: run_on_servo_kernel(sc), a.repeat)
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


def water_hammer(a) -> None:
    """The line's circuit: the adaptive method, rk4 at the file's step, and the adaptive
    method with the history among Radau's states (``held=()``); errors over 0.1 s."""
    base = load_circuit(ROOT / "examples" / "water_hammer.toml")

    def adaptive(c, held: bool):
        cc = build(c)
        t = np.arange(round(c.duration / c.step) // c.record_every + 1) * (c.record_every * c.step)
        atol = state_atol([unit for _, unit in cc.state_names], cc.s0)
        return integrate_circuit_adaptive(
            cc.s0,
            t,
            cc.P,
            cc.net,
            atol=atol,
            max_step=ADAPTIVE_MAX_STEPS * c.step,
            held=cc.held if held else (),
            held_step=c.step,
        )

    run = dataclasses.replace(base, duration=a.duration)
    print(f"water_hammer, {a.duration * 1e3:g} ms (records every 0.1 ms)")
    load = _load()
    rk4 = _best(lambda: simulate(run), a.repeat)
    new = _best(lambda: adaptive(run, True), a.repeat)
    print(f"  rk4 at 10 us {rk4:.3f} s, adaptive {new:.3f} s, ratio {new / rk4:.1f} (load {load})")
    if not a.skip_old:
        load = _load()
        t0 = time.perf_counter()
        adaptive(run, False)
        old = time.perf_counter() - t0
        print(f"  adaptive, history among Radau's states: {old:.2f} s (load {load})")
    floor = dataclasses.replace(base, duration=0.1)
    cc = build(floor)
    iv = [name for name, _ in cc.state_names].index("valve_in.pressure")
    fine = simulate(dataclasses.replace(floor, step=1e-6, record_every=100)).states[:, iv]
    span = np.ptp(fine)
    got = {"rk4 at 10 us": simulate(cc).states[:, iv], "adaptive": adaptive(floor, True)[:, iv]}
    if not a.skip_old:
        got["adaptive, history among Radau's states"] = adaptive(floor, False)[:, iv]
    for name, p in got.items():
        print(
            f"  0.1 s, valve pressure error / range against rk4 at 1 us, {name}: "
            f"{np.max(np.abs(p - fine)) / span:.1e}"
        )


if __name__ == "__main__":
    main()
