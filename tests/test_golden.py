"""Golden outputs: refactoring must not move a single published or computed number.

The files in ``tests/data/golden`` were written by hydroarm before the layered architecture
(commit a1d0ec3, the last one with the packed parameter vector): ``table2.csv``,
``table3.csv`` and ``validation.csv`` of ``hydroarm reproduce``, ``arm_validation.csv`` of
``hydroarm arm --config examples/ucl-arm.toml`` and the result file of ``hydroarm sweep
--config examples/throughput.toml`` (gzipped). The comparison is byte for byte: the same
kernels on the same inputs give the same IEEE results, so any difference is a change of
physics or of arithmetic, and must be made on purpose (with the golden file renewed in the
same commit and the reason in CHANGELOG.md). ``arm_validation.csv`` was renewed when the arm
moved onto the system kernel (its mechanism: the coupled inertia and velocity terms, the
pumped power pack; docs/arm.md).
"""

import gzip
from pathlib import Path

import pytest

from hydroarm.arm import load_arm
from hydroarm.batch.sweep import load_sweep, run_sweep
from hydroarm.files import csv_text
from hydroarm.paper.arm_validation import validation_rows

GOLDEN = Path(__file__).parent / "data" / "golden"
EXAMPLES = Path(__file__).parents[1] / "examples"


@pytest.mark.parametrize("name", ["table2.csv", "table3.csv", "validation.csv"])
def test_reproduce_files_unchanged(repro, name):
    out, _ = repro
    assert (out / name).read_text() == (GOLDEN / name).read_text()


@pytest.mark.slow
def test_arm_validation_unchanged():
    rows = validation_rows(load_arm(EXAMPLES / "ucl-arm.toml"))
    text = csv_text(["quantity", "measured", "model", "rel_error"], rows)
    assert text == (GOLDEN / "arm_validation.csv").read_text()


@pytest.mark.slow
def test_throughput_sweep_unchanged(tmp_path):
    out = run_sweep(load_sweep(EXAMPLES / "throughput.toml"), tmp_path / "tp.csv")
    with gzip.open(GOLDEN / "throughput_sweep.csv.gz", "rt") as fh:
        expected = fh.read()
    assert Path(out).read_text() == expected
