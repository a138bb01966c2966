"""Progress of a long command: one line per stage on a terminal, and off a terminal (a log,
a CI job) a line at most every `INTERVAL` seconds, so that a long run is never silent
and a short one stays quiet. In a Jupyter notebook (an IPython kernel) a ``tqdm.auto`` bar
instead (a widget where ipywidgets is installed, else tqdm's text bar), redrawn in place."""

from __future__ import annotations

import os
import sys
import time

#: seconds between progress lines off a terminal (``HYDROARM_PROGRESS_INTERVAL``; 0: every)
INTERVAL = 15.0


def interval() -> float:
    """The seconds between progress lines off a terminal (the environment's setting, else
    `INTERVAL`; a value that is not a number ≥ 0 is ignored)."""
    raw = os.environ.get("HYDROARM_PROGRESS_INTERVAL")
    try:
        v = float(raw) if raw is not None else INTERVAL
    except ValueError:
        return INTERVAL
    return v if v >= 0 else INTERVAL


def in_notebook() -> bool:
    """True inside a Jupyter kernel (IPython running with a kernel; not a terminal IPython)."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
    except Exception:  # an IPython that is not running
        return False
    return shell is not None and getattr(shell, "kernel", None) is not None


def notebook_bar(total: int, desc: str):
    """A ``tqdm.auto`` bar of ``total`` steps in a notebook, else None (a bar that cannot be
    made, e.g. an old tqdm, is None too: the text lines then)."""
    if not in_notebook():
        return None
    try:
        from tqdm.auto import tqdm

        return tqdm(total=total, desc=desc, leave=True)
    except Exception:
        return None


class Throttle:
    """Whether to show a progress line now: always on a terminal (``tty``), else when
    `interval` seconds have passed since the last one shown (or at the end)."""

    def __init__(self, tty: bool):
        self.tty = tty
        self.every = interval()
        self.last = time.perf_counter()

    def __call__(self, final: bool = False) -> bool:
        if self.tty:
            return True
        now = time.perf_counter()
        if final or now - self.last >= self.every:
            self.last = now
            return True
        return False


class Progress:
    """One line per stage on a terminal; off a terminal a line every `interval`
    seconds at most (``enabled`` True or False forces every line or none)."""

    def __init__(self, total: int, stream=None, enabled: bool | None = None):
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.throttle = Throttle(_isatty(self.stream))
        self.total = total
        self.n = 0
        self.t0 = time.perf_counter()
        self._notes: Throttle | None = None  # the notes' own clock (every interval)
        # a notebook: a bar in place of the lines (unless a stream or the lines were asked for)
        self.bar = notebook_bar(total, "hydroarm") if stream is None and enabled is None else None

    def __call__(self, label: str):
        self.n += 1
        if self.bar is not None:
            self.bar.set_description(label, refresh=False)
            self.bar.update(1)
            if self.n >= self.total:
                self.bar.close()
            return
        show = self.enabled if self.enabled is not None else self.throttle()
        if show:
            dt = time.perf_counter() - self.t0
            self.stream.write(f"[{self.n}/{self.total}] {label} ({dt:.1f} s)\n")
            self.stream.flush()

    def note(self, label: str):
        """A line within a stage (not counted: ``[n/total] …``), at most every
        `interval` seconds on a terminal or off it (a long fit's evaluations), so that
        a stage that runs for minutes is never silent."""
        if self.enabled is False or not self.notes():
            return
        if self.bar is not None:
            self.bar.set_postfix_str(label)
            return
        dt = time.perf_counter() - self.t0
        self.stream.write(f"[{self.n}/{self.total}] {label} ({dt:.1f} s)\n")
        self.stream.flush()

    @property
    def notes(self) -> Throttle:
        if self._notes is None:
            self._notes = Throttle(False)
        return self._notes


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False
