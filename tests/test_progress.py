"""Progress off a terminal: a line at most every HYDROARM_PROGRESS_INTERVAL seconds."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

from hydroarm.io.progress import Progress, interval

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_off_a_terminal_lines_are_throttled(monkeypatch):
    buf = io.StringIO()  # not a terminal
    monkeypatch.setenv("HYDROARM_PROGRESS_INTERVAL", "1000")
    p = Progress(3, stream=buf)
    p("a")
    p("b")
    assert buf.getvalue() == ""  # a short command stays quiet
    monkeypatch.setenv("HYDROARM_PROGRESS_INTERVAL", "0")
    p = Progress(2, stream=buf)
    p("a")
    p("b")
    assert buf.getvalue().splitlines() == [
        line for line in buf.getvalue().splitlines() if line.startswith("[")
    ]
    assert len(buf.getvalue().splitlines()) == 2


def test_interval_setting(monkeypatch):
    monkeypatch.setenv("HYDROARM_PROGRESS_INTERVAL", "2.5")
    assert interval() == 2.5
    monkeypatch.setenv("HYDROARM_PROGRESS_INTERVAL", "soon")
    assert interval() == 15.0


def test_a_sweep_off_a_terminal_reports_progress(tmp_path):
    """A sweep run with its stderr in a pipe (as in CI or a batch job) writes periodic
    progress lines there when the interval is 0."""
    env = {"HYDROARM_PROGRESS_INTERVAL": "0", "PATH": "/usr/bin:/bin"}
    import os

    env = {**os.environ, **env}
    r = subprocess.run(
        [sys.executable, "-m", "hydroarm", "sweep", "--config",
         str(EXAMPLES / "counterbalance_study.toml"), "--out", str(tmp_path / "s.csv"),
         "--chunk", "4"],
        capture_output=True, text=True, env=env, timeout=600,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    lines = [x for x in r.stderr.splitlines() if x.startswith("sweep: ")]
    assert lines and lines[-1].startswith("sweep: 3/3 chunks"), r.stderr
