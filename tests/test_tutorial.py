"""docs/tutorial-own-servo.md runs as written: every ``hydroarm`` command of its bash blocks,
in order, from a folder with the repository's ``examples/``; each exits 0 and writes what
the text says it writes. The numbers the text quotes are checked against the runs."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial-own-servo.md"
FENCE = re.compile(r"```bash\n(.*?)```", re.S)


def commands() -> list[list[str]]:
    out = []
    for block in FENCE.findall(TUTORIAL.read_text()):
        for line in block.splitlines():
            if line.startswith("hydroarm "):
                out.append(shlex.split(line)[1:])
    return out


def test_tutorial_has_every_step():
    assert [c[0] for c in commands()] == [
        "simulate",
        "expand",
        "linearize",
        "fit",
        "design",
        "fmu",
    ]


@pytest.mark.slow
def test_tutorial_commands_run(tmp_path):
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    printed = {}
    for args in commands():
        r = subprocess.run(
            [sys.executable, "-m", "hydroarm", *args], cwd=tmp_path, capture_output=True, text=True
        )
        assert r.returncode == 0, f"hydroarm {' '.join(args)}: {r.stderr}"
        printed[args[0]] = r.stdout
    for name in ("boom.csv", "boom.png", "boom_circuit.toml", "boom_bode.png", "boom.fmu"):
        assert (tmp_path / name).exists(), name
    assert (tmp_path / "boom_fit" / "fitted.toml").exists()
    assert (tmp_path / "boom_design" / "designs.csv").exists()
    # the overshoot of the gains as built: about 35 mm over the 0.3 m target
    run = pd.read_csv(tmp_path / "boom.csv")
    lift = run[(run.t_s > 0.2) & (run.t_s < 3.0)]
    assert 0.025 < lift.position_m.max() - 0.3 < 0.045
    # linearize: the loop open at rest, K_v = 3.6 1/s at the nearest point with flow
    assert "loop open" in printed["linearize"]
    assert re.search(r"K_v = 3\.6\d* 1/s", printed["linearize"])
    # fit: 4849 ± 390 N*s/m from the synthetic lift (truth 4200)
    m = re.search(r"viscous_friction\s+([\d.]+) ± ([\d.e+]+)", printed["fit"])
    estimate, se = float(m.group(1)), float(m.group(2))
    assert abs(estimate - 4849) < 5 and abs(estimate - 4200) < 2 * se
    # design: 16 candidates, 5 feasible
    assert "16 designs" in printed["design"] and "5 feasible" in printed["design"]
