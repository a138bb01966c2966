"""Throughput of the batch engine against references measured in the same run.

Workload (examples/throughput.toml): 2,000 Monte Carlo scenarios around load 6, raising, the
paper's Euler scheme, 10 µs step, 1 s of motion each (2×10⁸ scenario-steps).

Prints scenario-steps per second for
  * hydroarm's batch engine (numba, parallel over scenarios, metrics on the fly),
  * a plain numpy vectorised Euler loop over all scenarios (same equations),
  * a per-scenario scipy ``solve_ivp`` (LSODA) loop at equal accuracy: its tolerance is the
    loosest of a ladder whose largest error in the jack position over the motion (sampled
    every 1 ms, against a tight Radau reference) is no larger than the Euler scheme's. The
    10 us Euler workload is far more steps than that accuracy needs, so the batch engine is
    also timed at its cheapest setting that meets it (rk4 at the largest step of a ladder up
    to 1 ms), against LSODA at the Euler scheme's error and at rk4's own,
  * a plain C loop of the same Euler scheme, -O3 -fopenmp on all cores (if gcc is found),
and the ratios; then the peak memory of a 10⁶-scenario metrics-only sweep and the cold
start of a sweep in a fresh process (numba cache loaded).

Run: python benchmarks/throughput.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.batch.engine import METRICS, run_batch  # noqa: E402
from hydroarm.batch.sweep import load_sweep, scenario_inputs  # noqa: E402
from hydroarm.core.params import (  # noqa: E402
    J_AREA,
    J_BETA,
    J_CRANK,
    J_E_SAT,
    J_FLOW_COEFF,
    J_HORIZ,
    J_LEAK,
    J_RATIO,
    J_SUPPLY,
    J_VOLUME,
    L_ARM,
    L_INERTIA,
    L_WEIGHT,
    joint_at,
    load_at,
)
from hydroarm.integrators.fixed import EULER, RK4  # noqa: E402

FAILED, STALLED = METRICS.index("failed"), METRICS.index("stalled")


def numpy_reference(params, th0, p0, y1, h, nsteps):
    """Euler scheme of eqs. (5)-(7) vectorised over scenarios with numpy."""
    P = params.T
    A, eo, L, V, beta = P[J_AREA], P[J_E_SAT], P[J_LEAK], P[J_VOLUME], P[J_BETA]
    kq = P[J_FLOW_COEFF] * np.sqrt(0.5 * P[J_SUPPLY])
    r, n, W, X, inertia, thh = (
        P[J_CRANK],
        P[J_RATIO],
        P[L_WEIGHT],
        P[L_ARM],
        P[L_INERTIA],
        P[J_HORIZ],
    )
    th, om, p = th0.copy(), np.zeros_like(th0), p0.copy()
    for _ in range(nsteps):
        x = r * np.sin(th / n)
        xd = r * np.cos(th / n) * om / n
        e = np.clip(y1 - x, -eo, eo)
        p = p + h * beta / V * (kq * e - A * xd - 2 * L * p)
        om = om + h * (A * p * r / n - W * X * np.cos(th - thh)) / inertia
        th = th + h * om
    return th


REPEAT = 3
GRID = 1001  # samples of the trajectory, 1 ms apart over the 1 s motion


def _rhs(sw, i, y):
    from hydroarm.core.equations import derivatives

    J, L = joint_at(sw.params, i), load_at(sw.params, i)
    return lambda t, s: list(derivatives(s[0], s[1], s[2], y, J, L))


def radau_trajectory(sw, th0, p0, y1, i):
    """Tight reference θ₂(t) of scenario i on the GRID (Radau, rtol 1e-11)."""
    from scipy.integrate import solve_ivp

    t = np.linspace(0.0, sw.base.duration, GRID)
    sol = solve_ivp(
        _rhs(sw, i, y1[i]),
        (0.0, sw.base.duration),
        [th0[i], 0.0, p0[i]],
        method="Radau",
        rtol=1e-11,
        atol=[1e-13, 1e-11, 1e-5],
        t_eval=t,
    )
    return sol.y[0]


def lsoda_trajectory(sw, th0, p0, y1, i, rtol):
    """θ₂(t) of scenario i on the GRID by LSODA at ``rtol`` (what a per-scenario loop runs)."""
    from scipy.integrate import solve_ivp

    t = np.linspace(0.0, sw.base.duration, GRID)
    sol = solve_ivp(
        _rhs(sw, i, y1[i]),
        (0.0, sw.base.duration),
        [th0[i], 0.0, p0[i]],
        method="LSODA",
        rtol=rtol,
        atol=[1e-10, 1e-8, 1e-2 * rtol / 1e-6],
        t_eval=t,
    )
    return sol.y[0]


def fixed_trajectory(sw, th0, p0, y0, y1, i, method, h):
    """θ₂(t) of scenario i on the GRID by hydroarm's fixed-step kernel."""
    from hydroarm.integrators import fixed
    from hydroarm.model.lever import step as step_input

    lev = step_input(y0[i], y1[i], 0.0)
    n = int(round(sw.base.duration / h))
    every = int(round(sw.base.duration / (GRID - 1) / h))
    th = fixed.integrate(
        method,
        th0[i],
        0.0,
        p0[i],
        0.0,
        h,
        n,
        every,
        lev.times,
        lev.positions,
        lev.sine,
        joint_at(sw.params, i),
        load_at(sw.params, i),
    )[1]
    return th if th.size == GRID else np.full(GRID, np.nan)


