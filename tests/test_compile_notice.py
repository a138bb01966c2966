"""The compile notice (issue 33): one line on stderr, on a terminal and in a log alike, when a
command is about to wait for numba to compile a kernel its disk cache lacks, naming the
kernel the file's kind runs; nothing when every kernel comes from the cache."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from numba import njit

import hydroarm.integrators.fixed as fixed
import hydroarm.integrators.system as system
import hydroarm.reference.servo_kernel as servo
from hydroarm import cli
from hydroarm.integrators.registry import CompileNotice, kernel_family

ROOT = Path(__file__).resolve().parents[1]
NOTICE = "hydroarm: compiling "


def _event(dispatcher):
    return SimpleNamespace(data={"dispatcher": dispatcher})


def test_the_notice_names_the_kernel_the_file_runs():
    assert kernel_family(system.integrate.py_func.__module__) == "the circuit system kernel"
    assert kernel_family("hydroarm_dispatch_0123abcd") == "the circuit system kernel"
    assert kernel_family("hydroarm.core.tree") == "the mechanism kernels"
    assert kernel_family(servo.integrate.py_func.__module__) == "the reference kernels"
    assert kernel_family(fixed.integrate.py_func.__module__) == "the single-joint kernels"


@pytest.mark.parametrize("tty", [True, False])
def test_one_line_on_a_terminal_and_off_it(tty):
    class Stream(io.StringIO):
        def isatty(self):
            return tty

    err = Stream()
    notice = CompileNotice(lambda: err)
    notice.on_start(_event(system.integrate))  # the first compile: the line
    notice.on_start(_event(fixed.integrate))  # any later one in the same command: none
    lines = err.getvalue().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(NOTICE + "the circuit system kernel for first use")
    assert "hydroarm warmup" in lines[0]


def test_kernels_without_a_disk_cache_are_not_announced():
    # numba's own helpers and functions compiled without cache=True compile in every process:
    # announcing them would print the line on every run
    err = io.StringIO()
    notice = CompileNotice(lambda: err)
    notice.on_start(_event(njit(lambda x: x + 1)))
    notice.on_start(SimpleNamespace(data=None))
    assert err.getvalue() == ""


def test_numba_announces_a_real_compilation_and_not_a_cache_load(tmp_path, monkeypatch):
    """A real numba compile event, on a kernel of a fresh module (compiled in about a second):
    the line while listening, nothing once the code is cached, nothing after remove()."""
    (tmp_path / "fresh_kernel_mod.py").write_text(
        "from numba import njit\n\n\n@njit(cache=True)\ndef twice(x):\n    return 2 * x\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    import fresh_kernel_mod

    err = io.StringIO()
    notice = CompileNotice(lambda: err)
    notice.install()
    try:
        assert fresh_kernel_mod.twice(2) == 4
        assert err.getvalue().startswith(NOTICE + "the simulation kernels for first use")
        notice.install()  # the next command: listening again, nothing said yet
        assert fresh_kernel_mod.twice(3) == 6  # in memory: no compilation
    finally:
        notice.remove()
    assert len(err.getvalue().splitlines()) == 1
    fresh_kernel_mod.twice(2.5)  # a new signature compiles, but nobody listens
    assert len(err.getvalue().splitlines()) == 1


def test_main_listens_only_while_a_command_runs(monkeypatch, capsys):
    # a bad input is reported before any kernel runs: the one error line, no notice, and the
    # listener is gone after main returns (a library call later prints nothing)
    assert cli.main(["simulate", "--load", "99"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("hydroarm: error: --load")
    assert not cli._NOTICE.listening


def _simulate_circuit(cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONUNBUFFERED": "1"}
    env["HYDROARM_COMPILE_NOTICE"] = "1"  # the suite silences it (conftest.py)
    env["HYDROARM_PROGRESS_INTERVAL"] = "1000"  # no progress lines: the notice alone
    return subprocess.run(
        [sys.executable, "-m", "hydroarm", "simulate", "--config",
         str(ROOT / "examples" / "orifice_rig.toml"), "--duration", "2 ms", "--print-every", "1"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=1200,
        cwd=ROOT,
    )  # fmt: skip


@pytest.mark.long  # one to four minutes of compiling: HYDROARM_LONG_TESTS=1 (conftest.py)
def test_a_cold_circuit_simulate_says_so_first_and_a_warm_one_says_nothing(tmp_path):
    """A circuit file with an empty numba cache: the notice names the system kernel and is
    the first thing written (stdout and stderr in one pipe, unbuffered: the order they were
    written in). The same command again, the cache now warm: no notice, the same output.
    The cold run compiles the whole system kernel: one to four minutes on a 2-core machine."""
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    cold = _simulate_circuit(cache)
    assert cold.returncode == 0, cold.stdout[-3000:]
    lines = cold.stdout.splitlines()
    assert lines[0].startswith(NOTICE + "the circuit system kernel for first use"), lines[:3]
    assert sum(line.startswith(NOTICE) for line in lines) == 1
    warm = _simulate_circuit(cache)
    assert warm.returncode == 0, warm.stdout[-3000:]
    assert NOTICE not in warm.stdout
    assert warm.stdout.splitlines() == lines[1:]  # the same table, nothing else
