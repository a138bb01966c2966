"""Speed of the paper's calibrations as fit files against references measured in the same run
(issue 16).

Prints (wall time, kernels compiled first):
  * the reference: one evaluation of all the targets of ``fit_table1.toml`` for one joint
    (four saturation tests on the batch engine, the gearbox loss at stall solved for the
    stall) and for three joints together (a Jacobian's points);
  * the Table III fit (``fit_table3.toml``: four velocities, K and L) and the Table I fit
    (``fit_table1.toml`` without its leave-one-out), their model evaluations and their time
    in units of the one-joint evaluation;
  * with ``--three-parameters``: the Table I fit with the gearbox loss at stall fitted as a
    third parameter against the stall target instead of solved (the formulation docs/fit.md
    explains it does not use: same optimum, a valley; about a minute).

Run: python benchmarks/fit_targets.py [--three-parameters]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hydroarm.analysis.fit import run_fit  # noqa: E402
from hydroarm.analysis.targets import target_residuals  # noqa: E402
from hydroarm.paper.calibration import paper_fit_problem  # noqa: E402


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--three-parameters", action="store_true")
    a = ap.parse_args(argv)
    t1 = replace(paper_fit_problem("fit_table1"), leave_one_out=False)
    t3 = paper_fit_problem("fit_table3")
    start = t1.start()
    target_residuals(t1.joints_at([start]), t1.targets, t1.met)  # compile, warm the guesses
    _, one = timed(lambda: target_residuals(t1.joints_at([start]), t1.targets, t1.met))
    pts = [start * (1 + 1e-4 * k) for k in range(3)]
    _, three = timed(lambda: target_residuals(t1.joints_at(pts), t1.targets, t1.met))
    print(f"reference: Table I targets of 1 joint {one:.2f} s, of 3 joints together {three:.2f} s")
    for name, prob in (("Table III", t3), ("Table I", t1)):
        res, dt = timed(lambda prob=prob: run_fit(prob))
        print(
            f"{name} fit: {res.evaluations} joint evaluations, {dt:.2f} s "
            f"({dt / one:.1f} x one Table I evaluation), chi2 {res.chi2:.3f}"
        )
    if a.three_parameters:
        p3 = replace(
            t1,
            parameters=(*t1.parameters, "gearbox_loss_at_stall"),
            solves=(),
            initial={**t1.initial, "gearbox_loss_at_stall": 0.96},
            bounds={**t1.bounds, "gearbox_loss_at_stall": (0.0, 0.99)},
        )
        res, dt = timed(lambda: run_fit(p3))
        print(
            f"Table I fit, c_stall fitted (3 parameters): {res.evaluations} joint evaluations, "
            f"{dt:.2f} s ({dt / one:.1f} x one evaluation), chi2 {res.chi2:.3f}"
        )


if __name__ == "__main__":
    main()
