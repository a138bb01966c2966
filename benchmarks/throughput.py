"""Throughput of the batch engine against references measured in the same run.

Workload (examples/throughput.toml): 2,000 Monte Carlo scenarios around load 6, raising, the
paper's Euler scheme, 10 µs step, 1 s of motion each (2×10⁸ scenario-steps).

Prints scenario-steps per second for
  * hydroarm's batch engine (numba, parallel over scenarios, metrics on the fly),
  * a plain numpy vectorised Euler loop over all scenarios (same equations),
  * a per-scenario scipy ``solve_ivp`` (LSODA) loop at equal accuracy (its tolerance is
    chosen so that its error in the final position against a tight Radau reference is no
    larger than the Euler scheme's),
  * a plain C loop of the same Euler scheme, -O3 -fopenmp on all cores (if gcc is found),
and the ratios; then the peak memory of a 10⁶-scenario metrics-only sweep and the cold
start of a sweep in a fresh process (numba cache loaded).

Run: python benchmarks/throughput.py [--quick]
"""

from __future__ import annotations

import argparse
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

from hydroarm.batch.engine import run_batch  # noqa: E402
from hydroarm.batch.sweep import load_sweep, scenario_inputs  # noqa: E402
from hydroarm.core.joint import (  # noqa: E402
    P_AREA,
    P_ARM,
    P_BETA,
    P_CRANK,
    P_E_SAT,
    P_FLOW_COEFF,
    P_HORIZ,
    P_INERTIA,
    P_LEAK,
    P_RATIO,
    P_SUPPLY,
    P_VOLUME,
    P_WEIGHT,
)


def numpy_reference(params, th0, p0, y1, h, nsteps):
    """Euler scheme of eqs. (5)-(7) vectorised over scenarios with numpy."""
    P = params.T
    A, eo, L, V, beta = P[P_AREA], P[P_E_SAT], P[P_LEAK], P[P_VOLUME], P[P_BETA]
    kq = P[P_FLOW_COEFF] * np.sqrt(0.5 * P[P_SUPPLY])
    r, n, W, X, inertia, thh = P[P_CRANK], P[P_RATIO], P[P_WEIGHT], P[P_ARM], P[P_INERTIA], \
        P[P_HORIZ]
    th, om, p = th0.copy(), np.zeros_like(th0), p0.copy()
    for _ in range(nsteps):
        x = r * np.sin(th / n)
        xd = r * np.cos(th / n) * om / n
        e = np.clip(y1 - x, -eo, eo)
        p = p + h * beta / V * (kq * e - A * xd - 2 * L * p)
        om = om + h * (A * p * r / n - W * X * np.cos(th - thh)) / inertia
        th = th + h * om
    return th


def solve_ivp_reference(sw, th0, p0, y0, y1, idx, rtol):
    from scipy.integrate import solve_ivp

    from hydroarm.core.equations import derivatives

    b = sw.base
    out = []
    for i in idx:
        P = sw.params[i]

        def rhs(t, s, P=P, y=y1[i]):
            return list(derivatives(s[0], s[1], s[2], y, P))

        sol = solve_ivp(rhs, (0.0, b.duration), [th0[i], 0.0, p0[i]], method="LSODA",
                        rtol=rtol, atol=[1e-10, 1e-8, 1e-2 * rtol / 1e-6])
        out.append(sol.y[0, -1])
    return np.array(out)


def radau_final(sw, th0, p0, y1, i):
    from scipy.integrate import solve_ivp

    from hydroarm.core.equations import derivatives

    P = sw.params[i]
    sol = solve_ivp(lambda t, s: list(derivatives(s[0], s[1], s[2], y1[i], P)),
                    (0.0, sw.base.duration), [th0[i], 0.0, p0[i]], method="Radau",
                    rtol=1e-11, atol=[1e-13, 1e-11, 1e-5])
    return sol.y[0, -1]


def peak_memory_million(tmp: Path) -> float:
    """Peak RSS [MiB] of `hydroarm sweep` over 10⁶ scenarios (metrics only, 2 ms each)."""
    cfg = tmp / "million.toml"
    cfg.write_text((ROOT / "examples" / "throughput.toml").read_text()
                   .replace('duration = "1 s"', 'duration = "2 ms"')
                   .replace("n = 2000", "n = 1000000"))
    code = ("import resource, sys; from hydroarm.cli import main; "
            f"rc = main(['sweep', '--config', {str(cfg)!r}, '--out', {str(tmp / 'm.csv')!r}, "
            "'--chunk', '65536']); "
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); sys.exit(rc)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    if r.returncode:
        raise RuntimeError(r.stderr)
    return float(r.stdout.strip().splitlines()[-1])


