"""Forward-dynamics speed of the tree kernel (hydroarm.core.tree) against Pinocchio.

Workload: a 4-joint and a 12-joint serial chain (revolute and prismatic joints, tilted axes,
made-up inertias; the same description built into both libraries), forward dynamics at random
states. Three figures per chain, each the best of ``--repeat`` timings of ``--calls`` calls:

* Pinocchio's ``pin.aba`` called from Python in a loop (the reference: what a Python user of
  Pinocchio gets);
* our ABA (:func:`hydroarm.core.tree.forward_dynamics`) called from Python in the same loop
  (numba's dispatch of the array arguments included);
* our ABA in a loop compiled with it (how the system kernel's integrators will call it).

Then the whole system kernel (:func:`hydroarm.model.circuit.simulate`: the tree's ABA inside
the circuit right-hand side, RK4 at 1 ms, the joints' projections, recording) on the same
chains run passive for ``--duration`` seconds, as a real-time factor (simulated seconds per
wall second; the issue's targets: 4 joints ≥ 300×, 12 joints ≥ 50×), against today's
decoupled UCL arm (``hydroarm.reference.arm_decoupled.simulate_decoupled`` on
examples/ucl-arm.toml, RK4 at 1 ms) measured in the same run.

Last, the UCL arm as one mechanism file (examples/ucl-arm-mechanism.toml: coupled dynamics,
each joint's circuit and the pumped supply, RK4 at 1 ms) against the decoupled arm model over
the same 9 s of block stacking: issue 30's 4-joint target.

Ratios are against the Pinocchio loop measured in the same run; the machine's load average is
printed with each line (the machines are shared). Requires ``pin`` (the test extra).

Last figures (2-core machine, 2026-11-28 02:13-02:21 UTC, load average 3 to 8.5, with
``--cpu``: the thread's CPU time; docs/mechanism.md "Speed"): the UCL arm as a mechanism
158-160x real time (6.3 us a step), 0.70-0.73x the decoupled arm's 212-228x; the commit
before the tree's coordinate-axis joints and ten-number composite inertias (1142266), run
alternately in the same conditions, 129-135x (7.4-7.9 us a step): 1.2x faster, the UCL arm's
states within 9e-15 of their range (round-off), the other mechanism examples bit-identical;
issue 30's 300x missed by 1.9x. The passive chains unchanged (4 joints about 294x, 12 about
102x). The tree's kernels used to take numba's reference counting from whichever caller
compiled them first (this script's ``compiled_loop`` does, before the system kernel): their
figures then depended on the order things first ran in; they now set it off themselves
(hydroarm/core/tree.py).

Run: python benchmarks/mechanism_speed.py [--calls 20000] [--repeat 3] [--cpu]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.core import tree as T  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.model.circuit import Circuit, build, simulate  # noqa: E402
from hydroarm.model.mechanism import Joint, Link, Mechanism, inertia_matrix  # noqa: E402
from hydroarm.reference.arm_decoupled import simulate_decoupled as simulate_arm  # noqa: E402


def chain(n: int) -> Mechanism:
    """A serial chain: every third joint prismatic, axes tilted, links 0.3 m long."""
    links = [Link("base")]
    joints = []
    for i in range(n):
        links.append(
            Link(f"l{i}", 1.0 + 0.1 * i, (0.01, 0.02, -0.15), (0.02, 0.021, 0.003, 1e-4, 0, 0))
        )
        prismatic = i % 3 == 2
        joints.append(
            Joint(
                f"j{i}",
                "prismatic" if prismatic else "revolute",
                "base" if i == 0 else f"l{i - 1}",
                f"l{i}",
                axis=(0.1, 1.0, 0.2 * (i % 2)) if not prismatic else (0.0, 0.0, 1.0),
                origin=(0.0, 0.0, -0.3 if i else 0.0),
                rpy=(0.0, 0.1 * i, 0.0),
            )
        )
    return Mechanism(tuple(links), tuple(joints))


def pinocchio_model(mech: Mechanism):
    model = pin.Model()
    model.gravity = pin.Motion(np.r_[mech.gravity, 0.0, 0.0, 0.0])
    links = {link.name: link for link in mech.links}
    for i, j in enumerate(mech.joints):
        axis = np.asarray(j.axis) / np.linalg.norm(j.axis)
        jm = (
            pin.JointModelPrismaticUnaligned(axis)
            if j.type == "prismatic"
            else pin.JointModelRevoluteUnaligned(axis)
        )
        jid = model.addJoint(
            i, jm, pin.SE3(pin.rpy.rpyToMatrix(*j.rpy), np.asarray(j.origin)), j.name
        )
        link = links[j.child]
        model.appendBodyToJoint(
            jid,
            pin.Inertia(link.mass, np.asarray(link.com), inertia_matrix(link.inertia)),
            pin.SE3.Identity(),
        )
    return model


@njit(cache=True, nogil=True)
def compiled_loop(tree, q, qd, tau, fext, work, qdd, calls):
    """``calls`` forward-dynamics evaluations in compiled code (the integrator's way)."""
    s = 0.0
    for _ in range(calls):
        q[0] += 1e-9  # a new state each call (nothing is hoisted out of the loop)
        T.forward_dynamics(tree, q, qd, tau, fext, work, qdd)
        s += qdd[0]
    return s


#: the clock of :func:`best`: the wall, or with ``--cpu`` this thread's CPU time (every timed
#: loop runs in the calling thread), which moves less than the wall on a busy machine
CLOCK = time.perf_counter


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = CLOCK()
        fn()
        times.append(CLOCK() - t0)
    return min(times)


def measure(n: int, calls: int, repeat: int, rng) -> None:
    """Time the three loops on an ``n``-joint chain and print one line."""
    mech = chain(n)
    tree = mech.compile().tree
    model = pinocchio_model(mech)
    data = model.createData()
    work = T.make_tree_work(n)
    q, qd, tau = (rng.normal(size=n) for _ in range(3))
    fext = np.zeros((n, 6))
    qdd = np.zeros(n)
    T.forward_dynamics(tree, q, qd, tau, fext, work, qdd)
    err = np.abs(qdd - pin.aba(model, data, q, qd, tau)).max() / np.abs(qdd).max()
    assert err < 1e-9, err
    compiled_loop(tree, q.copy(), qd, tau, fext, work, qdd, 10)

    def pinocchio_loop():
        for _ in range(calls):
            pin.aba(model, data, q, qd, tau)

    def python_loop():
        for _ in range(calls):
            T.forward_dynamics(tree, q, qd, tau, fext, work, qdd)

    def native_loop():
        compiled_loop(tree, q.copy(), qd, tau, fext, work, qdd, calls)

    t_pin = best(pinocchio_loop, repeat)
    t_py = best(python_loop, repeat)
    t_nat = best(native_loop, repeat)
    print(
        f"{n:2d} joints: pin.aba from Python {calls / t_pin:.3g} calls/s "
        f"({1e6 * t_pin / calls:.2f} us); ours from Python {calls / t_py:.3g} calls/s, ratio "
        f"{t_pin / t_py:.2f}x; ours compiled {calls / t_nat:.3g} calls/s "
        f"({1e6 * t_nat / calls:.2f} us), ratio {t_pin / t_nat:.2f}x; RK4 at 1 ms on the "
        f"dynamics alone: {calls / t_nat / 4000:.0f}x real time; load average "
        f"{os.getloadavg()[0]:.2f} (relative difference from pin.aba {err:.1e})"
    )


def real_time(n: int, duration: float, repeat: int, reference: float) -> None:
    """The system kernel's real-time factor on a passive ``n``-joint chain, RK4 at 1 ms."""
    circuit = Circuit(
        name=f"chain{n}", components=(), mechanism=chain(n), method="rk4", step=1e-3,
        duration=duration, record_every=10,
        initial_joints={f"j{i}": 0.2 for i in range(n)},
    )  # fmt: skip
    compiled = build(circuit)
    simulate(compiled.circuit.replace(duration=0.01))  # compile
    t = best(lambda: simulate(compiled), repeat)
    print(
        f"{n:2d} joints, system kernel (RK4 at 1 ms, passive): {duration / t:.0f}x real time "
        f"({1e6 * t / (duration / 1e-3):.1f} us a step), {duration / t / reference:.2f}x the "
        f"decoupled UCL arm; load average {os.getloadavg()[0]:.2f}"
    )


def arm_reference(duration: float, repeat: int) -> float:
    """Today's decoupled 4-joint UCL arm (RK4 at 1 ms): its real-time factor."""
    sc = load_arm(ROOT / "examples" / "ucl-arm.toml")
    sc = sc.replace(duration=duration) if hasattr(sc, "replace") else sc
    simulate_arm(sc)
    t = best(lambda: simulate_arm(sc), repeat)
    factor = sc.duration / t
    print(
        f"decoupled UCL arm (examples/ucl-arm.toml, {sc.duration:g} s): {factor:.0f}x real time; "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    return factor


def ucl_arm_mechanism(repeat: int, reference: float) -> None:
    """The UCL arm as one mechanism file (examples/ucl-arm-mechanism.toml, written by
    ``hydroarm expand``: the coupled tree with the reach's shoulder coupling, each joint's
    circuit, the pump, relief valve and supply volume; RK4 at 1 ms over its block-stacking
    inputs): issue 30's 4-joint target (≥ 300× real time) against the decoupled arm."""
    circuit = load_circuit(ROOT / "examples" / "ucl-arm-mechanism.toml")
    compiled = build(circuit)
    simulate(build(circuit.replace(duration=0.01)))  # compile
    t = best(lambda: simulate(compiled), repeat)
    c0 = time.thread_time()  # one thread: the CPU time moves less than the wall on a busy machine
    simulate(compiled)
    cpu = time.thread_time() - c0
    steps = circuit.duration / circuit.step
    print(
        f"UCL arm as a mechanism (examples/ucl-arm-mechanism.toml, {circuit.duration:g} s, "
        f"RK4 at {circuit.step * 1e3:g} ms): {circuit.duration / t:.0f}x real time "
        f"({1e6 * t / steps:.1f} us a step; CPU {1e6 * cpu / steps:.1f} us a step), "
        f"{circuit.duration / t / reference:.2f}x the decoupled UCL arm; load average "
        f"{os.getloadavg()[0]:.2f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--cpu", action="store_true", help="time by this thread's CPU time")
    a = ap.parse_args()
    if a.cpu:
        global CLOCK
        CLOCK = time.thread_time
        print("every time below is this thread's CPU time (time.thread_time), not the wall")
    rng = np.random.default_rng(0)
    print(f"forward dynamics, {a.calls} calls per timing, best of {a.repeat}")
    for n in (4, 12):
        measure(n, a.calls, a.repeat, rng)
    reference = arm_reference(a.duration, a.repeat)
    for n in (4, 12):
        real_time(n, a.duration, a.repeat, reference)
    ucl_arm_mechanism(a.repeat, arm_reference(9.0, a.repeat))


if __name__ == "__main__":
    main()
