"""Files shared by every layer: the one path check of every file the program reads or writes
(`checked_path`), output paths checked before any work, atomic writes (a file is
written whole or not at all, with one clear error line on a full disk), staging folders for
commands that write several files (on the output's own file system), folder locks, and the
CSV text of result rows."""

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


def write_error(path, exc: OSError, field: str | None = None) -> HydroarmError:
    """The one-line error for an OSError while writing ``path``: ``<field>: <path>: cannot
    write: ...`` when the option or key that named the output is known, else ``<path>: ...``."""
    if field:
        err = HydroarmError(field, f"{shown_path(path)}: cannot write: {os_problem(exc)}")
    else:
        err = HydroarmError(shown_path(path), f"cannot write: {os_problem(exc)}")
    err.path, err.os_error = str(path), exc  # staging_folder and the CLI name the option
    return err


# ------------------------------------------------------------------ paths ---
NAME_MAX = 255  # bytes in one name of a path: Linux's NAME_MAX (ext4, tmpfs, XFS; NTFS: 255)
PATH_MAX = 4096  # bytes in a whole path, its end included: Linux's PATH_MAX
SHOWN_MAX = 120  # a path up to this many characters is shown whole in a message
SHOWN_ENDS = 30  # characters kept at each end of a longer one


def shown_path(path) -> str:
    """``path`` for a message: whole up to SHOWN_MAX characters, else its first and last
    SHOWN_ENDS characters around ``…`` (a path near PATH_MAX would flood the line)."""
    text = str(path).replace("\0", "\\0")  # a NUL shown as \0, not sent to the terminal
    if len(text) <= SHOWN_MAX:
        return text
    return f"{text[:SHOWN_ENDS]}…{text[-SHOWN_ENDS:]} ({len(text)} characters)"


def checked_path(field: str, path, base=None) -> Path:
    """The one check of every path the program reads or writes (a configuration, a file it
    names, an output): ``base / path`` (``base``: the folder a relative name in a file is
    read from) resolved, symbolic links followed. Refused with a one-line error naming
    ``field``: a NUL character in the name, a name over NAME_MAX bytes, a path over PATH_MAX
    bytes, a symbolic-link loop. The message shows a long path shortened
    (`shown_path`). Returns the resolved path (a missing file is not an error here:
    the reader or writer says so)."""
    if path is None:
        raise HydroarmError(field, "is empty (give a file name)")
    try:
        text = os.fspath(path)
    except TypeError:
        raise HydroarmError(field, f"expected a file name, got {path!r}") from None
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    shown = shown_path(text)
    where = "" if field == shown else f"{shown}: "  # the field may be the path itself
    if "\0" in text:
        raise HydroarmError(field, f"{where}a NUL character in the name (not allowed)")
    full = text if base is None else os.path.join(os.fspath(base), text)
    encoded = os.fsencode(full)
    for part in encoded.split(b"/"):
        if len(part) > NAME_MAX:
            raise HydroarmError(
                field,
                f"{where}a name in the path is {len(part)} bytes long (at most {NAME_MAX})",
            )
    if len(encoded) >= PATH_MAX:
        raise HydroarmError(
            field, f"{where}the path is {len(encoded)} bytes long (at most {PATH_MAX - 1})"
        )
    try:
        resolved = Path(full).resolve()
    except RuntimeError:  # Python 3.11-3.12: "Symlink loop from ..."
        raise HydroarmError(field, f"{where}a loop of symbolic links") from None
    except OSError as exc:  # Python 3.13: ELOOP; a folder that cannot be searched
        if exc.errno == errno.ELOOP:
            raise HydroarmError(field, f"{where}a loop of symbolic links") from None
        raise HydroarmError(field, f"{where}{os_problem(exc)}") from None
    if len(os.fsencode(str(resolved))) >= PATH_MAX:  # a relative name below a deep folder
        raise HydroarmError(
            field,
            f"{where}the full path is {len(os.fsencode(str(resolved)))} "
            f"bytes long (at most {PATH_MAX - 1})",
        )
    return resolved


def _check_parent(field: str, path: Path) -> None:
    """The folder that will hold ``path`` exists, is a folder and is writable."""
    parent = path.parent
    if not parent.exists():
        up = parent
        while not up.exists() and up != up.parent:
            up = up.parent
        if up.exists() and not up.is_dir():
            raise HydroarmError(
                field, f"{shown_path(path)}: {shown_path(up)} is a file, not a folder"
            )
        raise HydroarmError(
            field, f"{shown_path(path)}: folder {shown_path(parent)} does not exist"
        )
    if not parent.is_dir():
        raise HydroarmError(
            field, f"{shown_path(path)}: {shown_path(parent)} is a file, not a folder"
        )
    if not os.access(parent, os.W_OK | os.X_OK):
        raise HydroarmError(
            field,
            f"{shown_path(path)}: cannot write to folder {shown_path(parent)} (permission denied)",
        )


