"""The integration methods, registered in one place behind one ``run`` signature.

Every spelling of a method elsewhere in hydroarm comes from `METHODS`: the names a
scenario, a file or the command line accepts, and the integer codes that the compiled
kernels branch on (`EULER`,
`RK4`, frozen by numba as globals).

========== ============ ==========================================================
name       fixed step   reference
========== ============ ==========================================================
euler      yes          the paper's eqs. (5)–(7): semi-implicit Euler, first order
rk4        yes          classical fourth-order Runge–Kutta
adaptive   no           scipy's Radau IIA (order 5), the stiff-safe reference
========== ============ ==========================================================
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from typing import IO, NamedTuple

import numpy as np
from numba.core import event as numba_event

from ..core.lever import evaluate_many
from ..errors import HydroarmError
from .adaptive import integrate_adaptive
from .fixed import EULER, RK4, integrate

ADAPTIVE = 2  # code of the adaptive reference (never passed to a compiled kernel)


class Method(NamedTuple):
    """One integration method."""

    name: str  # the name a scenario, a file and the CLI use
    code: int  # the integer the compiled kernels branch on
    fixed_step: bool  # True: a fixed step T; False: T is only the output interval
    description: str  # one line, for help texts
    reference: str  # where the scheme comes from


METHODS: dict[str, Method] = {
    m.name: m
    for m in (
        Method(
            "euler",
            EULER,
            True,
            "the paper's rectangular scheme, pressure then velocity then angle",
            "the paper's eqs. (5)-(7), Appendix I: semi-implicit (symplectic) Euler, order 1",
        ),
        Method(
            "rk4",
            RK4,
            True,
            "classical Runge-Kutta on the same right-hand side",
            "classical fourth-order Runge-Kutta",
        ),
        Method(
            "adaptive",
            ADAPTIVE,
            False,
            "stiff-safe adaptive reference; the step is the output interval",
            "scipy.integrate.solve_ivp, method 'Radau' (Radau IIA, order 5)",
        ),
    )
}


def method(name: str) -> Method:
    """The registered method called ``name``; any other name: one clear
    [`HydroarmError`][hydroarm.HydroarmError]."""
    try:
        return METHODS[name]
    except (KeyError, TypeError):
        raise HydroarmError(
            "solver.method", f"must be one of {', '.join(METHODS)}, got {name!r}"
        ) from None


def method_names() -> tuple[str, ...]:
    """Every registered method name, in registry order."""
    return tuple(METHODS)


def fixed_step_methods() -> tuple[str, ...]:
    """The names of the fixed-step methods (those the compiled kernels run)."""
    return tuple(m.name for m in METHODS.values() if m.fixed_step)


def run(
    name: str,
    theta0: float,
    omega0: float,
    p0: float,
    t0: float,
    h: float,
    nsteps: int,
    record_every: int,
    tab_t: np.ndarray,
    tab_y: np.ndarray,
    sine: np.ndarray,
    J,
    L,
):
    """Integrate one joint with the method ``name``: the one run signature of every method.

    Fixed-step methods take ``nsteps`` steps of ``h``; the adaptive reference integrates the
    same span and is sampled at the same output times (every ``record_every``-th step).
    Returns (t, θ₂, ω, p, y, bad_step) as `integrate`:
    bad_step is −1 or the first step whose state was not finite (the adaptive method: −1).
    """
    m = method(name)
    if m.fixed_step:
        return integrate(
            m.code, theta0, omega0, p0, t0, h, nsteps, record_every, tab_t, tab_y, sine, J, L
        )
    if J.dry_friction or math.isfinite(J.end_stop_angle):
        raise HydroarmError(
            "solver.method",
            f"'{m.name}' cannot integrate dry friction or end stops (non-smooth physics); "
            f"use {' or '.join(repr(n) for n in fixed_step_methods())}",
        )
    n = nsteps // record_every
    t = t0 + np.arange(n + 1) * h * record_every
    th, om, pp = integrate_adaptive(
        theta0, omega0, p0, t0, float(t[-1]), t, tab_t, tab_y, sine, J, L
    )
    return t, th, om, pp, evaluate_many(t, tab_t, tab_y, sine), -1


def compiled_on_disk(kernel) -> bool:
    """Whether a numba kernel (``cache=True``) has compiled code in numba's on-disk cache, as
    far as its cache index tells (True when it cannot be told: no notice then)."""
    try:
        return os.path.exists(kernel._cache._cache_file._index_path)
    except AttributeError:  # another numba version or a kernel without a disk cache
        return True


#: what a compile notice calls the kernel numba starts compiling, by the module of that
#: kernel (the first prefix that matches): the entry point a command calls from Python, so
#: a circuit, component servo, arm or mechanism file names the system kernel
KERNEL_FAMILIES: tuple[tuple[tuple[str, ...], str], ...] = (
    (
        ("hydroarm.integrators.system", "hydroarm.core.circuit", "hydroarm_dispatch_"),
        "the circuit system kernel",
    ),
    (("hydroarm.core.tree",), "the mechanism kernels"),
    # the old servo kernel and arm loop, held apart for the tests and benchmarks
    (("hydroarm.reference",), "the reference kernels"),
    (("hydroarm.",), "the single-joint kernels"),
)


def kernel_family(module: str) -> str:
    """The family of `KERNEL_FAMILIES` a kernel defined in ``module`` belongs to."""
    for prefixes, name in KERNEL_FAMILIES:
        if module.startswith(prefixes):
            return name
    return "the simulation kernels"


def compile_notice_line(family: str) -> str:
    """The one line of `CompileNotice` (the same on a terminal and in a log)."""
    return (
        f"hydroarm: compiling {family} for first use (numba, once: a minute or two on a small "
        "machine; later runs load the cached code in about a second; `hydroarm warmup` "
        "compiles every kernel ahead)"
    )


def _disk_cached(dispatcher) -> bool:
    """Whether a numba dispatcher keeps its compiled code on disk (``cache=True``)."""
    return getattr(getattr(dispatcher, "_cache", None), "_cache_file", None) is not None


class CompileNotice(numba_event.Listener):
    """One line on ``stream()`` when numba starts compiling a disk-cached kernel, i.e. when a
    command is about to wait for a compilation its cache cannot spare it: numba's
    ``numba:compile`` event fires after the cache lookup missed and before the compiler runs.
    At most one line between `install` and `remove`; nothing when every kernel
    the command calls is loaded from the cache (functions compiled without a cache, numba's
    own helpers, compile in every process and are not announced). ``stream`` is called at
    print time (sys.stderr as it is then)."""

    def __init__(self, stream: Callable[[], IO[str]] = lambda: sys.stderr) -> None:
        self.stream = stream
        self.said: str | None = None  # the line printed, if any
        self.listening = False

    def on_start(self, event) -> None:
        if self.said is not None:
            return
        data = event.data if isinstance(event.data, dict) else {}
        dispatcher = data.get("dispatcher")
        if dispatcher is None or not _disk_cached(dispatcher):
            return
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        self.said = compile_notice_line(kernel_family(module))
        try:
            out = self.stream()
            print(self.said, file=out, flush=True)
        except (OSError, ValueError):  # a closed or broken stderr: the run goes on
            pass

    def on_end(self, event) -> None:
        pass

    def install(self) -> None:
        """Listen from now on (again: a new line may be printed)."""
        self.said = None
        if not self.listening:
            numba_event.register("numba:compile", self)
            self.listening = True

    def remove(self) -> None:
        """Stop listening (nothing if not listening)."""
        if self.listening:
            numba_event.unregister("numba:compile", self)
            self.listening = False
