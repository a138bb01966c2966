"""Rewrite the Sphinx roles of hydroarm's docstrings as mkdocstrings cross-references (issue 33).

The documentation site (mkdocs.yml: mkdocs-material, mkdocstrings, numpy docstrings) shows a
Sphinx role (``:func:`x```, ``:class:`~hydroarm.a.B```, ``:mod:`.servo```) literally. Each role
becomes either

- an autorefs cross-reference, ``[`B`][hydroarm.B]``, when its target is one of the objects of
  the API reference (docs/api.md: the names of ``hydroarm.__all__``, and the public members of
  its classes), linked under that public name; or
- plain code, ``B``, when the target is private, internal or outside hydroarm (the API reference
  documents ``hydroarm.__all__`` only, and ``mkdocs build --strict`` fails on a reference that
  resolves to nothing).

Each target is resolved by importing it: an absolute dotted name; a relative one (``.servo``,
``..core.params``) against the module's package, then as a suffix of a loaded hydroarm module;
a bare name against the module itself, then ``hydroarm``. The text shown is the target as
written, less its leading dots, or its last name only after a ``~`` (as Sphinx shows it).
Roles in comments become plain code. Idempotent: a second run changes nothing.

    python tools/sphinx_roles_to_autorefs.py [FILE ...]   # default: every hydroarm/**/*.py

``tests/test_docstrings.py`` holds the convention: no docstring carries a Sphinx role.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import io
import re
import sys
import tokenize
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROLE = re.compile(r":(?:py:)?(func|class|meth|mod|data|attr|exc|obj):`([^`]+)`")
_MISSING = object()


def _import_path(path: str):
    """The object a dotted path names, or _MISSING."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for name in parts[i:]:
            obj = getattr(obj, name, _MISSING)
            if obj is _MISSING:
                return _MISSING
        return obj
    return _MISSING


def resolve(
    target: str, module: str, is_package: bool, cls: str | None = None
) -> tuple[str, object] | None:
    """(dotted path, object) of a role's target written in `module` (in class `cls`), or None."""
    package = module if is_package else module.rpartition(".")[0]
    if target.startswith("."):
        rest = target.lstrip(".")
        up = len(target) - len(rest) - 1
        base = package.split(".")
        base = base[: len(base) - up] if up else base
        candidates = [".".join([*base, rest]), f"{module}.{rest}"]
        # Sphinx's ".name": any object whose name ends with it (the loaded hydroarm modules)
        candidates += sorted(
            m for m in sys.modules if m.startswith("hydroarm") and m.endswith(f".{rest}")
        )
    else:
        candidates = [target, f"{module}.{target}", f"{package}.{target}", f"hydroarm.{target}"]
        if cls:  # a bare member name, in its class's docstrings
            candidates.insert(0, f"{module}.{cls}.{target}")
        # a stale module path: the object under its public name; a builtin
        last = target.rpartition(".")[2]
        candidates += [f"hydroarm.{last}", f"builtins.{target}"]
    for path in candidates:
        obj = _import_path(path)
        if obj is not _MISSING:
            return path, obj
    return None


def _api() -> dict[int, str]:
    """id(object) -> its name in the API reference, for hydroarm.__all__ and class members."""
    import hydroarm

    names: dict[int, str] = {}
    for name in hydroarm.__all__:
        obj = getattr(hydroarm, name)
        if isinstance(obj, type | tuple | dict | list) or callable(obj):
            names[id(obj)] = f"hydroarm.{name}"
    return names


def _members(cls: type) -> set[str]:
    """The public members mkdocstrings documents on a class page: its own, not inherited."""
    own = set(vars(cls)) | set(getattr(cls, "__annotations__", {}))
    return {m for m in own if not m.startswith("_")}


def public_path(path: str, obj: object, api: dict[int, str]) -> str | None:
    """The API reference's identifier of a resolved target, or None if it has none."""
    if not inspect.ismodule(obj) and id(obj) in api:
        return api[id(obj)]
    parent_path, _, member = path.rpartition(".")
    if parent_path:
        parent = _import_path(parent_path)
        if isinstance(parent, type) and id(parent) in api and member in _members(parent):
            return f"{api[id(parent)]}.{member}"
    return None


def convert(
    text: str,
    module: str,
    is_package: bool,
    api,
    stats: Counter,
    link: bool = True,
    cls: str | None = None,
) -> str:
    def repl(m: re.Match) -> str:
        written = m.group(2)
        title = re.fullmatch(r"(.*?)\s*<([^<>]+)>", written, flags=re.S)  # "text <target>"
        written = re.sub(r"\s+", "", title.group(2) if title else written)
        tilde = written.startswith("~")
        target = written.lstrip("~")
        shown = target.rsplit(".", 1)[-1] if tilde else target.lstrip(".")
        if title:
            shown = " ".join(title.group(1).split())
        found = resolve(target, module, is_package, cls) if link else None
        ref = public_path(*found, api) if found else None
        if found is None:
            stats["unresolved" if link else "comment"] += 1
            if link:
                stats[f"unresolved: {target} ({module})"] += 1
        if ref is None:
            stats["code"] += 1
            return f"`{shown}`"
        stats["link"] += 1
        return f"[`{shown}`][{ref}]"

    return ROLE.sub(repl, text)