def check_output_file(field: str, path) -> Path:
    """Refuse an output file that cannot be written, before any work starts: an empty name,
    a folder, a path under a regular file, a missing parent folder (never created) or an
    unwritable place. Returns the path."""
    if path is None or str(path).strip() == "":
        raise HydroarmError(field, "is empty (give a file name)")
    checked_path(field, path)
    p = Path(path)
    if p.is_dir():
        raise HydroarmError(field, f"{shown_path(p)} is a folder, not a file")
    _check_parent(field, p)
    if p.exists() and not os.access(p, os.W_OK):
        raise HydroarmError(field, f"{shown_path(p)}: permission denied")
    return p


def check_output_folder(field: str, path, *, create: bool = True) -> Path:
    """Refuse an output folder that cannot be written, before any work starts: an empty name,
    an existing file, a path under a regular file, an unwritable place. A missing folder is
    allowed when ``create`` (only its last level is created, later; its parent must exist).
    Returns the path."""
    if path is None or str(path).strip() == "":
        raise HydroarmError(field, "is empty (give a folder name)")
    checked_path(field, path)
    p = Path(path)
    if p.exists():
        if not p.is_dir():
            raise HydroarmError(field, f"{shown_path(p)} exists and is not a folder")
        if not os.access(p, os.W_OK | os.X_OK):
            raise HydroarmError(
                field, f"cannot write to folder {shown_path(p)} (permission denied)"
            )
    elif not create:
        raise HydroarmError(field, f"folder {shown_path(p)} does not exist")
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
    process, SIGKILL included; release it with `unlock`."""
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


def stage_parent(out: Path) -> Path:
    """Where the staging folder of the output folder ``out`` goes: on the same file system
    (device) as ``out``, so that moving each finished file in is one rename. Beside ``out``
    in its parent when they share a device (or ``out`` is not made yet), else inside ``out``
    itself (``out`` is a mount point, e.g. a small tmpfs given as ``--out``)."""
    out = Path(out)
    try:
        if out.is_dir() and (os.path.ismount(out) or out.stat().st_dev != out.parent.stat().st_dev):
            return out
    except OSError:
        pass
    return out.parent


@contextlib.contextmanager
def staging_folder(out: Path, field: str = "--out"):
    """A fresh staging folder ``.hydroarm-stage-<name>-*`` on the output folder's own file
    system (`stage_parent`: beside ``out``, or inside it when it is a mount point),
    locked while this process lives and removed at the end; stale ones (no live owner) are
    removed first. Move the finished files into ``out`` with `move_into` (one rename
    each). A write that fails inside (a full disk) names ``field`` and the file in ``out``
    it was for; nothing is left in ``out``."""
    out = Path(out)
    parent = stage_parent(out)
    remove_stale_stages(parent)
    try:
        stage = Path(tempfile.mkdtemp(prefix=f"{STAGE_PREFIX}{out.name}-", dir=parent))
    except OSError as exc:
        raise write_error(out, exc, field) from exc
    fd = try_lock(stage)
    try:
        yield stage
    except OSError as exc:
        raise write_error(_failed_path(exc, stage, out), exc, field) from exc
    except HydroarmError as exc:  # an atomic write inside the stage: name the output
        if exc.os_error is None:
            raise
        failed = _failed_path(exc, stage, out, exc.path)
        raise write_error(failed, exc.os_error, field) from exc
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        unlock(fd)


def _failed_path(exc, stage: Path, out: Path, name=None) -> Path:
    name = name or getattr(exc, "filename", None)
    if name:
        p = Path(name)
        with contextlib.suppress(ValueError):
            return out / p.relative_to(stage)
        return p
    return out


def move_into(stage: Path, out: Path, names, field: str = "--out") -> None:
    """Move the staged files ``names`` into the folder ``out`` (created: the last level
    only), each by one rename (the stage is on ``out``'s file system: `staging_folder`)."""
    out = Path(out)
    try:
        out.mkdir(exist_ok=True)
        for n in names:
            os.replace(stage / n, out / n)
    except OSError as exc:
        raise write_error(out, exc, field) from exc


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
