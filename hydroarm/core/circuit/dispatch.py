"""One compiled entry per law, branching on the component's kind code (issue 28).

The laws of every registered component (:mod:`.components`) are gathered into tuples in
kind order, and the dispatchers below unroll over them at compile time (numba's
``literal_unroll``): no closures, and numba caches the result. A component without
``signals`` or ``project`` gets the no-op of this module in its place.
"""

from __future__ import annotations

import warnings

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
