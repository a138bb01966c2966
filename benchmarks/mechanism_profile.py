"""Where one step of the UCL arm as a mechanism goes (issue 30's speed target).

Each part of the right-hand side timed in isolation, in a compiled loop of ``--calls`` calls
at a state of the run (examples/ucl-arm-mechanism.toml after 2 s of its block stacking):
the whole step (RK4 at 1 ms: four right-hand sides and the projection), one right-hand
side, its parts (the signals, the components' laws, the joints' accelerations), and the
tree's algorithms under the joints' accelerations (placements, bias forces by RNEA, the
mass matrix by CRBA, the coupled solve). Best of ``--repeat``; the machine's load average
with each line (the machines are shared: compare only figures of one run).

Run: python benchmarks/mechanism_profile.py [--calls 200000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.core import tree as T  # noqa: E402
from hydroarm.core.circuit import system as S  # noqa: E402
from hydroarm.integrators.system import advance_steps, stepper  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.model.circuit import build, simulate  # noqa: E402

_FLAGS = {"cache": False, "nogil": True, "error_model": "numpy", "_nrt": False}


@njit(**_FLAGS)
def loop_step(code, A, b, c, h, s, P, net, work, out, K, tmp, st, calls):
    x = 0.0
    for _ in range(calls):
        for j in range(s.shape[0]):  # the same step every call
            st[j] = s[j]
        advance_steps(code, A, b, c, 2.0, 0, h, 1, st, P, net, work, out, K, tmp)
        x += st[0]
    return x


@njit(**_FLAGS)
def loop_rhs(s, P, net, work, d, calls):
    x = 0.0
    for i in range(calls):
        S.system_rhs(2.0 + 1e-12 * i, s, P, net, work, d)
        x += d[0]
    return x


@njit(**_FLAGS)
def loop_signals(s, P, net, work, calls):
    x = 0.0
    for i in range(calls):
        S.evaluate_signals(2.0 + 1e-12 * i, s, P, net, work)
        x += work[3][0]
    return x


@njit(**_FLAGS)
def loop_laws(s, P, net, work, d, calls):
    x = 0.0
    pn, xm, vm, sig, thr, cap, qn, cn, fm, mm = work[:10]
    for i in range(calls):
        S.all_laws(
            2.0 + 1e-12 * i, s, P, d, net[28], net[3], pn, xm, vm, sig, thr, cap, qn, cn, fm, mm
        )
        x += thr[0, 0]
    return x


@njit(**_FLAGS)
def loop_joints(net, work, d, nh, nm, m0, calls):
    x = 0.0
    mm = work[9]
    for _ in range(calls):
        for k in range(mm.shape[0]):  # the masses the laws summed (the call overwrites them)
            mm[k] = m0[k]
        S.joint_accelerations(
            net[11:21], net[24], net[25], net[21], net[22], work[1], work[2], work[8],
            work[9], work[10], work[11], work[12], work[13], work[14], work[15], nh + nm, d,
        )  # fmt: skip
        x += d[nh + nm]
    return x


@njit(**_FLAGS)
def loop_mechanical(P, net, work, d, nh, f0, m0, calls):
    x = 0.0
    fm, mm = work[8], work[9]
    for _ in range(calls):
        for k in range(fm.shape[0]):
            fm[k] = f0[k]
            mm[k] = m0[k]
        S.mechanical_accelerations(P, net, work, nh, d)
        x += d[-1]
    return x


@njit(**_FLAGS)
def loop_tree(which, tree, cpl, laws, q, qd, tau, fext, tw, qdd, calls):
    x = 0.0
    for _ in range(calls):
        if which == 0:
            T.joint_placements(tree, q, tw)
        elif which == 1:
            T.bias_forces(tree, q, qd, fext, tw, qdd)
        elif which == 2:
            T.mass_matrix(tree, q, tw, tw.M)
        elif which == 3:
            T.forward_dynamics_coupled(tree, cpl, laws, q, qd, tau, fext, tw, qdd)
        else:
            T.forward_dynamics(tree, q, qd, tau, fext, tw, qdd)
        x += qdd[0] + tw.M[0, 0] + tw.R[0, 0, 0]
    return x


def best(fn, repeat: int) -> tuple[float, float]:
    """The least wall and the least CPU time (this thread's: it moves less than the wall on a
    busy machine) of ``repeat`` calls."""
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.thread_time()
        fn()
        cpu.append(time.thread_time() - c0)
        wall.append(time.perf_counter() - t0)
    return min(wall), min(cpu)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--calls", type=int, default=200000)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    circuit = load_circuit(ROOT / "examples" / "ucl-arm-mechanism.toml")
    compiled = build(circuit.replace(duration=2.0))
    res = simulate(compiled)
    s = np.ascontiguousarray(res.states[-1])
    P, net = compiled.P, compiled.net
    work = S.make_work(net)
    d = np.empty(s.size)
    code, A, b, c = stepper("rk4")
    out, K, tmp = np.empty(s.size), np.empty((4, s.size)), np.empty(s.size)
    dims = net[9]
    nh, nm = int(dims[0]), int(dims[1])
    S.system_rhs(2.0, s, P, net, work, d)  # the work arrays at this state
    m0 = work[9].copy()
    tree = S.tree_of(net)
    tw = work[10]
    q, qd, tau, fext = work[11].copy(), work[12].copy(), work[13].copy(), work[15].copy()
    qdd = np.empty(q.size)
    n = a.calls
    rows = [
        ("RK4 step (4 rhs + projection)", lambda: loop_step(
            code, A, b, c, 1e-3, s, P, net, work, out, K, tmp, s.copy(), n), 1),
        ("rhs: system_rhs", lambda: loop_rhs(s, P, net, work, d, n), 1),
        ("rhs part: evaluate_signals", lambda: loop_signals(s, P, net, work, n), 1),
        ("rhs part: all_laws", lambda: loop_laws(s, P, net, work, d, n), 1),
        ("rhs part: mechanical_accelerations", lambda: loop_mechanical(
            P, net, work, d, nh, work[8].copy(), work[9].copy(), n), 1),
        ("  joint_accelerations", lambda: loop_joints(net, work, d, nh, nm, m0, n), 1),
        ("  tree: joint_placements", lambda: loop_tree(
            0, tree, net[24], net[25], q, qd, tau, fext, tw, qdd, n), 1),
        ("  tree: bias_forces (RNEA)", lambda: loop_tree(
            1, tree, net[24], net[25], q, qd, tau, fext, tw, qdd, n), 1),
        ("  tree: mass_matrix (CRBA)", lambda: loop_tree(
            2, tree, net[24], net[25], q, qd, tau, fext, tw, qdd, n), 1),
        ("  tree: forward_dynamics_coupled", lambda: loop_tree(
            3, tree, net[24], net[25], q, qd, tau, fext, tw, qdd, n), 1),
        ("  tree: forward_dynamics (ABA, no coupling)", lambda: loop_tree(
            4, tree, net[24], net[25], q, qd, tau, fext, tw, qdd, n), 1),
    ]  # fmt: skip
    print(f"UCL arm as a mechanism: {q.size} joints, {s.size} states; {n} calls a timing")
    print(f"{'':45s} {'wall':>8s}    {'CPU':>8s}")
    for name, fn, _ in rows:
        fn()  # compile
        t, c = best(fn, a.repeat)
        print(f"{name:45s} {1e9 * t / n:8.0f} ns {1e9 * c / n:8.0f} ns   load "
              f"{os.getloadavg()[0]:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
