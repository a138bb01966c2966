"""A ``hydroarm explore`` server in a subprocess for the explore tests (not a test module):
started on a free port, waited for by its own readiness, stopped at the end.

Readiness, not a time budget: :meth:`ExploreServer.wait` returns once the server has printed
its URL (its arm or file checked, the kernels loaded or compiled) and its port answers. It
waits as long as the server works towards that: it gives up only when the server ends, or when
its process has used no CPU time for :data:`STALL_S` (a hang, not a slow machine: at a load of
4-8 on 2 cores a compile is slow but never idle)."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from urllib.request import urlopen

STALL_S = 120.0  # [s] without CPU time used by the server: it hangs (module doc)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def press(track, fraction: float, touch: bool = False) -> None:
    """A click (a tap, ``touch``) on a slider's track (a Playwright locator) at ``fraction``
    of its width. Playwright's own click or tap at a position inside the element: it scrolls
    the element into view, waits until it stands still and checks that the element itself
    receives the event. A page point measured beforehand can miss: the live pages' labels
    above a slider re-wrap as their numbers change, and a scroll may still be moving it."""
    box = track.bounding_box()
    assert box is not None
    where = {"x": fraction * box["width"], "y": 0.5 * box["height"]}
    if touch:
        track.tap(position=where)
    else:
        track.click(position=where)


def cpu_seconds(pid: int) -> float:
    """User + system CPU time [s] of a process (Linux /proc; elsewhere the wall clock, so
    that the stall rule becomes a plain time budget)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return time.monotonic()


class ExploreServer:
    """``hydroarm explore ARGS --port P --no-browser`` in a subprocess (its own session, so
    that it is stopped with its children); stdout and stderr collected by threads."""

    def __init__(self, *args: str, port: int | None = None):
        self.port = port or free_port()
        # NiceGUI runs in its own test mode when it sees pytest's variables: the server is a user's
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
        env.update(MPLBACKEND="Agg", PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "hydroarm.cli", "explore", *args,
             "--port", str(self.port), "--no-browser"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
            start_new_session=True,
        )  # fmt: skip
        self.out: list[str] = []
        self.err: list[str] = []
        self.url = ""
        self._printed = threading.Event()
        threading.Thread(target=self._read, args=(self.proc.stdout, self.out), daemon=True).start()
        threading.Thread(target=self._read, args=(self.proc.stderr, self.err), daemon=True).start()

    def _read(self, stream, lines: list[str]) -> None:
        for line in stream:
            lines.append(line)
            if "hydroarm explore: http://" in line and not self.url:
                self.url = line.split("hydroarm explore: ", 1)[1].split()[0]
                self._printed.set()

    def _alive(self, last: list[float]) -> None:
        """Raise if the server ended or has used no CPU for STALL_S (``last``: [cpu, when])."""
        if self.proc.poll() is not None:
            time.sleep(0.2)  # the readers take the last lines
            raise AssertionError(
                f"the server ended ({self.proc.returncode}): {''.join(self.err)[-3000:]}"
            )
        cpu, now = cpu_seconds(self.proc.pid), time.monotonic()
        if cpu != last[0]:
            last[:] = [cpu, now]
        elif now - last[1] > STALL_S:
            raise AssertionError(f"the server used no CPU for {STALL_S:.0f} s before it was ready")

    def wait(self) -> ExploreServer:
        """Until the URL is printed and the page answers (module doc); returns self."""
        last = [cpu_seconds(self.proc.pid), time.monotonic()]
        while not self._printed.wait(0.25):
            self._alive(last)
        while True:
            try:
                with urlopen(self.url, timeout=5) as r:
                    if r.status == 200:
                        return self
            except OSError:
                self._alive(last)
                time.sleep(0.1)

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait(timeout=10)


def excavator_copy(folder: Path) -> Path:
    """examples/excavator.toml (with its [block_task]) and its cycle copied into ``folder``,
    the page's runs 0.5 s long (the file's run sets only the view and the levers' ranges; the
    live view is stepped): what the live tests of the excavator's task open."""
    examples = Path(__file__).parents[1] / "examples"
    (folder / "excavator_cycle.csv").write_text((examples / "excavator_cycle.csv").read_text())
    path = folder / "excavator.toml"
    text = (examples / "excavator.toml").read_text()
    path.write_text(text + '\n[explore]\nduration = "0.5 s"\n')
    return path
