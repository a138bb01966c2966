"""numba's disk cache follows the sources a kernel compiles in (hydroarm.core.jit_cache).

The case that made it: ``core/components.py``'s cached valve laws kept an older
``signed_sqrt`` of ``core/equations.py`` after it changed (numba stamps a function with its own
file), and the excavator's operating point then failed to solve."""

from __future__ import annotations

from pathlib import Path

import pytest

import hydroarm.core.components as components
from hydroarm.core import jit_cache


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """A package ``pkg``: ``a`` imports ``b`` (relative), ``c`` (absolute, names in brackets
    over lines, a comment among them), ``d`` (``import pkg.d``) and the subpackage ``sub``,
    which finds its modules itself; ``b`` imports ``deep``; ``e`` is imported by nobody."""
    root = tmp_path / "pkg"
    (root / "sub").mkdir(parents=True)
    files = {
        "__init__.py": "",
        "a.py": (
            "import numpy as np\nfrom .b import f\nfrom pkg.c import (\n    g,  # note\n"
            "    h,\n)\nimport pkg.d\nfrom . import sub\n\ndef run():\n    return f()\n"
        ),
        "b.py": "from .deep import k\n\ndef f():\n    return k\n",
        "c.py": "g = h = 1\n",
        "d.py": "",
        "deep.py": "k = 1\n",
        "e.py": "x = 1\n",
        "sub/__init__.py": "import pkgutil\nfor i in pkgutil.iter_modules(__path__):\n    pass\n",
        "sub/x.py": "",
    }
    for name, text in files.items():
        (root / name).write_text(text)
    jit_cache.imported_files.cache_clear()
    jit_cache.closure_stamp.cache_clear()
    jit_cache._digest.cache_clear()
    yield root
    jit_cache.imported_files.cache_clear()
    jit_cache.closure_stamp.cache_clear()
    jit_cache._digest.cache_clear()


def test_a_modules_imports_are_read_from_its_text(package):
    got = {
        f.relative_to(package).as_posix()
        for f in jit_cache.imported_files(package / "a.py", package)
    }
    assert got == {"__init__.py", "b.py", "c.py", "d.py", "sub/__init__.py"}
    sub = jit_cache.imported_files(package / "sub" / "__init__.py", package)
    assert [f.name for f in sub] == ["x.py"]


def _stamp(package: Path) -> str:
    jit_cache.closure_stamp.cache_clear()
    jit_cache._digest.cache_clear()
    return jit_cache.closure_stamp(package / "a.py", package)


def test_the_stamp_follows_what_is_imported_at_any_depth_and_nothing_else(package):
    before = _stamp(package)
    (package / "e.py").write_text("x = 2\n")  # imported by nobody
    assert _stamp(package) == before
    (package / "deep.py").write_text("k = 2\n")  # a -> b -> deep
    changed = _stamp(package)
    assert changed != before
    (package / "sub" / "x.py").write_text("y = 1\n")  # found by its package
    assert _stamp(package) != changed


def test_hydroarms_kernels_are_cached_with_the_stamp_of_their_imports():
    locator = components.edge_flow._cache._impl.locator
    assert isinstance(locator, jit_cache.FollowsImports)
    own, imports = locator.get_source_stamp()
    assert imports == jit_cache.closure_stamp(Path(components.__file__).resolve())
    # the case that made it: the valve laws compile in core/equations.py's signed_sqrt
    names = {f.name for f in jit_cache.imported_files(Path(components.__file__).resolve())}
    assert "equations.py" in names
