"""Progress on a terminal: one line per stage of a long command."""

from __future__ import annotations

import sys
import time


class Progress:
    """One line per stage on a terminal; silent otherwise."""

    def __init__(self, total: int, stream=None, enabled: bool | None = None):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.total = total
        self.n = 0
        self.t0 = time.perf_counter()

    def __call__(self, label: str):
        self.n += 1
        if self.enabled:
            dt = time.perf_counter() - self.t0
            self.stream.write(f"[{self.n}/{self.total}] {label} ({dt:.1f} s)\n")
            self.stream.flush()
