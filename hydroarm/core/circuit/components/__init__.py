"""The circuit component library: one module a component (issue 28; docs/components.md).

Every module of this package that defines ``DECLARATION`` is a component type; the registry
below finds them, so that adding a component is adding its module (with its test and its
docs page): its kind code, file keys, sweep names and docs table follow from the module.
Kind codes are the positions of the types in name order.
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType


def _discover() -> dict[str, ModuleType]:
    found: dict[str, ModuleType] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        decl = getattr(module, "DECLARATION", None)
        if decl is None:
            continue
        if decl.type in found:
            raise ImportError(f"component type {decl.type!r} declared twice")
        found[decl.type] = module
    return dict(sorted(found.items()))


TYPES: dict[str, ModuleType] = _discover()
KIND: dict[str, int] = {name: i for i, name in enumerate(TYPES)}
