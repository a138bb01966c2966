"""File output shared by every layer: atomic writes (a file is written whole or not at all)
and the CSV text of result rows."""

from __future__ import annotations

import csv
import io
import os
import tempfile
from pathlib import Path


def atomic_write_bytes(path, data: bytes) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; outputs are ordinary files
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path, text: str) -> None:
    atomic_write_bytes(path, text.encode("utf-8"))


def csv_text(header, rows) -> str:
    """CSV text of dict rows: the columns of ``header``; floats to 6 significant digits,
    None as an empty field."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow(
            [
                "" if r.get(h) is None else (f"{r[h]:.6g}" if isinstance(r[h], float) else r[h])
                for h in header
            ]
        )
    return buf.getvalue()
