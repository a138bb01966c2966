"""numba's disk cache, stamped with every hydroarm source a compiled function can compile in.

numba stamps a cached function with its own file's content only ("Notes on caching" in
numba's developer documentation: the cache is invalidated when *the corresponding source file*
is modified). A jitted function called from another file is compiled into its caller's object
code, so a change to the callee's file leaves the caller's cached copy running the old code.
That happened here: the valve laws of ``core/components.py``, cached, kept an older
``signed_sqrt`` of ``core/equations.py`` after it changed, and the excavator's operating point
then failed to solve; a ``pip install --upgrade`` leaves numba's cache files (no part of the
wheel's record) beside the new sources in the same way.

`install` puts one locator first in numba's list, for hydroarm's own files only: the cache
folder and names that numba's own locator chooses, with the source stamp extended by a hash of
every hydroarm module that the function's file imports, directly or through others (read from
the files' import statements, not executed). A change to any of them empties that function's
cache. The circuit kernel's generated dispatch module lives outside the package; its callers
follow the components with `hydroarm.core.circuit.dispatch.follows_components`.
"""

from __future__ import annotations

import hashlib
import re
from functools import cache
from pathlib import Path

from numba.core import caching

PACKAGE = Path(__file__).resolve().parents[1]  # the hydroarm folder


def _module_file(root: Path, dotted: list[str]) -> Path | None:
    """The file of module ``dotted`` (its parts below ``root``'s package), or None."""
    base = root.joinpath(*dotted)
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


# an import statement: ``from <module> import <names>`` (names in brackets may span lines)
# or ``import <module>``, at any indentation
_IMPORT = re.compile(
    r"^[ \t]*(?:from[ \t]+(\.*)([\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n#]*)"
    r"|import[ \t]+([\w.]+))",
    re.MULTILINE,
)


@cache
def imported_files(path: Path, root: Path = PACKAGE) -> tuple[Path, ...]:
    """The files of the modules of package ``root`` that the module at ``path`` imports
    (``import``/``from … import``, relative or absolute, read from its text; a package
    whose ``__init__`` finds its modules with ``pkgutil.iter_modules`` imports them all)."""
    try:
        source = path.read_text(encoding="utf-8")
    except (OSError, ValueError):
        return ()
    here = list(path.relative_to(root).parent.parts)
    found: set[Path] = set()
    if path.name == "__init__.py" and "iter_modules(__path__)" in source:
        found.update(f for f in path.parent.glob("*.py") if f != path)
    for m in _IMPORT.finditer(source):
        dots, module, names, plain = m.groups()
        if plain is not None:
            targets = [plain.split(".")[1:]] if _ours(plain, root) else []
        else:
            if dots:
                up = len(dots) - 1
                if up > len(here):
                    continue
                base = here[: len(here) - up] + (module.split(".") if module else [])
            elif _ours(module, root):
                base = module.split(".")[1:]
            else:
                continue
            parts = names.strip("() \t").replace("\n", ",").split(",")
            listed = [n.split()[0] for n in parts if n.strip()]
            targets = [base] + [base + [n] for n in listed if n and n != "*" and n.isidentifier()]
        for dotted in targets:
            f = _module_file(root, dotted)
            if f is not None and f != path:
                found.add(f)
    return tuple(sorted(found))


@cache
def _digest(path: Path) -> bytes:
    return hashlib.sha256(path.read_bytes()).digest()


def _ours(dotted: str, root: Path) -> bool:
    return dotted.split(".")[0] == root.name


@cache
def closure_stamp(path: Path, root: Path = PACKAGE) -> str:
    """A hash of the contents of every module of package ``root`` that the module at
    ``path`` imports, directly or through the modules it imports (``path`` itself aside:
    numba stamps it)."""
    seen: set[Path] = set()
    todo = list(imported_files(path, root))
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        todo.extend(imported_files(f, root))
    seen.discard(path)
    h = hashlib.sha256()
    for f in sorted(seen):
        h.update(str(f.relative_to(root)).encode())
        h.update(_digest(f))
    return h.hexdigest()


# numba's locator list (``CacheImpl``; ``_CacheImpl`` before numba 0.62): ours goes first
_IMPL = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")  # noqa: B009
_NUMBA_LOCATORS = list(_IMPL._locator_classes)


class FollowsImports(caching._CacheLocator):
    """numba's own locator for a hydroarm file, with the stamp of the modules it imports
    added to its source stamp (module doc)."""

    def __init__(self, inner: caching._CacheLocator, py_file: Path) -> None:
        self._inner = inner
        self._py_file = py_file

    def ensure_cache_path(self) -> None:
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        return self._inner.get_cache_path()

    def get_source_stamp(self):
        return (self._inner.get_source_stamp(), closure_stamp(self._py_file))

    def get_disambiguator(self) -> str:
        return self._inner.get_disambiguator()

    @classmethod
    def from_function(cls, py_func, py_file):
        path = Path(py_file).resolve()
        if not path.is_relative_to(PACKAGE):
            return None
        for other in _NUMBA_LOCATORS:
            inner = other.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner, path)
        return None


def install() -> None:
    """Put `FollowsImports` first in numba's locators (once; before any hydroarm function
    is decorated: importing this module installs it, and hydroarm's ``__init__`` imports it
    first)."""
    classes = _IMPL._locator_classes
    if FollowsImports not in classes:
        classes.insert(0, FollowsImports)


install()