def trajectory_error(sw, th, ref, i):
    """Largest error of the jack position over the motion, relative to the travel."""
    from hydroarm.core.equations import jack_position_trace

    J = joint_at(sw.params, i)
    x, xr = jack_position_trace(th, J), jack_position_trace(ref, J)
    return float(np.max(np.abs(x - xr)) / abs(xr[-1] - xr[0]))


def lsoda_at(sw, th0, p0, y1, ref, error, m=5):
    """(rtol, seconds per scenario) of LSODA at the loosest tolerance of a ladder whose
    trajectory error is no larger than ``error``; timed over m scenarios."""
    import time as _t

    rtol = 1e-10
    for rt in (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8, 1e-9, 1e-10):
        if trajectory_error(sw, lsoda_trajectory(sw, th0, p0, y1, 0, rt), ref, 0) <= error:
            rtol = rt
            break
    t = _t.perf_counter()
    for i in range(m):
        lsoda_trajectory(sw, th0, p0, y1, i, rtol)
    return rtol, (_t.perf_counter() - t) / m


def peak_memory_million(tmp: Path) -> float:
    """Peak RSS [MiB] of `hydroarm sweep` over 10⁶ scenarios (metrics only, 2 ms each)."""
    cfg = tmp / "million.toml"
    cfg.write_text(
        (ROOT / "examples" / "throughput.toml")
        .read_text()
        .replace('duration = "1 s"', 'duration = "2 ms"')
        .replace("n = 2000", "n = 1000000")
    )
    code = (
        "import resource, sys; from hydroarm.cli import main; "
        f"rc = main(['sweep', '--config', {str(cfg)!r}, '--out', {str(tmp / 'm.csv')!r}, "
        "'--chunk', '65536']); "
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); sys.exit(rc)"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    if r.returncode:
        raise RuntimeError(r.stderr)
    return float(r.stdout.strip().splitlines()[-1])


