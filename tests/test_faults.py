"""Faults the user can cause or meet (issue 20): bad output paths checked before any work, a
full disk, broken or busy sweep folders, stale staging folders, interruptions (SIGINT,
SIGTERM, SIGKILL), an unreachable Dask scheduler and jobs too large to run. Each gives one
line ``hydroarm: error: ...`` (exit 2) or ``hydroarm: interrupted`` (exit 130) and leaves
nothing half-written."""

import errno
import os
import pickle
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from test_arm import SMALL

from hydroarm import cli, files
from hydroarm.batch.sweep import load_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.errors import HydroarmError

ROOT = Path(__file__).resolve().parents[1]

SWEEP = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "lower"
[scenario.solver]
duration = "{duration}"
[grid]
weight = {{ start = "10 N", stop = "20 N", num = {num} }}
"""


def _tree(d: Path) -> set:
    return {str(p.relative_to(d)) for p in d.rglob("*")}


def _err_lines(capsys) -> list[str]:
    return capsys.readouterr().err.strip().splitlines()


def _sweep_cfg(tmp_path, duration="0.2 s", num=6) -> Path:
    cfg = tmp_path / "s.toml"
    cfg.write_text(SWEEP.format(duration=duration, num=num))
    return cfg


# ------------------------------------------------------------ output paths ---
SIM = ["simulate", "--load", "1", "--direction", "raise", "--duration", "0.05 s"]

# (name, command after the placeholders are filled, the text the error line must contain)
OUTPUT_CASES = [
    ("simulate-out-folder", [*SIM, "--out", "{d}"], "{d} is a folder"),
    ("simulate-out-empty", [*SIM, "--out", ""], "--out: is empty"),
    ("simulate-out-under-file", [*SIM, "--out", "{f}/x.csv"], "{f} is a file"),
    ("simulate-out-missing-parents", [*SIM, "--out", "{d}/a/b/c/x.csv"], "does not exist"),
    ("simulate-plot-folder", [*SIM, "--plot", "{d}"], "--plot: {d} is a folder"),
    ("simulate-plot-under-file", [*SIM, "--plot", "{f}/p.png"], "--plot: {f}/p.png"),
    ("sweep-out-folder", ["sweep", "--config", "{cfg}", "--out", "{d}/r.csv"], "is a folder"),
    ("sweep-out-under-file", ["sweep", "--config", "{cfg}", "--out", "{f}/r.csv"], "is a file"),
    ("sweep-out-empty", ["sweep", "--config", "{cfg}", "--out", ""], "--out: is empty"),
    ("reproduce-out-file", ["reproduce", "--out", "{f}"], "{f} exists and is not a folder"),
    ("reproduce-out-under-file", ["reproduce", "--out", "{f}/r"], "{f} is a file"),
    ("reproduce-missing-parents", ["reproduce", "--out", "{d}/a/b/r"], "does not exist"),
    ("validate-out-empty", ["validate", "--out", ""], "--out: is empty"),
    ("validate-out-under-file", ["validate", "--out", "{f}/v"], "{f} is a file"),
    ("arm-out-file", ["arm", "--config", "{cfg}", "--out", "{f}"], "is not a folder"),
    ("arm-missing-parents", ["arm", "--config", "{cfg}", "--out", "{d}/x/y/z"], "does not exist"),
]


@pytest.mark.parametrize(
    "argv, expected", [c[1:] for c in OUTPUT_CASES], ids=[c[0] for c in OUTPUT_CASES]
)
def test_bad_output_path_refused_before_work(tmp_path, capsys, argv, expected):
    d = tmp_path / "work"
    d.mkdir()
    (d / "r.csv").mkdir()  # a folder where the sweep wants a file
    f = tmp_path / "plain.txt"
    f.write_text("x")
    cfg = _sweep_cfg(tmp_path)
    fill = {"d": str(d), "f": str(f), "cfg": str(cfg)}
    before = _tree(tmp_path)
    t0 = time.perf_counter()
    assert main([a.format(**fill) for a in argv]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1, err
    assert err[0].startswith("hydroarm: error: ") and expected.format(**fill) in err[0], err
    assert _tree(tmp_path) == before  # nothing made, nothing half-written
    assert time.perf_counter() - t0 < 5  # refused before any simulation


def test_unwritable_output_folder(tmp_path, capsys, monkeypatch):
    # root ignores permissions: the check asks os.access, so ask it to say no
    locked = tmp_path / "locked"
    locked.mkdir()
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, m: False if Path(p) == locked else real(p, m))
    assert main([*SIM, "--out", str(locked / "x.csv")]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1 and str(locked) in err[0] and "permission denied" in err[0]
    assert main(["reproduce", "--out", str(locked)]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1 and "permission denied" in err[0]
    assert _tree(tmp_path) == {"locked"}


def test_missing_output_folder_made_one_level_only(tmp_path):
    assert files.check_output_folder("--out", tmp_path / "new") == tmp_path / "new"
    with pytest.raises(HydroarmError, match="does not exist"):
        files.check_output_folder("--out", tmp_path / "a" / "new")
    with pytest.raises(HydroarmError, match="does not exist"):
        files.check_output_folder("--out", tmp_path / "new", create=False)
    assert _tree(tmp_path) == set()


# --------------------------------------------------------------- full disk ---
def _enospc(*a, **k):
    raise OSError(errno.ENOSPC, "No space left on device")


def test_full_disk_while_writing_simulate_output(tmp_path, capsys, monkeypatch):
    real_fdopen = os.fdopen

    class Full:
        def __init__(self, fh):
            self.fh = fh

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

        def write(self, data):
            self.fh.write(data[: len(data) // 2])
            self.fh.flush()
            _enospc()

    monkeypatch.setattr(os, "fdopen", lambda fd, mode: Full(real_fdopen(fd, mode)))
    out = tmp_path / "x.csv"
    assert main([*SIM, "--out", str(out)]) == 2
    err = _err_lines(capsys)
    # the option that named the file, then the file (issue 31)
    assert err == [f"hydroarm: error: --out: {out}: cannot write: no space left on the device"]
    assert _tree(tmp_path) == set()  # the temporary file is gone


@pytest.mark.parametrize("exc", [errno.EACCES, errno.EROFS])
def test_atomic_write_errors_name_the_path(tmp_path, monkeypatch, exc):
    def fail(*a, **k):
        raise OSError(exc, os.strerror(exc))

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(HydroarmError) as e:
        files.atomic_write_text(tmp_path / "a.txt", "x")
    assert str(tmp_path / "a.txt") in str(e.value) and "\n" not in str(e.value)
    assert _tree(tmp_path) == set()


def test_full_disk_in_sweep_chunk_leaves_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("hydroarm.batch.sweep.np.save", _enospc)
    out = tmp_path / "r.csv"
    cfg = _sweep_cfg(tmp_path)
    assert main(["sweep", "--config", str(cfg), "--out", str(out), "--chunk", "2"]) == 2
    err = _err_lines(capsys)
    assert err[-1].startswith("hydroarm: error: ") and "no space left" in err[-1]
    assert sum(line.startswith("hydroarm:") for line in err) == 1
    assert _tree(tmp_path) == {"s.toml"}  # no parts folder, no temporary file


def test_full_disk_writing_sweep_result_keeps_resumable_chunks(tmp_path, capsys, monkeypatch):
    cfg = _sweep_cfg(tmp_path)
    ref = tmp_path / "ref.csv"
    assert main(["sweep", "--config", str(cfg), "--out", str(ref), "--chunk", "2"]) == 0

    def half_then_full(tmp, out, sw, cols):
        tmp.write_text("scenario,wei")
        _enospc()

    monkeypatch.setattr("hydroarm.batch.sweep._write_file", half_then_full)
    out = tmp_path / "r.csv"
    capsys.readouterr()
    assert main(["sweep", "--config", str(cfg), "--out", str(out), "--chunk", "2"]) == 2
    err = _err_lines(capsys)
    assert err[-1].startswith(f"hydroarm: error: {out}: cannot write: no space left")
    assert "--resume" in err[-1]
    assert not out.exists() and not (tmp_path / ".r.csv.tmp").exists()
    assert len(list((tmp_path / "r.csv.parts").glob("chunk_*.npy"))) == 3  # kept on purpose
    monkeypatch.undo()
    argv = ["sweep", "--config", str(cfg), "--out", str(out), "--chunk", "2", "--resume"]
    assert main(argv) == 0
    assert out.read_bytes() == ref.read_bytes()
    assert not (tmp_path / "r.csv.parts").exists()


# ----------------------------------------------------------- sweep folder ---
@pytest.mark.parametrize("manifest", ["", "{", "null", "{}"], ids=["empty", "cut", "null", "{}"])
def test_empty_or_corrupt_manifest_starts_afresh(tmp_path, manifest):
    sw = load_sweep(_sweep_cfg(tmp_path))
    run_sweep(sw, tmp_path / "ref.csv", chunk=2)
    parts = tmp_path / "r.csv.parts"
    parts.mkdir()
    (parts / "manifest.json").write_text(manifest)
    (parts / "chunk_000000.npy").write_bytes(b"junk of a sweep that cannot be trusted")
    for resume in (False, True):
        run_sweep(sw, tmp_path / "r.csv", chunk=2, resume=resume)
        assert (tmp_path / "r.csv").read_bytes() == (tmp_path / "ref.csv").read_bytes()
        assert not parts.exists()
        parts.mkdir()
        (parts / "manifest.json").write_text(manifest)


def test_manifest_written_atomically(tmp_path, monkeypatch):
    sw = load_sweep(_sweep_cfg(tmp_path))
    monkeypatch.setattr(os, "replace", _enospc)  # the disk fills as the manifest is written
    with pytest.raises(HydroarmError, match="no space left"):
        run_sweep(sw, tmp_path / "r.csv", chunk=2)
    assert _tree(tmp_path) == {"s.toml"}
    monkeypatch.undo()
    run_sweep(sw, tmp_path / "r.csv", chunk=2)  # nothing locks the sweep
    assert (tmp_path / "r.csv").exists()


def test_second_sweep_on_a_busy_parts_folder(tmp_path, capsys):
    cfg = _sweep_cfg(tmp_path)
    parts = tmp_path / "r.csv.parts"
    parts.mkdir()
    fd = files.try_lock(parts)  # a sweep running in another process holds this lock
    try:
        for extra in ([], ["--resume"]):
            argv = ["sweep", "--config", str(cfg), "--out", str(tmp_path / "r.csv"), *extra]
            assert main(argv) == 2
            err = _err_lines(capsys)
            assert err[-1].startswith("hydroarm: error: --out: ") and "in use" in err[-1]
        assert _tree(tmp_path) == {"s.toml", "r.csv.parts"}
    finally:
        files.unlock(fd)


# --------------------------------------------------------- staging folders ---
def test_stale_staging_folder_removed_live_one_kept(tmp_path):
    stale = tmp_path / (files.STAGE_PREFIX + "out-dead")
    stale.mkdir()
    (stale / "joints.csv").write_text("half")
    old = tmp_path / ".hydroarm-arm-abc123"  # left by an older hydroarm
    old.mkdir()
    live = tmp_path / (files.STAGE_PREFIX + "out-live")
    live.mkdir()
    fd = files.try_lock(live)
    try:
        with files.staging_folder(tmp_path / "out") as stage:
            assert stage.is_dir() and stage.name.startswith(files.STAGE_PREFIX + "out-")
            assert not stale.exists() and not old.exists() and live.exists()
            (stage / "a.txt").write_text("a")
            files.move_into(stage, tmp_path / "out", ["a.txt"])
        assert not stage.exists()
    finally:
        files.unlock(fd)
    assert _tree(tmp_path) == {"out", "out/a.txt", live.name}


def test_staging_folder_of_a_killed_process_removed_on_next_run(tmp_path):
    code = (
        "import sys, time; from pathlib import Path; from hydroarm import files\n"
        "with files.staging_folder(Path(sys.argv[1])) as s:\n"
        "    print(s, flush=True); time.sleep(60)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen(
        [sys.executable, "-c", code, str(tmp_path / "out")],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    stage = Path(p.stdout.readline().strip())
    assert stage.is_dir()
    assert files.remove_stale_stages(tmp_path) == []  # alive: kept
    p.kill()
    p.wait()
    assert stage.is_dir()  # SIGKILL: nothing cleans up ...
    assert files.remove_stale_stages(tmp_path) == [stage]  # ... until the next run
    assert _tree(tmp_path) == set()


# ------------------------------------------------------------ interruptions ---
def _start_sweep(tmp_path, out, *extra):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HYDROARM_DEBUG", None)
    cfg = _sweep_cfg(tmp_path, duration="2 s", num=40)
    argv = ["sweep", "--config", str(cfg), "--out", str(out), "--chunk", "1", *extra]
    return subprocess.Popen(
        [sys.executable, "-m", "hydroarm.cli", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    ), argv


def _wait_for_chunks(parts: Path, p, k=1, timeout=120):
    t0 = time.monotonic()
    while len(list(parts.glob("chunk_*.npy"))) < k:
        assert p.poll() is None, p.communicate()
        assert time.monotonic() - t0 < timeout
        time.sleep(0.02)


@pytest.fixture(scope="module")
def reference_sweep(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    sw = load_sweep(_sweep_cfg(d, duration="2 s", num=40))
    return run_sweep(sw, d / "ref.csv", chunk=1).read_bytes()


@pytest.mark.slow
@pytest.mark.parametrize(
    "sig, executor",
    [(signal.SIGINT, "local"), (signal.SIGTERM, "local"), (signal.SIGINT, "dask")],
    ids=["SIGINT", "SIGTERM", "SIGINT-dask"],
)
def test_signal_during_sweep_then_resume(tmp_path, reference_sweep, sig, executor):
    if executor == "dask":
        pytest.importorskip("distributed")
    out = tmp_path / "r.csv"
    p, argv = _start_sweep(tmp_path, out, "--executor", executor)
    _wait_for_chunks(tmp_path / "r.csv.parts", p)
    p.send_signal(sig)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    lines = [line for line in err.splitlines() if line.startswith("hydroarm")]
    assert len(lines) == 1 and lines[0].startswith("hydroarm: interrupted"), err
    assert "Traceback" not in err and "--resume" in lines[0]
    assert not out.exists() and not (tmp_path / ".r.csv.tmp").exists()
    assert main([*argv, "--resume"]) == 0
    assert out.read_bytes() == reference_sweep
    assert _tree(tmp_path) == {"s.toml", "r.csv"}


@pytest.mark.slow
def test_sigterm_at_start_of_sweep(tmp_path):
    # during start-up: the first chunk's compilation or loading of compiled code
    out = tmp_path / "r.csv"
    p, _ = _start_sweep(tmp_path, out)
    t0 = time.monotonic()
    while not (tmp_path / "r.csv.parts").exists():  # the command has started
        assert p.poll() is None and time.monotonic() - t0 < 60
        time.sleep(0.01)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("hydroarm: interrupted"), err
    assert "Traceback" not in err
    if "nothing kept" in err:
        assert _tree(tmp_path) == {"s.toml"}


@pytest.mark.slow
def test_sigkill_during_sweep_then_resume(tmp_path, reference_sweep):
    out = tmp_path / "r.csv"
    p, argv = _start_sweep(tmp_path, out)
    _wait_for_chunks(tmp_path / "r.csv.parts", p, k=2)
    p.kill()
    p.wait()
    assert main([*argv, "--resume"]) == 0  # the lock died with the process
    assert out.read_bytes() == reference_sweep
    assert _tree(tmp_path) == {"s.toml", "r.csv"}


def _wait_for_main(p, timeout=120):
    """Until the command in ``p`` has installed hydroarm's SIGTERM handler: its imports are
    over and `main` runs (a fixed wait was too short on a busy machine: the signal landed
    in the import, a traceback). Read from the process's caught-signal mask on Linux;
    elsewhere a fixed wait."""
    status = Path(f"/proc/{p.pid}/status")
    if not status.exists():
        time.sleep(6)
        return
    t0 = time.monotonic()
    while True:
        caught = [
            ln.split()[1] for ln in status.read_text().splitlines() if ln.startswith("SigCgt:")
        ]
        if int(caught[0], 16) >> (signal.SIGTERM - 1) & 1:
            return
        assert p.poll() is None and time.monotonic() - t0 < timeout
        time.sleep(0.05)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_inside_a_long_compiled_kernel(tmp_path, sig):
    # one long numba call: Python's handler cannot run until it returns
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    # the longest run allowed (10⁸ steps: 1000 s at 10 µs), about 10 s of compiled work
    argv = [*SIM[:-1], "1000 s", "--print-every", "1000000", "--out", str(tmp_path / "x.csv")]
    p = subprocess.Popen(
        [sys.executable, "-m", "hydroarm.cli", *argv],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    _wait_for_main(p)
    time.sleep(2)  # the input read, the kernel loaded from numba's cache: inside its 10 s
    assert p.poll() is None
    t0 = time.monotonic()
    p.send_signal(sig)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130 and err.splitlines() == ["hydroarm: interrupted"], err
    assert time.monotonic() - t0 < 10
    assert _tree(tmp_path) == set()


def test_keyboard_interrupt_inside_compiled_code_is_an_interruption(capsys, monkeypatch):
    def compiled(a):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise SystemError("integrate returned a result with an error set")  # noqa: B904

    monkeypatch.setattr(cli, "cmd_params", compiled)
    assert main(["params"]) == 130
    assert _err_lines(capsys) == ["hydroarm: interrupted"]


def test_swallowed_signal_still_exits_130(capsys, monkeypatch):
    def swallowing(a):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)
        except KeyboardInterrupt:
            pass  # e.g. a library that catches everything
        return 0

    monkeypatch.setattr(cli, "cmd_params", swallowing)
    before = signal.getsignal(signal.SIGTERM)
    assert main(["params"]) == 130
    assert _err_lines(capsys) == ["hydroarm: interrupted"]
    assert signal.getsignal(signal.SIGTERM) == before  # main() put it back


# ------------------------------------------------------------------- Dask ---
def test_scheduler_not_an_address(tmp_path, capsys):
    cfg = _sweep_cfg(tmp_path)
    out = str(tmp_path / "r.csv")
    for bad in ("not an address", "tcp://", "host:99999"):
        argv = ["sweep", "--config", str(cfg), "--out", out, "--executor", "dask"]
        assert main([*argv, "--scheduler", bad]) == 2
        err = _err_lines(capsys)
        assert err[-1].startswith("hydroarm: error: --scheduler: ") and "not a scheduler" in err[-1]
    assert main(["sweep", "--config", str(cfg), "--out", out, "--scheduler", "host:8786"]) == 2
    assert _err_lines(capsys)[-1] == "hydroarm: error: --scheduler: needs --executor dask"
    assert _tree(tmp_path) == {"s.toml"}


def test_scheduler_that_does_not_answer(tmp_path, capsys):
    pytest.importorskip("distributed")
    with socket.socket() as s:  # a free port: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cfg = _sweep_cfg(tmp_path)
    argv = ["sweep", "--config", str(cfg), "--out", str(tmp_path / "r.csv"), "--executor", "dask"]
    t0 = time.perf_counter()
    assert main([*argv, "--scheduler", f"127.0.0.1:{port}"]) == 2
    assert time.perf_counter() - t0 < 20
    err = _err_lines(capsys)
    assert err[-1] == (
        f"hydroarm: error: --scheduler: cannot reach tcp://127.0.0.1:{port} (no answer within 5 s)"
    )
    assert sum(line.startswith("hydroarm:") for line in err) == 1
    assert _tree(tmp_path) == {"s.toml"}


# --------------------------------------------------------------- job size ---
def test_records_that_do_not_fit_in_memory_refused_up_front(capsys, monkeypatch):
    t0 = time.perf_counter()
    # a run too long for any machine: refused when the scenario is read, by its steps
    assert main(["simulate", "--load", "1", "--direction", "raise", "--duration", "1e7 s"]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1 and err[0].startswith("hydroarm: error: --duration: ")
    assert "at most 1e+08" in err[0]
    # a run within the step limit whose records do not fit this (pretend small) machine
    monkeypatch.setattr("hydroarm.cli.memory_limit", lambda: 10**6)
    assert main(["simulate", "--load", "1", "--direction", "raise", "--duration", "10 s"]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1 and err[0].startswith("hydroarm: error: --duration: ")
    assert "GB of memory" in err[0] and "--print-every" in err[0]
    assert time.perf_counter() - t0 < 5


HUGE_SWEEP = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "lower"
[scenario.solver]
duration = "900 s"
[monte_carlo]
n = 20000
seed = 1
weight = { distribution = "normal", relative_sd = 0.05 }
"""


