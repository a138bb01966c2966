"""The example files (``hydroarm examples [--copy DIR]``): listed with one line each, and
copied into a folder of the user's, so that the README's and the docs' commands run from an
installed wheel.

The repository keeps them in ``examples/`` at its top; the wheel ships that folder as
``hydroarm/examples`` (a ``package-dir`` mapping in pyproject.toml, one copy). A source checkout
(editable install, ``PYTHONPATH``) reads the repository's folder.
"""

from __future__ import annotations

import os
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from ..errors import HydroarmError
from ..files import os_problem

SUFFIXES = (".toml", ".csv", ".py")
DESCRIPTION_CHARS = 90  # one line of a terminal beside the file name


@dataclass(frozen=True)
class Example:
    name: str
    path: Path
    description: str


def examples_folder() -> Path:
    """The folder of the example files: ``hydroarm/examples`` of an installed wheel, else the
    ``examples/`` of the source checkout this package runs from."""
    package = Path(__file__).resolve().parents[1]
    installed = package / "examples"
    if installed.is_dir():
        return installed
    checkout = package.parent
    if (checkout / "pyproject.toml").is_file() and (checkout / "examples").is_dir():
        return checkout / "examples"
    raise HydroarmError(
        "examples", f"no example files next to {package} (a broken installation: reinstall)"
    )


def _header(text: str, suffix: str) -> str:
    """The file's leading comment (``#`` lines) or docstring, as one paragraph."""
    lines = text.splitlines()
    if suffix == ".py":
        m = re.match(r'\s*(?:"""|\'\'\')(.*?)(?:\n\s*\n|"""|\'\'\')', text, re.S)
        return " ".join(m.group(1).split()) if m else ""
    out = []
    for line in lines:
        if not line.startswith("#"):
            break
        out.append(line.lstrip("#").strip())
    return " ".join(" ".join(out).split())


def describe(path: Path) -> str:
    """One line on an example: the first sentence of its header, shortened at a word, or a
    data file's column names."""
    text = path.read_text(encoding="utf-8")
    head = _header(text, path.suffix)
    if not head:
        first = next((ln for ln in text.splitlines() if ln.strip()), "")
        return f"data: columns {first.replace(',', ', ')}" if path.suffix == ".csv" else ""
    head = re.split(r"\s(?:Run|Try|Usage|Time it):", head)[0]
    while (shorter := re.sub(r"\s*\([^()]*\)", "", head)) != head:  # parentheses, inner first
        head = shorter
    m = re.match(r"(.+?(?<!e\.g)(?<!i\.e)[.?!])(\s|$)", head)
    line = (m.group(1) if m else head).rstrip(".:;, ")
    if len(line) > DESCRIPTION_CHARS:
        line = line[: DESCRIPTION_CHARS - 1].rsplit(" ", 1)[0].rstrip(",;") + "…"
    return line


def list_examples(folder: Path | None = None) -> list[Example]:
    """Every example file, sorted by name."""
    folder = examples_folder() if folder is None else folder
    return [
        Example(p.name, p, describe(p))
        for p in sorted(folder.iterdir())
        if p.is_file() and p.suffix in SUFFIXES and not p.name.startswith(("_", "."))
    ]


def copy_examples(dest, field: str = "--copy") -> list[Path]:
    """Copy every example file into ``dest`` (created if missing; its parent must exist).
    Refuses, before copying anything, a destination that is a file, a missing parent, or any
    example file already there (nothing is overwritten). A failure while copying removes the
    files this call wrote. Returns the written paths."""
    if dest is None or not str(dest).strip():
        raise HydroarmError(field, "is empty (give a folder)")
    d = Path(dest)
    if d.exists() and not d.is_dir():
        raise HydroarmError(field, f"{d} is a file, not a folder")
    if not d.exists() and not d.parent.is_dir():
        raise HydroarmError(field, f"{d}: folder {d.parent} does not exist")
    examples = list_examples()
    there = [e.name for e in examples if (d / e.name).exists()]
    if there:
        more = f" and {len(there) - 1} more" if len(there) > 1 else ""
        raise HydroarmError(
            field,
            f"{d / there[0]}{more} already exist (nothing was copied; give a new or empty folder)",
        )
    written: list[Path] = []
    created = not d.exists()
    try:
        d.mkdir(exist_ok=True)
        for e in examples:
            target = d / e.name
            tmp = d / f".{e.name}.part"
            shutil.copyfile(e.path, tmp)
            os.replace(tmp, target)
            written.append(target)
    except OSError as exc:
        for p in [*written, *(d / f".{e.name}.part" for e in examples)]:
            p.unlink(missing_ok=True)
        if created:
            try:
                d.rmdir()
            except OSError:
                pass
        raise HydroarmError(field, f"{d}: cannot copy: {os_problem(exc)}") from None
    return written
