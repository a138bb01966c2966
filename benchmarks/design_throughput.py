"""Throughput of `hydroarm design` against running the same scenarios one by one.

Workload: examples/redesign_shoulder.toml cut to ``--samples`` Sobol designs, no refinement
(2 load cases x 2 directions = 4 saturation tests per design, and the stall-mass search).

- ``design``: the command in a fresh process (``python -m hydroarm.cli design``), timed from
  the process start to its end: start-up (imports, loading the compiled kernels, reading the
  file) included; every design's saturation tests on the batch engine.
- one by one: the same designs (read back from designs.csv, every digit) in this process,
  each saturation test through ``hydroarm.simulate(...).metric_values()`` and each stall mass
  through ``stall_mass``, after a warm-up (compiled code loaded), so this side gets no
  start-up cost.

Both report the saturation tests (designs x cases x directions) per second, and the ratios
of the one-by-one time to the command's (everything), to the study's (the time in its
report: from the command's start to the end of the evaluation) and to the evaluation alone.
The stall-mass search (bisection on single simulations, the same on both sides but two
joints at a time in ``design``) is timed apart; ``--no-stall`` leaves it out of the design
(requirements without stall_mass) to time the batch engine alone. The worst-case values of
both sides are checked equal.

Run: python benchmarks/design_throughput.py [--samples 64] [--no-stall]
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import hydroarm as ha  # noqa: E402
from hydroarm.analysis import requirements as R  # noqa: E402
from hydroarm.analysis.design import read_design_file  # noqa: E402
from hydroarm.batch.saturation import stall_mass  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=64)
    ap.add_argument("--no-stall", action="store_true")
    a = ap.parse_args()
    text = (ROOT / "examples" / "redesign_shoulder.toml").read_text()
    if a.no_stall:
        text = text.replace('stall_mass = ">= 1 kg"', "").replace('"max stall_mass", ', "")
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "design.toml"
        cfg.write_text(text)
        out = Path(tmp) / "out"
        cmd = [sys.executable, "-m", "hydroarm.cli", "design", "--config", str(cfg)]
        cmd += ["--out", str(out), "--samples", str(a.samples), "--no-refine"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, cwd=tmp)
        t_design = time.perf_counter() - t0
        rows = list(csv.DictReader(open(out / "designs.csv")))
        report = (out / "design_report.md").read_text()
    m = re.search(r"Time: ([\d.]+) s in all, start-up included \(([\d.]+) s evaluating", report)
    assert m is not None
    t_study, t_eval = float(m.group(1)), float(m.group(2))
    study = read_design_file(cfg_text_path(text), samples=a.samples, refine=False)
    names = [v.name for v in study.variables]
    cols = [next(k for k in rows[0] if k == n or k.startswith(n + "_")) for n in names]
    joints = [
        study.joint.replace(**{n: float(r[c]) for n, c in zip(names, cols, strict=True)})
        for r in rows
    ]
    motions = sum(len(c.directions) for c in study.cases)
    n_tests = len(joints) * motions
    # warm-up: load the compiled kernels in this process
    ha.simulate(ha.saturation_test(joints[0], study.cases[0].load, "raise")).metrics()
    t0 = time.perf_counter()
    alone = []
    for j in joints:
        m: dict = {}
        for c in study.cases:
            for d in c.directions:
                sc = ha.saturation_test(j, c.load, d, duration=R.motion_duration(j))
                m[(c.name, d)] = R.motion_values(j, sc, ha.simulate(sc).metric_values(), None)
        alone.append(m)
    t_single = time.perf_counter() - t0
    t_stall = 0.0
    if not a.no_stall:
        t0 = time.perf_counter()
        for j, m in zip(joints, alone, strict=True):
            m[(None, None)] = {"stall_mass": stall_mass(j)}
        t_stall = time.perf_counter() - t0
    same = all(
        f"{R.worst(r, m):.6g}" == row[k]
        for m, row in zip(alone, rows, strict=True)
        for r, k in zip(study.requirements, _worst_columns(rows[0], study), strict=True)
    )
    print(
        f"{len(joints)} designs x {motions} saturation tests = {n_tests} tests"
        + ("" if a.no_stall else " + the stall-mass search of each design")
    )
    print(
        f"design command (fresh process: Python start-up, imports, kernels loaded, plots and "
        f"files included): {t_design:.2f} s, {n_tests / t_design:.3g} tests/s"
    )
    print(
        f"design study (its report: from the command's start, files not included): "
        f"{t_study:.2f} s, {n_tests / t_study:.3g} tests/s; evaluating {t_eval:.2f} s"
    )
    one = t_single + t_stall
    print(
        f"one by one (warm, this process): {one:.2f} s ({t_single:.2f} s simulate, "
        f"{t_stall:.2f} s stall mass), {n_tests / one:.3g} tests/s"
    )
    print(
        f"ratio one-by-one time / design time: command {one / t_design:.2f}x, study "
        f"{one / t_study:.2f}x, evaluation {one / t_eval:.2f}x; worst values equal: {same}"
    )


def cfg_text_path(text: str) -> Path:
    p = Path(tempfile.mkdtemp()) / "design.toml"
    p.write_text(text)
    return p


def _worst_columns(row: dict, study) -> list[str]:
    return [next(k for k in row if k.startswith(f"worst_{r.metric}")) for r in study.requirements]


if __name__ == "__main__":
    main()
