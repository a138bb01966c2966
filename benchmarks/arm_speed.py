"""Speed of the four-joint arm kernel against references measured in the same run (issue 21).

Workload: examples/ucl-arm.toml (block stacking, four joints, pump 0.6 l/min) at its default
scheme (coupled RK4, 1 ms step), the first ``--duration`` seconds (9 s: the whole run).

Prints, best of ``--repeat`` runs, each measurement taken twice (CPU time of this process):
  * the decoupled arm kernel (``hydroarm.reference.arm_decoupled.arm_integrate``) at the
    default scheme: µs per joint-step and its real-time factor (simulated time / CPU time);
  * the reference: the same kernel with the paper's Euler at 10 us (the scheme the example
    ran before, and the arm validation's), its real-time factor and the ratio;
  * the single-joint kernel (``hydroarm.integrators.fixed.integrate``) on the Euler steps of
    each joint with its load frozen at the start (the cost of the physics alone);
  * the accuracy of the default against the reference over the run: max |Δθ| of each
    joint's articulation angle (5 ms samples), its final angles and the lowest supply
    pressure (the pump's peak sag);
  * the pose load per step: the closed form (``pose_terms``, all joints at once) against the
    old finite differences (``pose_load_fd``, once per pose-loaded joint), and the ratio.

Run: python benchmarks/arm_speed.py [--quick]   (--quick: 1 s of the run, ~10 s in all)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hydroarm.reference.arm_decoupled as arm_model  # noqa: E402
from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.core.arm_kinematics import JOINT_NAMES, pose_load_fd, pose_terms  # noqa: E402
from hydroarm.core.params import joint_at, load_at  # noqa: E402
from hydroarm.integrators import fixed  # noqa: E402


def kernel_arguments(sc):
    """The arguments simulate_arm passes to arm_integrate for the scenario ``sc``."""
    seen = {}
    real = arm_model.arm_integrate

    def grab(*args):
        seen["args"] = args
        return real(*args)

    arm_model.arm_integrate = grab
    try:
        res = arm_model.simulate_decoupled(sc)
    finally:
        arm_model.arm_integrate = real
    return res, list(seen["args"]), real


def best_of(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


@njit(cache=True)
def _closed_form_loop(q, n, G):
    s = 0.0
    for i in range(n):
        t = pose_terms(q[0] + 1e-9 * i, q[1], q[2], G)
        s += t[0] + t[1] + t[2] + t[3] + t[4] + t[5]
    return s


@njit(cache=True)
def _finite_difference_loop(q, n, G):
    s = 0.0
    for _ in range(n):
        q[0] += 1e-9
        for j in range(3):  # shoulder elevation, humeral rotation, reach (the wrist: none)
            a, b = pose_load_fd(q, j, G)
            s += a + b
    return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 s of the run, 2 repeats")
    ap.add_argument("--duration", type=float, default=9.0)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    duration, repeat = (1.0, 2) if a.quick else (a.duration, a.repeat)
    sc = load_arm(ROOT / "examples" / "ucl-arm.toml").replace(duration=duration)
    every = 5e-3  # the accuracy's samples [s]
    fast, args, kernel = kernel_arguments(sc.replace(record_every=round(every / sc.step)))
    ref_sc = sc.replace(method="euler", step=10e-6, record_every=round(every / 10e-6))
    ref, rargs, _ = kernel_arguments(ref_sc)
    nj = len(args[1])
    n_fast, n_ref = args[6], rargs[6]

    PM = rargs[12]
    singles = []
    for j in range(nj):
        n = rargs[10][j]
        singles.append(
            (rargs[0], rargs[1][j], 0.0, rargs[3][j], 0.0, rargs[5], n_ref, rargs[7])
            + (rargs[8][j, :n], rargs[9][j, :n], rargs[11][j], joint_at(PM, j), load_at(PM, j))
        )
    for s1 in singles:
        fixed.integrate(*s1)

    print(
        f"workload: {sc.name}, {nj} joints, {duration:g} s; best of {repeat}, CPU time, "
        "each measured twice"
    )
    print(
        f"default: {sc.method} h = {sc.step * 1e3:g} ms ({n_fast} steps); reference: euler "
        f"h = 10 us ({n_ref} steps)"
    )
    for rnd in (1, 2):
        t_fast = best_of(lambda: kernel(*args), repeat)
        t_ref = best_of(lambda: kernel(*rargs), repeat)
        t_single = best_of(lambda: [fixed.integrate(*s1) for s1 in singles], repeat)
        print(f"run {rnd}:")
        print(
            f"  arm kernel, {sc.method} {sc.step * 1e3:g} ms  {t_fast / (n_fast * nj) * 1e6:7.3f}"
            f" us/joint-step  real time x{duration / t_fast:7.1f}"
        )
        print(
            f"  arm kernel, euler 10 us  {t_ref / (n_ref * nj) * 1e6:7.3f} us/joint-step  "
            f"real time x{duration / t_ref:7.1f}  (reference)   ratio {t_ref / t_fast:6.1f}"
        )
        print(
            f"  single joints, euler 10 us {t_single / (n_ref * nj) * 1e6:5.3f} us/joint-step  "
            f"real time x{duration / t_single:7.1f}  (physics alone; arm/single "
            f"{t_ref / t_single:.2f})"
        )

    qf, qr = fast.articulation_angles(), ref.articulation_angles()
    n = min(len(qf), len(qr))
    dmax = np.degrees(np.max(np.abs(qf[:n] - qr[:n]), axis=0))
    dfin = np.degrees(np.abs(qf[-1] - qr[-1]))
    print(f"accuracy of the default against the reference ({every * 1e3:g} ms samples):")
    for name in fast.names:
        k = JOINT_NAMES.index(name)
        print(
            f"  {name:20s} max |dtheta| {dmax[k]:.4f} deg   final {np.degrees(qf[-1, k]):9.4f} "
            f"vs {np.degrees(qr[-1, k]):9.4f} deg (|d| {dfin[k]:.1e})"
        )
    print(
        f"  lowest supply pressure {fast.supply_pressure.min() * 1e-5:.3f} bar vs "
        f"{ref.supply_pressure.min() * 1e-5:.3f} bar "
        f"(relief {sc.power_pack.supply_pressure * 1e-5:g})"
    )

    G = sc.geometry.params()
    q = np.radians([30.0, 20.0, 40.0, 0.0])
    npose = 200_000
    _closed_form_loop(q, 10, G)
    _finite_difference_loop(q.copy(), 10, G)
    t_cf = best_of(lambda: _closed_form_loop(q, npose, G), repeat)
    t_fd = best_of(lambda: _finite_difference_loop(q.copy(), npose, G), repeat)
    print(
        f"pose load per step: closed form {t_cf / npose * 1e9:7.1f} ns, finite differences "
        f"{t_fd / npose * 1e9:7.1f} ns (3 joints): {t_fd / t_cf:.1f}x"
    )


if __name__ == "__main__":
    main()
