"""Real-time factor of the live arm of ``hydroarm explore`` against the whole run of the same
physics, measured in the same run (issue 18).

Workload: examples/ucl-arm.toml (four joints, pump 0.6 l/min, coupled RK4 at 1 ms), its
block-stacking levers (examples/block_stacking.csv) over the first ``--duration`` seconds.

Prints, best of ``--repeat`` runs (wall time, this process):
  * the reference: the arm's circuit run whole on the system kernel
    (``simulate(build(arm_circuit(sc)))``, what ``ArmStepper`` steps, issue 28) in one call:
    its real-time factor (simulated seconds per wall second); beside it ``simulate_arm``
    (the arm's own kernel, the ``arm`` command's);
  * the stepper as the app steps it: ``ArmStepper.advance`` in chunks of the page's timer
    (1/30 s), the levers set before each chunk, ``outputs()`` read after it;
  * the live arm as the page's timer drives it: ``LiveArm.tick`` per chunk plus what the
    page reads each frame (angles, arm points, gauges, score), without the drawing itself,
    at the live arm's own step (the arm's stability check over its levers' states: 0.5 ms);
  * each one's ratio to the reference and the wall time per frame against the frame's 33 ms.

Run: python benchmarks/explore_realtime.py [--quick]   (--quick: 2 s of the run)
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.arm import JOINT_NAMES, load_arm, simulate_arm  # noqa: E402
from hydroarm.arm.expand import arm_circuit  # noqa: E402
from hydroarm.arm.stepper import ArmStepper  # noqa: E402
from hydroarm.explore.app import TICK_S  # noqa: E402
from hydroarm.explore.live import LiveArm  # noqa: E402
from hydroarm.model.circuit import build, simulate  # noqa: E402


def lever_table(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The block-stacking CSV: times [s] and {joint: articulation angle [rad]}."""
    rows = [r for r in csv.reader(ln for ln in path.open() if not ln.startswith("#"))]
    head, data = rows[0], np.array(rows[1:], dtype=float)
    t = data[:, 0]
    return t, {h[:-4]: np.radians(data[:, i]) for i, h in enumerate(head) if i > 0}


def best_of(fn, repeat: int) -> float:
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=9.0, help="simulated seconds (default 9)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="2 s of the run")
    a = ap.parse_args(argv)
    duration = 2.0 if a.quick else a.duration
    sc = load_arm(ROOT / "examples" / "ucl-arm.toml").replace(duration=duration)
    times, angles = lever_table(ROOT / "examples" / "block_stacking.csv")
    n_frames = int(round(duration / TICK_S))

    def reference():
        simulate(build(arm_circuit(sc)))

    def arm_kernel():
        simulate_arm(sc)

    def stepper():
        st = ArmStepper(sc)
        for k in range(n_frames):
            t = k * TICK_S
            st.levers = {
                n: sc.joint(n).lever_for_angle(float(np.interp(t, times, angles[n])))
                for n in JOINT_NAMES
            }
            st.advance(TICK_S)
            st.outputs()

    def live():
        arm = LiveArm(sc)
        for k in range(n_frames):
            t = k * TICK_S
            for n in JOINT_NAMES:
                arm.set_lever(n, float(np.interp(t, times, angles[n])))
            arm.tick(TICK_S)
            arm.angles()
            arm.points()
            arm.gauges()
            arm.score()

    for fn in (reference, arm_kernel, stepper, live):  # load (or compile) the kernels
        fn()
    simulated = n_frames * TICK_S
    load = os.getloadavg()[0]
    w_ref = best_of(reference, a.repeat)
    w_arm = best_of(arm_kernel, a.repeat)
    w_step = best_of(stepper, a.repeat)
    w_live = best_of(live, a.repeat)
    print(
        f"workload: examples/ucl-arm.toml, {sc.method} at {sc.step * 1e3:g} ms, "
        f"{duration:g} s simulated, frames of {TICK_S * 1e3:.1f} ms, best of {a.repeat}"
    )
    print(
        f"  whole run on the system kernel (arm_circuit)  {w_ref:8.3f} s wall  "
        f"real-time factor {duration / w_ref:8.1f}"
    )
    print(
        f"  the arm's own kernel (simulate_arm, whole run)  {w_arm:8.3f} s wall  "
        f"real-time factor {duration / w_arm:8.1f}  ({w_ref / w_arm:.2f} × its wall time)"
    )
    for label, w in (
        ("ArmStepper in app frames           ", w_step),
        (f"LiveArm.tick + page reads per frame (its step {LiveArm(sc).step * 1e3:g} ms)", w_live),
    ):
        print(
            f"  {label}  {w:8.3f} s wall  real-time factor {simulated / w:8.1f}  "
            f"({(simulated / w) / (duration / w_ref):.2f} × the whole run; "
            f"{w / n_frames * 1e3:.2f} ms of the {TICK_S * 1e3:.1f} ms frame)"
        )
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    print(f"  load average {load:.2f} before, {os.getloadavg()[0]:.2f} after; {now}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
