"""Sweeps on a Dask scheduler started as a separate process on 127.0.0.1 (not a LocalCluster):
the result file is byte-identical to the local run, also when a worker is killed mid-sweep."""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hydroarm.cli import main

pytest.importorskip("dask.distributed")

pytestmark = pytest.mark.slow

CONFIG = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "raise"
[scenario.solver]
duration = "0.6 s"
[monte_carlo]
n = {n}
seed = 5
weight = {{ distribution = "normal", relative_sd = 0.1 }}
flow_coefficient = {{ distribution = "uniform", relative = 0.1 }}
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def hydroarm(*args, **kw):
    return subprocess.run(
        [sys.executable, "-m", "hydroarm.cli", *args], capture_output=True, text=True, **kw
    )


def start(*args) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


def wait_for_port(port: int, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.2)
    raise TimeoutError(f"no scheduler on port {port}")


@pytest.fixture
def scheduler():
    """A scheduler and two single-threaded workers, each its own process."""
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [
        start(
            "distributed.cli.dask_scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--no-dashboard",
        )
    ]
    wait_for_port(port)
    workers = [
        start("distributed.cli.dask_worker", address, "--nthreads", "1", "--no-dashboard")
        for _ in range(2)
    ]
    procs += workers
    try:
        yield address, workers
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGKILL)
            p.wait()


def sweep_files(tmp_path: Path, n: int) -> Path:
    cfg = tmp_path / "sweep.toml"
    cfg.write_text(CONFIG.format(n=n))
    return cfg


def local_sweep(cfg: Path, out: Path) -> None:
    """The local run to compare with, `hydroarm sweep` run in this process: the reference
    file needs no process of its own (the Dask runs, which do, stay separate processes)."""
    assert main(["sweep", "--config", str(cfg), "--out", str(out)]) == 0


def test_separate_scheduler_matches_local(tmp_path, scheduler):
    address, _ = scheduler
    cfg = sweep_files(tmp_path, 64)
    local_sweep(cfg, tmp_path / "local.csv")
    run = hydroarm(
        "sweep",
        "--config",
        str(cfg),
        "--out",
        str(tmp_path / "dask.csv"),
        "--chunk",
        "8",
        "--executor",
        "dask",
        "--scheduler",
        address,
    )
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "local.csv").read_bytes()


def test_worker_killed_mid_sweep(tmp_path, scheduler):
    """One of two workers is killed while the sweep runs: Dask re-runs its chunks on the
    other, and the file is still identical to the local run."""
    address, workers = scheduler
    cfg = sweep_files(tmp_path, 256)
    local_sweep(cfg, tmp_path / "local.csv")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "hydroarm.cli",
            "sweep",
            "--config",
            str(cfg),
            "--out",
            str(tmp_path / "dask.csv"),
            "--chunk",
            "4",
            "--executor",
            "dask",
            "--scheduler",
            address,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    parts = tmp_path / "dask.csv.parts"
    end = time.monotonic() + 120
    while not list(parts.glob("chunk_*.npy")) and time.monotonic() < end:
        time.sleep(0.05)  # wait until the first chunks are done
    assert proc.poll() is None, "the sweep ended before a worker could be killed"
    os.killpg(workers[0].pid, signal.SIGKILL)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "local.csv").read_bytes()
