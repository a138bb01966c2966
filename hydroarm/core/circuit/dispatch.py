"""One compiled entry per law, branching on the component's kind code (issue 28).

The laws of every registered component (:mod:`.components`) are gathered into tuples in
kind order, and the dispatchers below unroll over them at compile time (numba's
``literal_unroll``): no closures, and numba caches the result. A component without
``signals`` or ``project`` gets the no-op of this module in its place.

numba's disk cache knows only the file of each function, not the laws compiled into it: a
component added, removed or changed would leave the dispatchers below, and every cached
function that calls them (the system kernel, the steppers), with the old laws. So each of
those is registered with :func:`follows_components`, which keeps beside its cache a stamp
of the component sources and empties that cache when the stamp differs.
"""

from __future__ import annotations

import hashlib
import warnings
from pathlib import Path
from typing import Any

from numba import literal_unroll
from numba.core.errors import NumbaExperimentalFeatureWarning

from .components import TYPES
from .laws import kernel

# the tuples of laws are typed as first-class functions (one signature per tuple)
warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)


@kernel
def no_signals(t, P, po, s, so, port, pn, xm, vm, sig):
    """A component without signal outputs."""
    return None


@kernel
def no_project(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig):
    """A component without a non-smooth part."""
    return None


def _fingerprint() -> str:
    h = hashlib.sha256()
    for name, module in TYPES.items():
        h.update(name.encode())
        h.update(Path(module.__file__ or "").read_bytes())
    h.update(Path(__file__).with_name("laws.py").read_bytes())
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


LAWS = tuple(m.law for m in TYPES.values())
SIGNALS = tuple(getattr(m, "signals", no_signals) for m in TYPES.values())
PROJECTS = tuple(getattr(m, "project", no_project) for m in TYPES.values())
HAS_SIGNALS = {name: hasattr(m, "signals") for name, m in TYPES.items()}
HAS_PROJECT = {name: hasattr(m, "project") for name, m in TYPES.items()}


@kernel
def law_of(kind, t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap):
    """The law of component kind ``kind`` (:mod:`.declare`)."""
    i = 0
    for f in literal_unroll(LAWS):
        if i == kind:
            f(t, c, P, po, s, so, d, port, pn, xm, vm, sig, thr, cap)
        i += 1


@kernel
def signals_of(kind, t, P, po, s, so, port, pn, xm, vm, sig):
    """The signal outputs of component kind ``kind``."""
    i = 0
    for f in literal_unroll(SIGNALS):
        if i == kind:
            f(t, P, po, s, so, port, pn, xm, vm, sig)
        i += 1


@kernel
def project_of(kind, t, h, P, po, s_old, s, so, port, xo, vo, mass, sig):
    """The non-smooth part of a step of component kind ``kind``."""
    i = 0
    for f in literal_unroll(PROJECTS):
        if i == kind:
            f(t, h, P, po, s_old, s, so, port, xo, vo, mass, sig)
        i += 1


follows_components(law_of, signals_of, project_of)
