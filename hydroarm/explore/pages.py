"""What both pages of ``hydroarm explore`` (the arm's and a system's) share: the runs of a
page's changes on a thread, the latest value of each control first, and the server."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

from ..errors import HydroarmError


async def run_latest(
    pending: dict,
    lock: asyncio.Lock,
    io_bound: Callable[..., Awaitable],
    setter: Callable[[str, Any], object],
    before: Callable[[], None] | None = None,
) -> str | None:
    """Apply the changes in ``pending`` (control name → its latest value) with
    ``setter(name, value)`` run by ``io_bound`` (NiceGUI's ``run.io_bound``: a thread; the
    numba kernels release the GIL), one after another under ``lock``. Values arriving
    meanwhile replace the pending one of their control, so a dragged slider runs its latest
    value next and skips the ones in between. ``before()`` is called before each run (a
    status line). Returns None when another call already holds the lock (it will run the
    new value), else the last refusal's one-line message ('' if every value was taken)."""
    if lock.locked():
        return None
    async with lock:
        refused = ""
        while pending:
            name, value = next(iter(pending.items()))
            del pending[name]
            if before is not None:
                before()
            try:
                await io_bound(setter, name, value)
            except HydroarmError as exc:  # a refused value: the setting is kept
                refused = str(exc)
        return refused


def serve_page(ui, *, port: int, show: bool) -> None:
    """Serve the pages built on NiceGUI's ``ui`` on 127.0.0.1:``port`` until interrupted
    (``show``: open the default browser)."""
    ui.run(
        host="127.0.0.1",
        port=port,
        show=show,
        reload=False,
        title="hydroarm explore",
        show_welcome_message=False,
        uvicorn_logging_level="warning",
    )