def cold_start(tmp: Path) -> float:
    """Seconds for a tiny sweep in a fresh process (compile cache already on disk)."""
    cfg = tmp / "tiny.toml"
    cfg.write_text(
        (ROOT / "examples" / "throughput.toml")
        .read_text()
        .replace('duration = "1 s"', 'duration = "1 ms"')
        .replace("n = 2000", "n = 2")
    )
    cmd = [
        sys.executable,
        "-m",
        "hydroarm.cli",
        "sweep",
        "--config",
        str(cfg),
        "--out",
        str(tmp / "t.csv"),
    ]
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)  # make sure caches exist
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="smaller workload (1/10 of the steps)")
    a = ap.parse_args()
    sw = load_sweep(ROOT / "examples" / "throughput.toml")
    b = sw.base
    th0, p0, y0, y1 = scenario_inputs(sw)
    n = sw.size
    nsteps = b.nsteps // (10 if a.quick else 1)
    h = b.step
    print(
        f"workload: {n} scenarios x {nsteps} Euler steps of {h * 1e6:g} us "
        f"({n * nsteps:.3g} scenario-steps); {os.cpu_count()} cores"
    )

    # this machine is shared: each compiled timing is the best of REPEAT runs
    run_batch(EULER, sw.params[:8], th0[:8], p0[:8], y0[:8], y1[:8], t_step=0.0, h=h, nsteps=10)
    t_batch = math.inf
    for _ in range(REPEAT):
        t = time.perf_counter()
        res = run_batch(EULER, sw.params, th0, p0, y0, y1, t_step=0.0, h=h, nsteps=nsteps)
        t_batch = min(t_batch, time.perf_counter() - t)
    r_batch = n * nsteps / t_batch
    print(
        f"hydroarm batch engine : {r_batch:10.3g} scenario-steps/s  ({t_batch:.2f} s; "
        f"{int((res[:, FAILED] > 0).sum())} failed, {int(res[:, STALLED].sum())} stalled "
        "and re-run)"
    )

    k = max(1, nsteps // 20)  # numpy: cost per step does not depend on the step count
    t = time.perf_counter()
    numpy_reference(sw.params, th0, p0, y1, h, k)
    r_numpy = n * k / (time.perf_counter() - t)
    print(
        f"numpy vectorised      : {r_numpy:10.3g} scenario-steps/s  "
        f"(ratio {r_batch / r_numpy:.1f}x)"
    )

    # equal accuracy: the largest error of the jack position over the motion (sampled every
    # 1 ms, relative to the travel) against a tight Radau reference, on scenario 0
    ref = radau_trajectory(sw, th0, p0, y1, 0)
    e_euler = trajectory_error(sw, fixed_trajectory(sw, th0, p0, y0, y1, 0, EULER, h), ref, 0)
    rtol, per = lsoda_at(sw, th0, p0, y1, ref, e_euler)
    per_batch = t_batch / n * (b.nsteps / nsteps)  # one scenario of the full 1 s workload
    print(
        f"solve_ivp LSODA loop  : {per * 1e3:8.2f} ms per scenario at rtol {rtol:g} (error "
        f"<= the Euler scheme's {e_euler:.1e} of the travel); batch euler "
        f"{per_batch * 1e3:.2f} ms: ratio {per / per_batch:.1f}x"
    )
    # The batch engine at its best for that accuracy: rk4 at the largest step of a ladder
    # (up to the 1 ms grid on which the error is measured) that meets the Euler scheme's
    # error and stays finite for every scenario of the workload.
    h4, e4, per4, res4 = None, None, math.inf, None
    for hh in (1e-3, 500e-6, 250e-6, 100e-6, 50e-6):
        e = trajectory_error(sw, fixed_trajectory(sw, th0, p0, y0, y1, 0, RK4, hh), ref, 0)
        if not (np.isfinite(e) and e <= e_euler):
            continue
        n4 = int(round(b.duration / hh))
        for _ in range(REPEAT):
            t = time.perf_counter()
            res4 = run_batch(RK4, sw.params, th0, p0, y0, y1, t_step=0.0, h=hh, nsteps=n4)
            per4 = min(per4, (time.perf_counter() - t) / n)
        if not res4[:, FAILED].any():
            h4, e4 = hh, e
            break
        per4 = math.inf
    if h4 is not None:
        print(
            f"batch rk4 at {h4 * 1e6:g} us   : {per4 * 1e3:8.3f} ms per scenario (error "
            f"{e4:.1e}, within the Euler scheme's); LSODA at the Euler scheme's error "
            f"{per * 1e3:.2f} ms: ratio {per / per4:.0f}x"
        )
        rtol4, per_l4 = lsoda_at(sw, th0, p0, y1, ref, e4)
        print(
            f"{'':22}  LSODA at rk4's own error (rtol {rtol4:g}) {per_l4 * 1e3:.2f} ms: "
            f"ratio {per_l4 / per4:.0f}x"
        )
        if not a.quick:  # the metrics of the two batch runs (Euler 10 us, rk4) side by side
            for name in ("saturation_velocity", "time_constant_start", "time_constant_end"):
                k = METRICS.index(name)
                d = np.nanmax(np.abs(res4[:, k] - res[:, k]) / np.abs(res[:, k]))
                print(f"{'':22}  {name}: rk4 and Euler agree to {d:.1e} (relative, largest)")

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc:
        with tempfile.TemporaryDirectory() as d:
            exe = Path(d) / "euler_ref"
            subprocess.run(
                [
                    cc,
                    "-O3",
                    "-fopenmp",
                    "-o",
                    str(exe),
                    str(ROOT / "benchmarks" / "euler_ref.c"),
                    "-lm",
                ],
                check=True,
            )
            secs = min(
                float(
                    subprocess.run(
                        [str(exe), str(n), str(nsteps)], check=True, capture_output=True, text=True
                    ).stdout.split()[0]
                )
                for _ in range(REPEAT)
            )
            r_c = n * nsteps / secs
        print(
            f"C -O3 OpenMP loop     : {r_c:10.3g} scenario-steps/s  (C / hydroarm "
            f"{r_c / r_batch:.2f}x)"
        )
    else:
        print("C reference           : no C compiler found")

    with tempfile.TemporaryDirectory() as d:
        print(
            f"cold start of a sweep : {cold_start(Path(d)):.2f} s (fresh process, cache "
            "on disk, includes Python start-up and imports)"
        )
        print(
            f"peak memory, 10^6-scenario metrics-only sweep: {peak_memory_million(Path(d)):.0f} MiB"
        )


if __name__ == "__main__":
    main()