def cold_start(tmp: Path) -> float:
    """Seconds for a tiny sweep in a fresh process (compile cache already on disk)."""
    cfg = tmp / "tiny.toml"
    cfg.write_text((ROOT / "examples" / "throughput.toml").read_text()
                   .replace('duration = "1 s"', 'duration = "1 ms"').replace("n = 2000", "n = 2"))
    cmd = [sys.executable, "-m", "hydroarm.cli", "sweep", "--config", str(cfg), "--out",
           str(tmp / "t.csv")]
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
    print(f"workload: {n} scenarios x {nsteps} Euler steps of {h * 1e6:g} us "
          f"({n * nsteps:.3g} scenario-steps); {os.cpu_count()} cores")

    run_batch(0, sw.params[:8], th0[:8], p0[:8], y0[:8], y1[:8], t_step=0.0, h=h, nsteps=10)
    t = time.perf_counter()
    run_batch(0, sw.params, th0, p0, y0, y1, t_step=0.0, h=h, nsteps=nsteps)
    t_batch = time.perf_counter() - t
    r_batch = n * nsteps / t_batch
    print(f"hydroarm batch engine : {r_batch:10.3g} scenario-steps/s  ({t_batch:.2f} s)")

    k = max(1, nsteps // 20)  # numpy: cost per step does not depend on the step count
    t = time.perf_counter()
    numpy_reference(sw.params, th0, p0, y1, h, k)
    r_numpy = n * k / (time.perf_counter() - t)
    print(f"numpy vectorised      : {r_numpy:10.3g} scenario-steps/s  "
          f"(ratio {r_batch / r_numpy:.1f}x)")

    # equal accuracy: the Euler scheme's final-position error against Radau
    from hydroarm.core.inputs import step as step_input
    from hydroarm.integrators import fixed

    i = 0
    ref = radau_final(sw, th0, p0, y1, i)
    lev = step_input(y0[i], y1[i], 0.0)
    e_euler = abs(fixed.integrate(0, th0[i], 0.0, p0[i], 0.0, h, b.nsteps, b.nsteps, lev.times,
                                  lev.positions, lev.sine, sw.params[i])[1][-1] - ref)
    rtol = None
    for rt in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9):
        if abs(solve_ivp_reference(sw, th0, p0, y0, y1, [i], rt)[0] - ref) <= e_euler:
            rtol = rt
            break
    rtol = rtol or 1e-9
    m = 5
    t = time.perf_counter()
    solve_ivp_reference(sw, th0, p0, y0, y1, range(m), rtol)
    per = (time.perf_counter() - t) / m
    r_ivp = b.nsteps / per  # Euler-step equivalents of one scenario per second
    print(f"solve_ivp LSODA loop  : {r_ivp:10.3g} scenario-steps/s  (rtol {rtol:g}; Euler "
          f"error {e_euler:.2e} rad; ratio per scenario {r_batch / r_ivp:.0f}x)")

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc:
        with tempfile.TemporaryDirectory() as d:
            exe = Path(d) / "euler_ref"
            subprocess.run([cc, "-O3", "-fopenmp", "-o", str(exe),
                            str(ROOT / "benchmarks" / "euler_ref.c"), "-lm"], check=True)
            out = subprocess.run([str(exe), str(n), str(nsteps)], check=True,
                                 capture_output=True, text=True).stdout.split()
            r_c = n * nsteps / float(out[0])
        print(f"C -O3 OpenMP loop     : {r_c:10.3g} scenario-steps/s  (C / hydroarm "
              f"{r_c / r_batch:.2f}x)")
    else:
        print("C reference           : no C compiler found")

    with tempfile.TemporaryDirectory() as d:
        print(f"cold start of a sweep : {cold_start(Path(d)):.2f} s (fresh process, cache "
              "on disk, includes Python start-up and imports)")
        print(f"peak memory, 10^6-scenario metrics-only sweep: "
              f"{peak_memory_million(Path(d)):.0f} MiB")


if __name__ == "__main__":
    main()
