"""Speed of the four-joint arm kernel against references measured in the same run (issue 21).

Workload: examples/ucl-arm.toml (block stacking, four joints, pump 0.6 l/min, the paper's
Euler scheme at its 10 us step), the first ``--duration`` seconds (9 s: the whole run).

Prints, best of ``--repeat`` runs (CPU time of this process):
  * the arm kernel (``hydroarm.arm.model.arm_integrate``): µs per joint-step, joint-steps/s
    and its real-time factor (simulated time / CPU time);
  * the reference: the single-joint kernel (``hydroarm.integrators.fixed.integrate``) on
    the same steps of each joint with its load frozen at the start (the cost of the physics
    alone), and the ratio;
  * the pose load per step: the closed form (``pose_terms``, all joints at once) against the
    old finite differences (``pose_load_fd``, once per pose-loaded joint), and the ratio.

Run: python benchmarks/arm_speed.py [--quick]   (--quick: 1 s of the run, ~5 s in all)
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

import hydroarm.arm.model as arm_model  # noqa: E402
from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.core.arm_kinematics import pose_load_fd, pose_terms  # noqa: E402
from hydroarm.core.params import joint_at, load_at  # noqa: E402
from hydroarm.integrators import fixed  # noqa: E402


def kernel_arguments(duration: float):
    """The arguments simulate_arm passes to arm_integrate for the example."""
    sc = load_arm(ROOT / "examples" / "ucl-arm.toml").replace(duration=duration)
    seen = {}
    real = arm_model.arm_integrate

    def grab(*args):
        seen["args"] = args
        return real(*args)

    arm_model.arm_integrate = grab
    try:
        arm_model.simulate_arm(sc, check_stability=False)
    finally:
        arm_model.arm_integrate = real
    return sc, list(seen["args"]), real


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
    sc, args, kernel = kernel_arguments(duration)
    nsteps, nj, h = args[6], len(args[1]), args[5]
    js = nsteps * nj
    t_arm = best_of(lambda: kernel(*args), repeat)

    PM = args[12]
    singles = []
    for j in range(nj):
        n = args[10][j]
        singles.append(
            (args[0], args[1][j], 0.0, args[3][j], 0.0, h, nsteps, args[7])
            + (args[8][j, :n], args[9][j, :n], args[11][j], joint_at(PM, j), load_at(PM, j))
        )
    for s in singles:
        fixed.integrate(*s)
    t_single = best_of(lambda: [fixed.integrate(*s) for s in singles], repeat)

    G = sc.geometry.params()
    q = np.radians([30.0, 20.0, 40.0, 0.0])
    npose = 200_000
    _closed_form_loop(q, 10, G)
    _finite_difference_loop(q.copy(), 10, G)
    t_cf = best_of(lambda: _closed_form_loop(q, npose, G), repeat)
    t_fd = best_of(lambda: _finite_difference_loop(q.copy(), npose, G), repeat)

    print(f"workload: {sc.name}, {nj} joints, {sc.method} h = {h * 1e6:g} us, {duration:g} s")
    print(f"  ({nsteps} steps, {js} joint-steps), best of {repeat}, CPU time")
    print(
        f"arm kernel      {t_arm / js * 1e6:7.3f} us/joint-step  {js / t_arm / 1e6:6.2f} M/s"
        f"  real time x{duration / t_arm:6.2f}"
    )
    print(
        f"single joints   {t_single / js * 1e6:7.3f} us/joint-step  {js / t_single / 1e6:6.2f} M/s"
        f"  real time x{duration / t_single:6.2f}  (reference)"
    )
    print(f"  arm / single-joint cost: {t_arm / t_single:.2f}")
    print(
        f"pose load per step: closed form {t_cf / npose * 1e9:7.1f} ns, finite differences "
        f"{t_fd / npose * 1e9:7.1f} ns (3 joints): {t_fd / t_cf:.1f}x"
    )


if __name__ == "__main__":
    main()
