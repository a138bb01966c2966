"""One compiled entry per law, branching on the component's kind code (issue 28).

The dispatchers ``law_of``, ``signals_of``, ``project_of`` and ``energy_of`` are an if-chain
over the kind codes of every registered component (`components`), each branch a direct
call of that component's law, so that numba compiles them as one function (a tuple of laws
unrolled with ``literal_unroll`` works too, but numba calls its entries as first-class
functions, through a pointer looked up at run time: 20 to 90 times slower, a right-hand side
of 25 components at 1.5 µs instead of 0.4 µs). The laws are compiled into their dispatcher,
and the dispatcher into the system kernel's loop over the components (numba's
``inline="always"``, `inlined_kernel`, on each law's own Python function): a
call copies every field of its array arguments, some 70 words for a law's, which was most of
a step's time (benchmarks/circuit_throughput.py). ``transmit_of`` (the linkages) stays a
call.
A component's branch of ``law_of`` also clears its ports' through variables before its law
and adds them to their nodes' sums after it: the ports and their domains are the
declaration's, so the loops over them are unrolled in the generated source, with no loop
over a component's ports or a node's at run time (benchmarks/servo_throughput.py).
``derive_of`` writes a component's derived quantities (`Derived`) into its block of P,
each formula called with the parameters its arguments name, at offsets taken from the
declaration (`with_derived` runs it once per parameter vector).

The chain's source is generated from the registry and written once to a file named after
the components' fingerprint (in numba's cache folder, or the user's cache), so that numba
caches it like any module and adding a component is adding its module; nothing here lists
them.

numba's disk cache knows only the file of each function, not the laws compiled into it: a
component added, removed or changed would leave every cached function that calls the
dispatchers (the system kernel, the steppers) with the old laws; so would a change to the
system kernel, the tree or the shared laws they compile in (the fingerprint covers those
files too). So each of those is
registered with `follows_components`, which keeps beside its cache a stamp of the
component sources and empties that cache when the stamp differs.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any

from .components import TYPES
from .declare import HYDRAULIC, MECHANICAL


def _fingerprint() -> str:
    h = hashlib.sha256()
    for name, module in TYPES.items():
        h.update(name.encode())
        h.update(Path(module.__file__ or "").read_bytes())
    h.update(Path(__file__).with_name("laws.py").read_bytes())
    h.update(Path(__file__).read_bytes())  # this file: how the dispatchers are made
    # and the files whose kernels the registered functions compile in or link: numba's
    # cache stamps a function with its own file only, so a change to the system kernel or
    # the tree left the steppers' cached copies (integrators/system.py) running the old code
    core = Path(__file__).resolve().parents[1]
    for path in (
        core / "circuit" / "system.py",
        core / "tree.py",
        core / "components.py",
        core / "equations.py",
        core / "kinematics.py",
        core / "trig.py",
        # the one loop's step, compiled into the observers' loop (integrators/observers.py)
        core.parent / "integrators" / "system.py",
    ):
        h.update(path.read_bytes())
    return h.hexdigest()


FINGERPRINT = _fingerprint()


def follows_components(*dispatchers) -> None:
    """Empty the disk cache of these compiled functions when the components changed since
    it was written (module doc); call at import, before they are first called."""
    for f in dispatchers:
        cache: Any = getattr(f, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        if index is None:
            continue
        stamp = Path(index + ".components")
        try:
            if stamp.exists() and stamp.read_text() == FINGERPRINT:
                continue
            cache.flush()
            stamp.write_text(FINGERPRINT)
        except OSError:  # a read-only cache: numba does not cache there either
            cache.disable()


HAS_SIGNALS = {name: hasattr(m, "signals") for name, m in TYPES.items()}
HAS_PROJECT = {name: hasattr(m, "project") for name, m in TYPES.items()}
HAS_TRANSMIT = {name: hasattr(m, "transmit") for name, m in TYPES.items()}
HAS_ENERGY = {name: hasattr(m, "energy") for name, m in TYPES.items()}
HAS_DERIVED = {name: bool(m.DECLARATION.derived) for name, m in TYPES.items()}

#: the node sums ``law_of`` adds each port's through variable and storage to (`_law_branch`)
_SUMS = "qn, cn, fm, mm"
_SIGNATURES = {
    "law": "t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap",
    "signals": "t, P, po, s, so, port, pn, xm, vm, sig",
    "project": "t, h, P, po, s_old, s, so, port, xo, vo, mass, sig, share",
    "transmit": "P, po, q, out",
    "energy": "t, c, P, po, s, so, d, eo, port, pn, xm, vm, sig, thr, cap, pref",
}


def _source() -> str:
    """The dispatchers' source: one if-chain a law, a branch a component kind."""
    lines = [
        '"""Generated by hydroarm.core.circuit.dispatch from the component registry."""',
        "from hydroarm.core.circuit.laws import inlined_kernel, kernel",
    ]
    for kind, module in enumerate(TYPES.values()):
        for law in _SIGNATURES:
            if hasattr(module, law):
                lines.append(f"from {module.__name__} import {law} as {law}_{kind}")
                if law != "transmit":  # compiled into the dispatcher (module doc)
                    lines.append(f"{law}_{kind} = inlined_kernel({law}_{kind}.py_func)")
    for law, args in _SIGNATURES.items():
        decorator = "kernel" if law == "transmit" else "inlined_kernel"
        head = f"{args}, {_SUMS}" if law == "law" else args
        lines += ["", "", f"@{decorator}", f"def {law}_of(kind, {head}):"]
        branches = [k for k, m in enumerate(TYPES.values()) if hasattr(m, law)]
        for j, kind in enumerate(branches):
            lines.append(f"    {'if' if j == 0 else 'elif'} kind == {kind}:")
            if law == "law":
                lines += _law_branch(kind, list(TYPES.values())[kind])
            else:
                lines.append(f"        {law}_{kind}({args})")
        if not branches:
            lines.append("    return None")
    lines += _derive_source()
    return "\n".join(lines) + "\n"


