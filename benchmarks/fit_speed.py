"""Speed of `hydroarm fit`: the batch Jacobian against serial forward differences (issue 16).

Workload: a 3-parameter fit (flow_coefficient, leakage_coefficient, trapped_volume) to two
synthetic 1.5 s traces (load 6, raise and lower; x every 5 ms, 299 samples each, noise
σ = 0.05 mm), generated at paper-calibrated with the three parameters raised by 10 %, fitted
from paper-calibrated.

Prints, best of ``--repeat`` runs of each engine (interleaved, in this process, kernels
compiled first):
  * ``batch``: the Jacobian's perturbed runs together on the batch engine
    (:func:`hydroarm.batch.traces.run_traces`, numba prange over the runs);
  * ``serial``: the reference, one :func:`hydroarm.simulate` per trace and evaluation and
    scipy's forward differences (the fit as it was before the batch engine, without its step
    check at every evaluation);
  * for each: wall time, CPU time of this process, model evaluations (parameter vectors) and
    engine runs, and the ratio serial/batch of the wall times; and that both give the same
    estimate.

Run: python benchmarks/fit_speed.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hydroarm as ha  # noqa: E402
from hydroarm.analysis.fit import FitProblem, Trace, model_samples, run_fit  # noqa: E402

PARAMS = ("flow_coefficient", "leakage_coefficient", "trapped_volume")
TIMES = np.arange(0.005, 1.5, 0.005)  # [s]
NOISE_MM = 0.05


def problem() -> FitProblem:
    start = ha.shoulder_elevation()
    truth = start.replace(**{k: getattr(start, k) * 1.1 for k in PARAMS})
    load = ha.paper_load(6)
    shapes = [
        Trace(t=TIMES, values=np.ones_like(TIMES), column="x_mm", load=load, direction=d, name=d)
        for d in ("raise", "lower")
    ]
    clean = [s[:, 1] * 1e3 for s in model_samples([truth], shapes)[0]]
    rng = np.random.default_rng(0)
    traces = tuple(
        Trace(
            t=TIMES,
            values=c + rng.normal(0.0, NOISE_MM, len(TIMES)),
            column="x_mm",
            load=load,
            direction=s.direction,
            name=s.name,
        )
        for c, s in zip(clean, shapes, strict=True)
    )
    return FitProblem(start, PARAMS, traces)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    prob = problem()
    run_fit(prob, engine="batch")  # compile / load the kernels
    best: dict = {}
    for _ in range(a.repeat):
        for engine in ("serial", "batch"):
            w0, c0 = time.perf_counter(), time.process_time()
            res = run_fit(prob, engine=engine)
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            if engine not in best or wall < best[engine][0]:
                best[engine] = (wall, cpu, res)
    print(
        f"3-parameter fit, two 1.5 s traces ({len(TIMES)} samples each), "
        f"{os.cpu_count()} CPUs, numba threads {ha_threads()}"
    )
    for engine in ("serial", "batch"):
        wall, cpu, res = best[engine]
        print(
            f"{engine:>6}: {wall:6.2f} s wall, {cpu:6.2f} s CPU, {res.evaluations} evaluations, "
            f"{res.engine_runs} engine runs"
        )
    ratio = best["serial"][0] / best["batch"][0]
    print(f"serial/batch wall-time ratio: {ratio:.2f}")
    s, b = best["serial"][2], best["batch"][2]
    rel = np.max(np.abs(s.estimate - b.estimate) / b.std_error)
    print(f"estimates agree within {rel:.2g} standard errors:")
    for k, e, se in zip(PARAMS, b.estimate, b.std_error, strict=True):
        print(f"  {k:<22} {e:.6g} ± {se:.2g}")
    return 0


def ha_threads() -> int:
    import numba

    return numba.get_num_threads()


if __name__ == "__main__":
    sys.exit(main())
