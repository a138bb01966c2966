"""Cost of advancing piece by piece (the steppers behind `hydroarm fmu`, issue 19) against the
whole run, measured in the same run (CPU time of this process, best of ``--repeat``).

* the joint: examples/load6_raise.toml (Euler, 10 us, 1.5 s) by ``hydroarm.simulate`` (the
  reference) and by ``JointStepper`` advanced in communication steps of 1 ms (100 internal
  steps a call) and of 10 us (one step a call), the lever set and the outputs read at each;
* the arm: examples/ucl-arm.toml (RK4, 1 ms, 9 s): its circuit run whole on the system
  kernel, ``simulate(build(arm_circuit(sc)))`` (the reference: what ``ArmStepper`` steps,
  issue 28), ``simulate_arm`` (the arm's own kernel) beside it, and ``ArmStepper`` in
  communication steps of 5 ms and 1 ms, the four levers set and every output read at each.

Prints each time, the stepper's time over the reference's, and whether the final states are
the same to the last bit where they must be (the joint: the raise test's lever is held).

Run: python benchmarks/stepper.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hydroarm as ha  # noqa: E402
from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.arm.expand import arm_circuit  # noqa: E402
from hydroarm.arm.stepper import ArmStepper  # noqa: E402
from hydroarm.model.circuit import build, simulate  # noqa: E402
from hydroarm.reference.arm_decoupled import simulate_decoupled as simulate_arm  # noqa: E402


def best(f, repeat):
    out, times = None, []
    for _ in range(repeat):
        t0 = time.process_time()
        out = f()
        times.append(time.process_time() - t0)
    return min(times), out


def joint_stepped(sc, comm):
    st = ha.JointStepper.from_scenario(sc)
    n = int(round(sc.duration / comm))
    for _ in range(n):
        st.lever = float(sc.lever(st.t)[0])
        st.advance(comm)
        st.outputs()
    return st.outputs()["theta"]


def arm_stepped(sc, comm):
    st = ArmStepper(sc)
    n = int(round(sc.duration / comm))
    for i in range(n):
        st.levers = {name: float(sc.inputs[name](i * comm)[0]) for name in st.names}
        st.advance(comm)
        st.outputs()
    return st.outputs()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    sc = ha.load_scenario(ROOT / "examples" / "load6_raise.toml")
    joint_stepped(sc.replace(duration=0.01), 1e-3)  # compile or load the kernels
    t_ref, ref = best(lambda: ha.simulate(sc), a.repeat)
    print(f"joint: simulate, {sc.nsteps} Euler steps: {t_ref * 1e3:.1f} ms")
    for comm in (1e-3, 10e-6):
        t, theta = best(lambda comm=comm: joint_stepped(sc, comm), a.repeat)
        same = theta == float(ref.theta[-1])
        print(
            f"joint: JointStepper, communication step {comm * 1e3:g} ms: {t * 1e3:.1f} ms "
            f"({t / t_ref:.2f}x simulate; final angle bit for bit: {same})"
        )
    arm = load_arm(ROOT / "examples" / "ucl-arm.toml")
    arm_stepped(arm.replace(duration=0.01), 5e-3)
    simulate(build(arm_circuit(arm.replace(duration=0.01))))
    t_ref, res = best(lambda: simulate(build(arm_circuit(arm))), a.repeat)
    print(f"arm: its circuit run whole, {arm.duration:g} s of RK4 at 1 ms: {t_ref * 1e3:.1f} ms")
    t_arm, _ = best(lambda: simulate_arm(arm, check_stability=False), a.repeat)
    print(f"arm: simulate_arm (the arm's own kernel): {t_arm * 1e3:.1f} ms")
    for comm in (5e-3, 1e-3):
        t, _ = best(lambda comm=comm: arm_stepped(arm, comm), a.repeat)
        print(
            f"arm: ArmStepper, communication step {comm * 1e3:g} ms: {t * 1e3:.1f} ms "
            f"({t / t_ref:.2f}x the circuit's whole run; {arm.duration / t:.0f}x real time)"
        )
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    print(f"load average {os.getloadavg()[0]:.2f}; {now}")


if __name__ == "__main__":
    main()