def _law_branch(kind: int, module: ModuleType) -> list[str]:
    """A component's branch of ``law_of``: its ports' through variables and storages
    cleared, its law, then each added to its node's sums (``qn``, ``cn`` at a hydraulic
    port's node, ``fm``, ``mm`` at a mechanical one's), port by port: as the components run
    in law order, each node's sums add its ports in law order, then port order, from 0. The
    ports and their domains are the declaration's, so the loops over them are unrolled
    here: a loop over a component's ports, and one over each node's ports after the laws,
    took a fifth of a right-hand side (benchmarks/servo_throughput.py)."""
    ports = module.DECLARATION.ports
    body = [f"        thr[c, {k}] = 0.0\n        cap[c, {k}] = 0.0" for k in range(len(ports))]
    body.append(f"        law_{kind}({_SIGNATURES['law']})")
    for k, p in enumerate(ports):
        if p.domain == HYDRAULIC:
            sums = ("qn", "cn")
        elif p.domain in MECHANICAL:
            sums = ("fm", "mm")
        else:
            continue
        body.append(f"        {sums[0]}[port[{k}]] += thr[c, {k}]")
        body.append(f"        {sums[1]}[port[{k}]] += cap[c, {k}]")
    return body


def _derive_source() -> list[str]:
    """``derive_of(kind, P, po)``: each derived quantity of the component at ``po`` from its
    parameters, in declaration order (a later one may read an earlier one from P)."""
    lines: list[str] = []
    body: list[str] = []
    for kind, module in enumerate(TYPES.values()):
        decl = module.DECLARATION
        if not decl.derived:
            continue
        par, _, _ = decl.indices()
        lines.append(f"from {module.__name__} import DECLARATION as declaration_{kind}")
        body.append(f"    {'if' if not body else 'elif'} kind == {kind}:")
        for j, q in enumerate(decl.derived):
            name = f"derive_{kind}_{j}"
            lines.append(f"{name} = inlined_kernel(declaration_{kind}.derived[{j}].formula)")
            args = ", ".join(f"P[po + {getattr(par, a)}]" for a in q.arguments)
            body.append(f"        P[po + {getattr(par, q.name)}] = {name}({args})")
    return [
        *lines,
        "",
        "",
        "@inlined_kernel",
        "def derive_of(kind, P, po):",
        *(body or ["    return None"]),
    ]


def _cache_folder() -> Path:
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return Path(env) / "hydroarm-dispatch"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hydroarm" / "dispatch"


def _load_generated() -> ModuleType:
    source = _source()
    tag = hashlib.sha256((FINGERPRINT + source).encode()).hexdigest()[:16]
    name = f"hydroarm_dispatch_{tag}"
    for folder in (_cache_folder(), Path(tempfile.gettempdir()) / "hydroarm-dispatch"):
        path = folder / f"{name}.py"
        try:
            if not path.exists() or path.read_text() != source:
                folder.mkdir(parents=True, exist_ok=True)
                fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
                with os.fdopen(fd, "w") as f:
                    f.write(source)
                os.replace(tmp, path)
            break
        except OSError:
            continue
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


_generated = _load_generated()
law_of = _generated.law_of
signals_of = _generated.signals_of
project_of = _generated.project_of
transmit_of = _generated.transmit_of
energy_of = _generated.energy_of
derive_of = _generated.derive_of
