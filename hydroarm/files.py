"""File output shared by every layer: output paths checked before any work, atomic writes (a
file is written whole or not at all, with one clear error line on a full disk), staging
folders for commands that write several files, folder locks, and the CSV text of result
rows."""

from __future__ import annotations

import contextlib
import csv
import errno
import fcntl
import io
import os
import shutil
import tempfile
from pathlib import Path

from .errors import HydroarmError

STAGE_PREFIX = ".hydroarm-stage-"  # staging folders: <output's parent>/.hydroarm-stage-*
# staging folders of hydroarm before 0.1.1 (no lock): removed as stale too
_OLD_STAGE_PREFIXES = (".hydroarm-reproduce-", ".hydroarm-validate-", ".hydroarm-arm-")
_LOCK_NAME = ".lock"


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM, with what was kept (one line, e.g. how to resume a sweep).

    The CLI prints ``hydroarm: interrupted: <detail>`` and exits with status 130."""


def os_problem(exc: OSError) -> str:
    """A short text for an operating-system error (no path, no errno number)."""
    known = {
        errno.ENOSPC: "no space left on the device",
        errno.EDQUOT: "disk quota exceeded",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
        errno.EROFS: "read-only file system",
        errno.ENOENT: "no such file or folder",
        errno.ENOTDIR: "a part of the path is a file, not a folder",
        errno.EISDIR: "is a folder",
        errno.ENAMETOOLONG: "name too long",
    }
    return known.get(exc.errno or 0) or (exc.strerror or type(exc).__name__).lower()


def write_error(path, exc: OSError) -> HydroarmError:
    """The one-line error for an OSError while writing ``path``."""
    return HydroarmError(str(path), f"cannot write: {os_problem(exc)}")


def _check_parent(field: str, path: Path) -> None:
    """The folder that will hold ``path`` exists, is a folder and is writable."""
    parent = path.parent
    if not parent.exists():
        up = parent
        while not up.exists() and up != up.parent:
            up = up.parent
        if up.exists() and not up.is_dir():
            raise HydroarmError(field, f"{path}: {up} is a file, not a folder")
        raise HydroarmError(field, f"{path}: folder {parent} does not exist")
    if not parent.is_dir():
        raise HydroarmError(field, f"{path}: {parent} is a file, not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise HydroarmError(field, f"{path}: cannot write to folder {parent} (permission denied)")


def check_output_file(field: str, path) -> Path:
    """Refuse an output file that cannot be written, before any work starts: an empty name,
    a folder, a path under a regular file, a missing parent folder (never created) or an
    unwritable place. Returns the path."""
    if path is None or str(path).strip() == "":
        raise HydroarmError(field, "is empty (give a file name)")
    p = Path(path)
    if p.is_dir():
        raise HydroarmError(field, f"{p} is a folder, not a file")
    _check_parent(field, p)
    if p.exists() and not os.access(p, os.W_OK):
        raise HydroarmError(field, f"{p}: permission denied")
    return p


def check_output_folder(field: str, path, *, create: bool = True) -> Path:
    """Refuse an output folder that cannot be written, before any work starts: an empty name,
    an existing file, a path under a regular file, an unwritable place. A missing folder is
    allowed when ``create`` (only its last level is created, later; its parent must exist).
    Returns the path."""
    if path is None or str(path).strip() == "":
        raise HydroarmError(field, "is empty (give a folder name)")
    p = Path(path)
    if p.exists():
        if not p.is_dir():
            raise HydroarmError(field, f"{p} exists and is not a folder")
        if not os.access(p, os.W_OK | os.X_OK):
            raise HydroarmError(field, f"cannot write to folder {p} (permission denied)")
    elif not create:
        raise HydroarmError(field, f"folder {p} does not exist")
    # the staging folder is made beside the output, in its parent
    _check_parent(field, p)
    return p


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (temporary file, then rename); an
    OSError (full disk, permission, read-only) becomes one error line naming the path."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; outputs are ordinary files
        os.replace(tmp, path)
        tmp = None
    except OSError as exc:
        raise write_error(path, exc) from exc
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def atomic_write_text(path, text: str) -> None:
    atomic_write_bytes(path, text.encode("utf-8"))


# ------------------------------------------------------------------ locks ---
def try_lock(path: Path):
    """An exclusive, non-blocking lock on the file or folder ``path``: the open descriptor,
    or None when another process holds it (or the path vanished). The lock ends with the
    process, SIGKILL included; release it with :func:`unlock`."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    return fd


def unlock(fd) -> None:
    if fd is not None:
        with contextlib.suppress(OSError):
            os.close(fd)


# --------------------------------------------------------------- staging ---
def remove_stale_stages(parent: Path) -> list[Path]:
    """Remove the staging folders in ``parent`` that no running hydroarm holds (left by a
    SIGKILL or a power cut): each live one is locked by its process. Returns those removed."""
    removed: list[Path] = []
    try:
        entries = [
            d for pre in (STAGE_PREFIX, *_OLD_STAGE_PREFIXES) for d in Path(parent).glob(pre + "*")
        ]
    except OSError:
        return removed
    for d in entries:
        if not d.is_dir() or d.is_symlink():
            continue
        fd = try_lock(d)
        if fd is None:
            continue  # in use by a running hydroarm (or already gone)
        try:
            shutil.rmtree(d, ignore_errors=True)
            removed.append(d)
        finally:
            unlock(fd)
    return removed


@contextlib.contextmanager
def staging_folder(out: Path, field: str = "--out"):
    """A fresh staging folder ``.hydroarm-stage-<name>-*`` beside the output folder ``out``,
    locked while this process lives and removed at the end; stale ones (no live owner) are
    removed first. Move the finished files into ``out`` with :func:`move_into`."""
    out = Path(out)
    parent = out.parent
    remove_stale_stages(parent)
    try:
        stage = Path(tempfile.mkdtemp(prefix=f"{STAGE_PREFIX}{out.name}-", dir=parent))
    except OSError as exc:
        raise write_error(parent, exc) from exc
    fd = try_lock(stage)
    try:
        yield stage
    except OSError as exc:
        raise write_error(_failed_path(exc, stage, out), exc) from exc
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        unlock(fd)


def _failed_path(exc: OSError, stage: Path, out: Path) -> Path:
    name = getattr(exc, "filename", None)
    if name:
        p = Path(name)
        with contextlib.suppress(ValueError):
            return out / p.relative_to(stage)
        return p
    return out


def move_into(stage: Path, out: Path, names) -> None:
    """Move the staged files ``names`` into the folder ``out`` (created: the last level only)."""
    out = Path(out)
    try:
        out.mkdir(exist_ok=True)
        for n in names:
            shutil.move(str(stage / n), str(out / n))
    except OSError as exc:
        raise write_error(out, exc) from exc


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