def module_name(path: Path) -> tuple[str, bool]:
    rel = path.resolve().relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    is_package = parts[-1] == "__init__"
    if is_package:
        parts.pop()
    return ".".join(parts), is_package


LIMIT = 100  # ruff's line-length (pyproject.toml)
_NOT_A_LINE_START = re.compile(r"([-+*#>|]|\d+[.)])(\s|$)")
_PARAMETER = re.compile(r"\s*\*{0,2}\w+ : ")


def reflow(text: str, column: int) -> str:
    """Rewrap the lines of a docstring (starting at `column` of its first line) that now run
    past LIMIT: the words past it join the next line of the same paragraph, or a line of
    their own; a word never starts a line where Markdown would read a list, heading or
    table."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        line = lines[i]
        start = column if i == 0 else 0
        if start + len(line) <= LIMIT or line.lstrip().startswith((">>>", "...")):
            i += 1
            continue
        # the first line's words go on at the docstring's column
        indent = " " * column if i == 0 else line[: len(line) - len(line.lstrip())]
        lead = len(line) - len(line.lstrip())
        fits = [p for p in range(lead + 1, len(line) - 1) if line[p] == " "]
        fits = [p for p in fits if not _NOT_A_LINE_START.match(line[p + 1 :])]
        # the last space that fits, else the first (a word longer than a line stays whole)
        cut = max((p for p in fits if start + p <= LIMIT), default=min(fits, default=None))
        if cut is None:
            i += 1
            continue
        head, tail = line[:cut].rstrip(), line[cut + 1 :].strip()
        lines[i] = head
        nxt = lines[i + 1] if i + 1 < len(lines) else None
        joins = (
            nxt is not None
            and nxt.strip()
            and nxt[: len(nxt) - len(nxt.lstrip())] == indent
            and not _NOT_A_LINE_START.match(nxt.lstrip())
            and not _PARAMETER.match(nxt)
            and not set(nxt.strip()) <= set("-=\"'")
            and not (i + 2 < len(lines) and set(lines[i + 2].strip()) == {"-"})
        )
        if joins:
            lines[i + 1] = f"{indent}{tail} {nxt.lstrip()}"
        else:
            lines.insert(i + 1, f"{indent}{tail}")
        i += 1
    return "\n".join(lines)


def _classes(source: str) -> list[tuple[int, int, str]]:
    """(first line, last line, qualified name) of each class of a module."""
    out = []

    def walk(node, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ClassDef):
                name = f"{prefix}{child.name}"
                out.append((child.lineno, child.end_lineno or child.lineno, name))
                walk(child, f"{name}.")
            else:
                walk(child, prefix)

    walk(ast.parse(source), "")
    return out


def convert_file(path: Path, api, stats: Counter) -> bool:
    source = path.read_text(encoding="utf-8")
    if not ROLE.search(source):
        return False
    module, is_package = module_name(path)
    lines = source.splitlines(keepends=True)
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line))
    classes = _classes(source)
    edits = []
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type not in (tokenize.STRING, tokenize.COMMENT) or not ROLE.search(tok.string):
            continue
        start = offsets[tok.start[0] - 1] + tok.start[1]
        end = offsets[tok.end[0] - 1] + tok.end[1]
        line = tok.start[0]
        inside = [c for c in classes if c[0] <= line <= c[1]]
        cls = max(inside)[2] if inside else None  # the innermost class
        new = convert(tok.string, module, is_package, api, stats, tok.type == tokenize.STRING, cls)
        if tok.type == tokenize.STRING:
            new = reflow(new, tok.start[1])
        edits.append((start, end, new))
    for start, end, new in reversed(edits):
        source = source[:start] + new + source[end:]
    path.write_text(source, encoding="utf-8")
    return True


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    files = [Path(a) for a in argv] or sorted((ROOT / "hydroarm").rglob("*.py"))
    api = _api()
    stats: Counter = Counter()
    changed = [f for f in files if convert_file(f, api, stats)]
    unresolved = sorted(k for k in stats if k.startswith("unresolved: "))
    for k in unresolved:
        print(k)
    print(
        f"{len(changed)} files: {stats['link']} links, {stats['code']} plain code "
        f"({stats['unresolved']} unresolved targets, {stats['comment']} in comments)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