def test_huge_sweep_refused_without_force(tmp_path, capsys):
    cfg = tmp_path / "s.toml"
    cfg.write_text(HUGE_SWEEP)  # 2·10⁴ scenarios x 9·10⁷ steps = 1.8·10¹² scenario-steps
    assert main(["sweep", "--config", str(cfg), "--out", str(tmp_path / "r.csv")]) == 2
    err = _err_lines(capsys)
    assert len(err) == 1, err
    assert err[0].startswith("hydroarm: error: --config: ") and "--force" in err[0]
    assert "1.8e+12" in err[0]
    assert _tree(tmp_path) == {"s.toml"}


# `hydroarm ARGV` in a real interpreter, its main() as `python -m hydroarm.cli` runs it, with
# reproduce's validation step answered from a pickle (see _start_reproduce)
WITH_VALIDATION = (
    "import pickle, sys\n"
    "import hydroarm.paper.validate as v\n"
    "with open(sys.argv[1], 'rb') as fh:\n"
    "    result = pickle.load(fh)\n"
    "v.compute = lambda **kw: result\n"
    "from hydroarm.cli import main\n"
    "sys.exit(main(sys.argv[2:]))\n"
)


def _start_staging(tmp_path, argv, staged_file, validation=None):
    """Start `hydroarm ARGV` and return once its staging folder holds ``staged_file``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HYDROARM_DEBUG", None)
    command = ["-m", "hydroarm.cli"] if validation is None else ["-c", WITH_VALIDATION, validation]
    p = subprocess.Popen(
        [sys.executable, *command, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    t0 = time.monotonic()
    while not list(tmp_path.glob(f"{files.STAGE_PREFIX}*/{staged_file}")):  # staging under way
        assert p.poll() is None, p.communicate()
        assert time.monotonic() - t0 < 120
        time.sleep(0.02)
    return p


def _start_arm(tmp_path):
    cfg = tmp_path / "arm.toml"
    cfg.write_text(SMALL)
    argv = ["arm", "--config", str(cfg), "--out", str(tmp_path / "o")]
    return _start_staging(tmp_path, argv, "joints.csv"), argv


@pytest.mark.slow
def test_sigint_during_arm_staging(tmp_path):
    p, _ = _start_arm(tmp_path)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert err.strip().splitlines() == ["hydroarm: interrupted"]
    assert _tree(tmp_path) == {"arm.toml"}  # staging removed, no output folder


@pytest.mark.slow
def test_sigkill_during_arm_staging_then_rerun(tmp_path, capsys):
    p, argv = _start_arm(tmp_path)
    p.kill()
    p.wait()
    assert len(list(tmp_path.glob(files.STAGE_PREFIX + "*"))) == 1  # left by the SIGKILL
    assert main([*argv, "--no-animation"]) == 0
    assert not list(tmp_path.glob(files.STAGE_PREFIX + "*"))  # removed by the next run
    assert (tmp_path / "o" / "joints.csv").exists()


def _start_reproduce(tmp_path, out, validation):
    return _start_staging(tmp_path, ["reproduce", "--out", str(out)], "table3.csv", validation)


@pytest.fixture
def validation_pickle(reuse_validation, tmp_path_factory):
    """reproduce's validation step, pickled for the processes of the test below (None: they
    compute it). What is tested there happens after every computation, while the results are
    staged; the validation, half of a reproduce's time, is the `repro` run's, its values the
    same. The rest (Tables II and III, Figs. 7-11, the figures and report) is computed and
    written by each process as in any `hydroarm reproduce`."""
    if reuse_validation is None:
        return None
    path = tmp_path_factory.mktemp("validation") / "validation.pickle"
    path.write_bytes(pickle.dumps(reuse_validation))
    return str(path)


@pytest.mark.slow
def test_signals_during_reproduce_then_rerun(tmp_path, capsys, validation_pickle):
    """SIGINT and SIGTERM during `reproduce`: exit 130, one line, the previous results kept
    untouched; SIGKILL: a staging folder left, removed by the rerun, whose tables equal the
    golden ones (tests/data/golden)."""
    out = tmp_path / "r"
    out.mkdir()
    (out / "table3.csv").write_text("earlier results\n")
    for sig in (signal.SIGINT, signal.SIGTERM):
        p = _start_reproduce(tmp_path, out, validation_pickle)
        p.send_signal(sig)
        _, err = p.communicate(timeout=60)
        assert p.returncode == 130, err
        assert err.strip().splitlines()[-1:] == ["hydroarm: interrupted"]
        assert _tree(tmp_path) == {"r", "r/table3.csv"}
        assert (out / "table3.csv").read_text() == "earlier results\n"
    p = _start_reproduce(tmp_path, out, validation_pickle)
    p.kill()
    p.wait()
    assert len(list(tmp_path.glob(files.STAGE_PREFIX + "*"))) == 1  # left by the SIGKILL
    # the rerun: in this process, its validation step the `repro` run's (validation_pickle)
    assert main(["reproduce", "--out", str(out)]) == 0
    assert not list(tmp_path.glob(files.STAGE_PREFIX + "*"))  # removed by the next run
    golden = ROOT / "tests" / "data" / "golden"
    for name in ("table2.csv", "table3.csv"):
        assert (out / name).read_bytes() == (golden / name).read_bytes()


# ------------------------------------------------ an output on its own file system ---
EVALUATION = """[joint]
parameter_set = "ucl-arm-measured"
[[load_case]]
name = "light"
load = 1
[requirements]
time_constant = "<= 50 ms"
"""


def test_staging_on_a_full_mount_point_leaves_nothing(tmp_path, capsys, monkeypatch):
    """--out is a 64 kB tmpfs of its own (issue 31): the staging folder is made on it (one
    rename per file at the end), the card's figure fills it, and nothing is left there; the
    line names --out. Before, the stage sat on the parent's file system and the final copy
    left card.csv and an empty card.md."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root")
    out = tmp_path / "out"
    out.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(out)], capture_output=True
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.decode().strip()}")
    try:
        assert files.stage_parent(out) == out  # a mount point: the stage goes inside it
        (tmp_path / "e.toml").write_text(EVALUATION)
        monkeypatch.chdir(tmp_path)
        assert main(["evaluate", "--config", "e.toml", "--out", "out"]) == 2
        err = _err_lines(capsys)
        assert len(err) == 1 and err[0].startswith("hydroarm: error: --out: out/"), err
        assert "no space left on the device" in err[0], err
        assert list(out.iterdir()) == []  # no card.csv, no empty card.md, no stage
    finally:
        subprocess.run(["umount", str(out)], check=False)


def test_stage_beside_an_output_on_the_same_device(tmp_path):
    out = tmp_path / "o"
    assert files.stage_parent(out) == tmp_path  # not made yet: beside it
    out.mkdir()
    assert files.stage_parent(out) == tmp_path  # same device as its parent
    with files.staging_folder(out) as stage:
        assert stage.parent == tmp_path and stage.stat().st_dev == out.stat().st_dev
        (stage / "a.txt").write_text("a")
        files.move_into(stage, out, ["a.txt"])
    assert [p.name for p in tmp_path.iterdir()] == ["o"] and (out / "a.txt").read_text() == "a"
