"""Static states of a circuit: ṡ = 0 solved on the system kernel (issue 29; docs/linear.md).

`steady_state` finds the state at which every derivative of the circuit's right-hand
side (`hydroarm.integrators.system.derivatives_at`, the one physics) vanishes, with the
inputs held at their values at a time t, some mechanical positions optionally pinned at a
pose and some inputs optionally freed to hold it (a reference that holds a servo at 0.7 m):

1. every ``signal_source`` is frozen at its value at t (``waveform = constant``, its
   ``offset`` that value): the inputs as parameters (`frozen_parameters`);
2. the states the kernel never moves are *held* (a tank's node, a latch, an algebraic spool
   or static relief opening: a zero row of the Jacobian at two points; a linkage's slave, a
   coupled joint); the projection sets them (`system_project` with h = 0), at every trial state of
   the solve, so that they follow the unknowns; a line's wave history is filled with the static
   state's waves (`line_flows`). A component state that no derivative reads, its own included (a
   PID's ∫e dt at K_i = 0), is an *accumulator*: held, its rate no condition;
3. a first guess: a run of the frozen circuit from the initial state (or the caller's) for
   the circuit's duration or `SETTLE_TIME`, whichever is longer (at most
   `SETTLE_STEPS` steps), so that pump-fed nodes start near their relief settings and
   controllers near their balance, however short a run the user asks for;
4. least squares (scipy ``least_squares``, trust region) on the rows of ṡ, each row divided by
   its Jacobian row's norm in scaled states (a residual is then the relative change of state
   that would cancel it), the unknowns scaled by `state_scales`; Jacobians by central
   differences (`jacobian`); then Newton steps with finer differences (`newton_polish`),
   which land on a kink of a law (a closed valve at null, a pump at zero stroke) where the
   trust region stops short of it;
5. *floating levels*: directions v with J·v = 0 that leave ṡ unchanged for a shift of 10 % of
   their scale (a node pair sealed with no leakage path: their common pressure level; a load
   held by a closed valve: its position) are reported, not solved for; a floating pressure
   level is set at mid-pressure (Merritt's null: p_A + p_B = p_s + p_T for a servo's
   chambers);
6. checks: the residual below `RESIDUAL_TOL`, every absolute pressure at or above the
   cavitation pressure and at most `pressure_ceiling`, every position within its
   actuator's stroke; otherwise a one-line [`HydroarmError`][hydroarm.HydroarmError].
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..core.circuit.components import TYPES
from ..core.circuit.system import (
    SYS,
    all_laws,
    evaluate_signals,
    make_work,
    system_project,
    with_derived,
)
from ..errors import HydroarmError
from ..integrators.system import derivatives_at, integrate, stepper

#: central-difference step, a fraction of each state's scale: ε^(1/3) balances the O(h²)
#: truncation against the O(ε/h) rounding of a central difference (Nocedal and Wright 2006,
#: Numerical Optimization, §8.1)
FD_STEP = float(np.finfo(float).eps) ** (1.0 / 3.0)
#: largest residual of a static state: the relative change of state that would cancel the
#: worst row (module doc, step 4). The solve (`newton_polish` last) ends at 1e-12 or less on
#: every example with a static state (the excavator's 7e-13 on its valves' and pump's kinks,
#: 1e-15 to 0 elsewhere: the rows' round-off), four decades below; a circuit that moves
#: leaves far more (the boom's open lever 0.31, two_actuators' run end 4.6e-4)
RESIDUAL_TOL = 1e-8
#: a singular value below this fraction of the largest is a candidate null direction
NULL_CANDIDATE = 1e-6
#: central-difference step of the Newton polish, in scaled unknowns: √ε, so that its
#: Jacobian resolves a kink of a law (a closed-centre spool at null, a compensator at zero
#: stroke, an edge's opening clipped at 0) from 1e-8 of its scale on, where `FD_STEP` (6e-6)
#: straddles one and averages its two slopes; its rounding, ε/h = √ε relative, only slows
#: Newton's convergence by that factor
POLISH_STEP = float(np.sqrt(np.finfo(float).eps))
#: at most this many Newton steps of the polish
POLISH_STEPS = 12
#: a candidate is a floating level when a shift of this fraction of its scale changes no row
#: by more than FLOAT_TOL (scaled as the residuals)
FLOAT_SHIFT = 0.1
FLOAT_TOL = 1e-9
#: at most this many steps in the settling run of the first guess
SETTLE_STEPS = 400_000
#: the shortest settling run of the first guess [s]: a run shortened with --duration starts
#: from the same guess as a long one (the excavator's PID loops and compensator need about
#: 0.5 s from its file's pose; a 0.02 s run left the solve 0.11 off)
SETTLE_TIME = 1.0

_SOURCE = TYPES["signal_source"]
_LINE = TYPES["line"]


@dataclass
class SteadyState:
    """A static state of a compiled circuit: ``state`` (the full state vector, SI), ``P``
    (the parameter vector with the inputs frozen at ``t`` and the freed inputs at their
    solved values), ``inputs`` (freed input name → value), ``held`` (mask of the states the
    kernel never moves), ``floating`` (null directions: (label, vector over the states)),
    ``residual`` (largest scaled residual) and ``notes``."""

    state: np.ndarray
    P: np.ndarray
    t: float
    inputs: dict[str, float]
    held: np.ndarray
    floating: list[tuple[str, np.ndarray]] = field(default_factory=list)
    residual: float = 0.0
    notes: list[str] = field(default_factory=list)


# ------------------------------------------------------------------- helpers ---
def component_index(compiled, name: str) -> int:
    for i, c in enumerate(compiled.circuit.components):
        if c.name == name:
            return i
    raise HydroarmError("input", f"{name!r}: no component of that name")


def source_offset_index(compiled, name: str) -> int:
    """The index in P of a signal source's ``offset`` (its value once frozen)."""
    ci = component_index(compiled, name)
    if compiled.circuit.components[ci].type != "signal_source":
        raise HydroarmError("input", f"{name!r} is not a signal_source")
    return compiled.poff[ci] + _SOURCE.par.offset


def frozen_parameters(compiled, t: float, P: np.ndarray | None = None) -> np.ndarray:
    """P with every signal source held at its value at t (a constant): inputs as
    parameters, so that a steady state exists and an input can be perturbed."""
    P = (compiled.P if P is None else P).copy()
    for ci, c in enumerate(compiled.circuit.components):
        if c.type == "signal_source":
            po = compiled.poff[ci]
            v = float(_SOURCE.value(t, P, po))
            P[po + _SOURCE.par.waveform] = _SOURCE.CONSTANT
            P[po + _SOURCE.par.offset] = v
    return P


def signal_values(compiled, t: float, s: np.ndarray, P: np.ndarray) -> dict[str, float]:
    """Every signal's value at (t, s), by name."""
    work = make_work(compiled.net)
    evaluate_signals(t, s, with_derived(P, compiled.net), compiled.net, work)
    sig = work[3]
    return {name: float(sig[i]) for name, i in compiled.signals.items()}


def _evaluated(compiled, t: float, s: np.ndarray, P: np.ndarray, laws: bool):
    """The kernel's work arrays (`hydroarm.core.circuit.system.make_work`) at (t, s) after
    its signals (`evaluate_signals`: node values, each linkage's slave from its master) and,
    with ``laws``, every component's law (`all_laws`): the first half of the right-hand side."""
    net = compiled.net
    work = make_work(net)
    PP = with_derived(P, net)
    evaluate_signals(t, s, PP, net, work)
    if laws:
        pn, xm, vm, sig, thr, cap, qn, cn, fm, mm = work[:10]  # the node sums start at 0
        all_laws(t, s, PP, np.zeros(s.size), net[28], net[3], pn, xm, vm, sig, thr, cap,
                 qn, cn, fm, mm)  # fmt: skip
    return work


def node_positions(compiled, t: float, s: np.ndarray, P: np.ndarray) -> dict[str, float]:
    """Every mechanical node's position [m or rad] at (t, s), by name: its state, or where
    its linkage puts it (a crank's rod: the linkage's ``transmit`` law), unclipped (the
    stops act in the projection)."""
    xm = _evaluated(compiled, t, s, P, laws=False)[1]
    return {name: float(xm[m]) for name, m in compiled.mechanical.items()}


def linkage_levers(compiled, t: float, s: np.ndarray, P: np.ndarray) -> dict[str, float]:
    """Each linkage's slave node (by name) → its force lever at (t, s): the factor [m, or
    none] from a force on the slave to the force or torque on its master (a crank's torque
    arm: its ``transmit`` law's fourth output)."""
    gf = _evaluated(compiled, t, s, P, laws=False)[19]
    names = list(compiled.mechanical)
    return {names[sl]: float(gf[k]) for k, sl in enumerate(compiled.slaves[:, 0])}


def compliances(compiled, t: float, s: np.ndarray, P: np.ndarray) -> np.ndarray:
    """(components × ports): the compliance [m³/Pa] each component's law adds at each of its
    hydraulic ports at (t, s) (a chamber's V/β_e), its mass [kg or kg m²] at a mechanical
    port: the ``cap`` its law writes (`hydroarm.core.circuit.declare`)."""
    return _evaluated(compiled, t, s, P, laws=True)[5].copy()


def project(compiled, t: float, s: np.ndarray, P: np.ndarray) -> np.ndarray:
    """The state after the kernel's projection with h = 0 (latches, algebraic states, tanks'
    nodes, filters settled)."""
    out = s.copy()
    PP = with_derived(P, compiled.net)
    system_project(t, 0.0, s.copy(), out, PP, compiled.net, make_work(compiled.net), 1.0)
    return out


def line_flows(compiled, s: np.ndarray, P: np.ndarray) -> np.ndarray:
    """P with each ``line``'s ``initial_flow`` set to the flow its end pressures drive
    through its laminar resistance at rest, q = (p_a − p_b)/R (a lossless line keeps its
    own): the kernel's projection at h = 0 then fills the line's wave history with the
    static state's waves, p_mean ± Z·q, a line at rest carrying a steady flow with no wave
    in flight. (Filled from ``initial_flow`` as a run's start fills it, a closed line at
    rest would hold the waves of the flow it started with, and no static state would
    close: the water-hammer pipe's 0.018.)"""
    out = P
    for ci, c in enumerate(compiled.circuit.components):
        if c.type != "line":
            continue
        po = int(compiled.poff[ci])
        _, r_half, _, _, _, _ = _LINE.line_constants(P, po)
        if r_half <= 0.0:
            continue
        if out is P:
            out = P.copy()
        ia, ib = compiled.hydraulic[c.ports["a"]], compiled.hydraulic[c.ports["b"]]
        out[po + _LINE.par.initial_flow] = (s[ia] - s[ib]) / (2.0 * r_half)
    return out


def steady_lines(compiled, t: float, s: np.ndarray, P: np.ndarray) -> None:
    """Each line's wave history, in place, the static state's at the state's end pressures
    (`line_flows`; the line's own projection at h = 0)."""
    PP = line_flows(compiled, s, P)
    if PP is P:
        return
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    ports = compiled.net[3]
    for ci, c in enumerate(compiled.circuit.components):
        if c.type == "line":
            po, so = int(compiled.poff[ci]), int(compiled.soff[ci])
            mass, sig = np.zeros(max(nm, 1)), np.zeros(1)
            _LINE.project(t, 0.0, PP, po, s, s, so, ports[ci], nh, nh + nm, mass, sig, 1.0)


def strokes(compiled) -> dict[str, tuple[float, float, str]]:
    """Mechanical node → (lowest, highest position, the cylinder) of the cylinders on it."""
    out: dict[str, tuple[float, float, str]] = {}
    for ci, c in enumerate(compiled.circuit.components):
        if c.type == "cylinder":
            v = compiled.values[ci]
            lo = v["position_at_a_end"]
            out[c.ports["rod"]] = (lo, lo + v["stroke"], c.name)
    return out


def pressure_ceiling(compiled, P: np.ndarray) -> float:
    """The highest absolute pressure a static state may hold: the highest tank pressure or,
    where a relief valve guards a node, 1.5 × its cracking pressure (room for its override);
    inf for a circuit with a pump or flow source and no relief valve."""
    tanks = [1.0e5]
    reliefs = []
    flow_sources = False
    for ci, c in enumerate(compiled.circuit.components):
        v = compiled.values[ci]
        if c.type == "tank":
            tanks.append(v["pressure"])
        elif c.type in ("relief_valve", "counterbalance_valve"):
            reliefs.append(v.get("cracking_pressure", v.get("setting", 0.0)))
        elif c.type in ("fixed_pump", "variable_pump", "flow_source"):
            flow_sources = True
    if flow_sources and not reliefs:
        return math.inf
    return max(max(tanks), 1.5 * max(reliefs, default=0.0))


def state_scales(compiled, P: np.ndarray) -> np.ndarray:
    """A typical magnitude of every state (finite-difference steps, the solve's scaling):
    pressures the ceiling's (at least 10 bar), positions and velocities the stroke's (1 m or
    1 rad without a cylinder; a velocity's per second), component states their declared
    scale."""
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    ceiling = pressure_ceiling(compiled, P)
    p = ceiling if math.isfinite(ceiling) else 1.0e7
    sc = np.ones(len(compiled.s0))
    sc[:nh] = max(p, 1.0e6)
    st = strokes(compiled)
    for name, m in compiled.mechanical.items():
        length = st[name][1] - st[name][0] if name in st else 1.0
        sc[nh + m] = length
        sc[nh + nm + m] = length
    for ci, (decl, vals) in enumerate(zip(compiled.decls, compiled.values, strict=True)):
        j = compiled.soff[ci]
        for state, n in zip(decl.states, decl.state_count(vals), strict=True):
            sc[j : j + n] = state.scale
            j += n
    return sc


def rhs(compiled, t: float, s: np.ndarray, P: np.ndarray) -> np.ndarray:
    """ṡ at (t, s): the system kernel's right-hand side."""
    return np.asarray(derivatives_at(t, s, P, compiled.net))


def jacobian(f, x: np.ndarray, scale: np.ndarray, cols=None, step: float = FD_STEP) -> np.ndarray:
    """∂f/∂x by central differences, step ``step`` (`FD_STEP`) × scale per column."""
    cols = range(x.size) if cols is None else cols
    cols = list(cols)
    out = None
    for j, i in enumerate(cols):
        h = step * scale[i]
        xp = x.copy()
        xm = x.copy()
        xp[i] += h
        xm[i] -= h
        col = (np.asarray(f(xp)) - np.asarray(f(xm))) / (2.0 * h)
        if out is None:
            out = np.empty((col.size, len(cols)))
        out[:, j] = col
    assert out is not None
    return out


def held_states(compiled, t: float, s: np.ndarray, P: np.ndarray, scale) -> np.ndarray:
    """Mask of the states the kernel never moves: a tank's node, and every state whose row
    of the Jacobian and whose derivative vanish at s and at a shifted s (latches, algebraic
    states; module doc), every component state no derivative reads (an accumulator), and
    the nodes a linkage positions from its master and the joints
    coupled to another (set by the kernel, as a tank's node)."""
    n = s.size
    nh = len(compiled.hydraulic)
    held = np.zeros(n, bool)
    held[:nh] = compiled.fixed != 0
    rng = np.random.default_rng(29)
    zero = np.ones(n, bool)
    unread = np.ones(n, bool)
    for s_at in (s, s + 1e-3 * scale * rng.standard_normal(n)):
        J = jacobian(lambda x: rhs(compiled, t, x, P), s_at, scale)
        zero &= np.all(J == 0.0, axis=1) & (rhs(compiled, t, s_at, P) == 0.0)
        unread &= np.all(J == 0.0, axis=0)
    nm = len(compiled.mechanical)
    zero[nh : nh + 2 * nm] = False  # mechanics always move
    # an accumulator: a component's state no derivative reads, its own included (a PID's
    # ∫e dt at K_i = 0): it is no part of a static state, and its rate (there the error)
    # no condition on one (a proportional loop holds a load with an error)
    unread[: nh + 2 * nm] = False
    zero |= unread
    for slave in compiled.slaves[:, 0]:  # but a linkage's slave follows its master
        held[nh + slave] = held[nh + nm + slave] = True
    for joint in compiled.couplings[:, 0]:  # and so does a coupled joint
        held[nh + joint] = held[nh + nm + joint] = True
    return held | zero


def _settle(compiled, t: float, s: np.ndarray, P: np.ndarray) -> np.ndarray | None:
    c = compiled.circuit
    method = c.method if c.method != "adaptive" else "rk4"
    n = max(2, min(int(round(max(c.duration, SETTLE_TIME) / c.step)), SETTLE_STEPS))
    code, A, b, cc = stepper(method)
    _, S, bad = integrate(code, A, b, cc, s, t, c.step, n, n, P, compiled.net)
    end = S[-1]
    if bad >= 0 or not np.all(np.isfinite(end)):
        return None
    return end


# --------------------------------------------------------------- the solve ---
def _pins_on_masters(compiled, pin: dict, field_name: str) -> dict:
    """The pins with a coupled joint's pin moved to its master, q_m = (q_s − offset)/ratio (a
    coupled joint is set by the kernel from its master); a joint held by a ratio-0 coupling
    can be pinned only at its offset."""
    mech = compiled.mechanism
    if mech is None or not mech.couplings.size:
        return pin
    out = {}
    for name, x in pin.items():
        j = compiled.mechanical[name]
        if j >= mech.n or mech.master[j] == j:
            out[name] = x
            continue
        r, o = float(mech.ratio[j]), float(mech.offset[j])
        if r == 0.0:
            if x != o:
                raise HydroarmError(
                    field_name, f"{name!r} is held at {o:g} by its coupling: it cannot be at {x:g}"
                )
            continue
        out[mech.joint_names[mech.master[j]]] = (x - o) / r
    return out


def steady_state(
    compiled,
    t: float = 0.0,
    pin: Mapping[str, float] | None = None,
    free: Sequence[str] = (),
    guess: np.ndarray | None = None,
    P: np.ndarray | None = None,
    settle: bool = True,
    field_name: str = "operating point",
) -> SteadyState:
    """The static state of a compiled circuit (module doc). ``pin``: mechanical node →
    position [m or rad] held there at rest; ``free``: signal sources whose (frozen) value is
    solved for as well (the reference that holds a pinned pose); ``guess``: a state to start
    from (default the circuit's initial state); ``P``: a parameter vector to start from
    (default the circuit's); ``settle``: run the frozen circuit first (step 3).
    ``field_name`` names the errors' field."""
    pin = dict(pin or {})
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    n = len(compiled.s0)
    P0 = frozen_parameters(compiled, t, P)
    st = strokes(compiled)
    for name, x in pin.items():
        if name not in compiled.mechanical:
            raise HydroarmError(
                field_name, f"{name!r} is not a mechanical node ({', '.join(compiled.mechanical)})"
            )
        if name in st and not st[name][0] <= x <= st[name][1]:
            lo, hi, cyl = st[name]
            raise HydroarmError(
                field_name,
                f"{x:g} is outside the stroke of {cyl} ({lo:g} … {hi:g}) at node {name!r}",
            )
    pin = _pins_on_masters(compiled, pin, field_name)
    free_idx = [source_offset_index(compiled, name) for name in free]
    s = (compiled.s0 if guess is None else guess).astype(float).copy()
    for name, x in pin.items():
        s[nh + compiled.mechanical[name]] = x
        s[nh + nm + compiled.mechanical[name]] = 0.0

    def proj(x, P):  # the kernel's projection at h = 0, each line's history at rest
        return project(compiled, t, x, line_flows(compiled, x, P))

    # a freed reference read by a PID whose measurement senses a pinned node starts at the
    # measurement there (the reference that would hold the pose with no error)
    sig = signal_values(compiled, t, proj(s, P0), P0)
    for name, k in zip(free, free_idx, strict=True):
        ci = component_index(compiled, name)
        out = compiled.circuit.components[ci].ports["out"]
        for c in compiled.circuit.components:
            if c.type == "pid" and c.ports.get("reference") == out:
                P0[k] = sig[c.ports["measurement"]]
    s = proj(s, P0)
    if settle:
        end = _settle(compiled, t, s, P0)
        if end is not None:
            if pin:  # the run's pressures and states, the pose put back
                for name, x in pin.items():
                    end[nh + compiled.mechanical[name]] = x
                    end[nh + nm + compiled.mechanical[name]] = 0.0
            s = proj(end, P0)
    scale = state_scales(compiled, P0)
    held = held_states(compiled, t, s, P0, scale)
    pinned = np.zeros(n, bool)
    for name in pin:
        pinned[nh + compiled.mechanical[name]] = True
        pinned[nh + nm + compiled.mechanical[name]] = True
    unknown = np.nonzero(~held & ~pinned)[0]
    rows = np.nonzero(~held)[0]
    rows = np.array([i for i in rows if not (pinned[i] and i < nh + nm)], np.int64)
    floor = max(P0[SYS.cavitation_pressure], 1.0)
    u_scale = np.array([max(abs(P0[k]), 1e-3) for k in free_idx])

    def unpack(z, s_base, P_base):
        ss = s_base.copy()
        ss[unknown] = s_base[unknown] + z[: unknown.size] * scale[unknown]
        PP = P_base.copy()
        for j, k in enumerate(free_idx):
            PP[k] = P_base[k] + z[unknown.size + j] * u_scale[j]
        return ss, PP

    residual = math.inf
    floating: list[tuple[str, np.ndarray]] = []
    norm = np.ones(rows.size)
    for _ in range(4):  # re-solve while the projection changes a held state (a latch)
        s_base, P_base = s.copy(), P0.copy()
        z0 = np.zeros(unknown.size + len(free_idx))

        def raw(z, s_base=s_base, P_base=P_base):
            ss, PP = unpack(z, s_base, P_base)
            # the held states follow the unknowns as the kernel's projection sets them (an
            # algebraic spool from its command, a static relief's opening from its
            # pressure, a slave from its master, a line's history from its ends)
            ss[held] = proj(ss, PP)[held]
            return rhs(compiled, t, ss, PP)[rows]

        J0 = jacobian(raw, z0, np.ones(z0.size))
        norm = np.sum(np.abs(J0), axis=1)
        norm = np.maximum(norm, 1e-12 * max(float(np.max(norm, initial=0.0)), 1e-300))

        def res(z, raw=raw, norm=norm):
            return raw(z) / norm

        def jac(z, raw=raw, norm=norm):
            return jacobian(raw, z, np.ones(z.size)) / norm[:, None]

        z = z0
        if np.max(np.abs(res(z0))) > RESIDUAL_TOL * 1e-3:
            lower = np.full(z0.size, -np.inf)  # pressures stay at or above the floor
            for j, i in enumerate(unknown):
                if i < nh:
                    lower[j] = min((floor - s_base[i]) / scale[i], 0.0)
            sol = bounded_least_squares(res, z0, jac, lower)
            z = newton_polish(res, sol.x, lower)
        s_new, P_new = unpack(z, s_base, P_base)
        # floating levels: null directions of the state block that leave ṡ unchanged
        J = jacobian(lambda x, P_new=P_new: rhs(compiled, t, x, P_new)[rows], s_new, scale, unknown)
        J = J * scale[unknown][None, :] / norm[:, None]
        floating = _floating(compiled, t, s_new, P_new, J, unknown, rows, norm, scale)
        s_new = _centre_levels(compiled, s_new, floating)
        s_proj = proj(s_new, P_new)
        changed = np.any(s_proj[held] != s_new[held])
        s, P0 = s_proj, P_new
        r = rhs(compiled, t, s, P0)[rows] / norm
        residual = float(np.max(np.abs(r))) if r.size else 0.0
        if not changed:
            break
    notes: list[str] = []
    inputs = {name: float(P0[k]) for name, k in zip(free, free_idx, strict=True)}
    result = SteadyState(s, P0, t, inputs, held, floating, residual, notes)
    _check(compiled, result, field_name, pin)
    return result


def bounded_least_squares(res, z0, jac, lower):
    """scipy's trust-region least squares of ``res`` from z0 (Jacobian ``jac``), every
    unknown at or above ``lower``, tolerances at rounding (step 4 of the module doc)."""
    from scipy.optimize import least_squares

    return least_squares(
        res, z0, jac=jac, bounds=(lower, np.inf), method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )


def newton_polish(res, z, lower):
    """z after Gauss-Newton steps on ``res`` (the solve's scaled rows), each at or above
    ``lower`` and kept only while it lowers the largest row (step 4 of the module doc).

    A static state often lies on a kink of a law: the excavator's three closed-centre valves
    hold their loads at null (each metering edge's opening clipped at 0, the flow from P a V in
    the spool position) and its pump deadheads at zero stroke (the compensator's target
    clipped at 0). The trust region's central differences, step `FD_STEP` of each scale
    (6e-9 m of a spool), straddle such a kink and average its slopes, its model stops
    predicting its steps, and it stops on xtol wherever round-off leaves it: 1.8e-10 m of
    the boom's spool from null, a residual of 2.3e-7 in the pump's node (P), with √√x for
    x^¼ in the orifice law, and the same with pow from a start moved by 1e-9 of itself.
    Newton with the one-sided slopes that `POLISH_STEP` resolves lands on the kink (each
    branch is linear there): 1e-12 or less. Singular values below `NULL_CANDIDATE` of the
    largest are dropped from its pseudo-inverse: they are the directions the rows do not fix
    (the floating levels of step 5; a deadheaded pump's pressure, anywhere between its zero
    stroke and its relief), along which a step would be unbounded."""
    f = res(z)
    worst = float(np.max(np.abs(f), initial=0.0))
    ones = np.ones(z.size)
    for _ in range(POLISH_STEPS):
        if worst <= RESIDUAL_TOL * 1e-3:
            break
        J = jacobian(res, z, ones, step=POLISH_STEP)
        dz = np.linalg.lstsq(J, -f, rcond=NULL_CANDIDATE)[0]
        trial = np.maximum(z + dz, lower)
        f_trial = res(trial)
        worst_trial = float(np.max(np.abs(f_trial)))
        if not worst_trial < worst:
            break
        z, f, worst = trial, f_trial, worst_trial
    return z


def _floating(compiled, t, s, P, J, unknown, rows, norm, scale) -> list[tuple[str, np.ndarray]]:
    """The floating levels among the unknowns of a circuit (module doc, step 5):
    `null_levels` of its kernel's rows."""
    nh = len(compiled.hydraulic)
    names = [n for n, _ in compiled.state_names]

    def f(x):
        return rhs(compiled, t, x, P)[rows] / norm

    return null_levels(f, s, J, unknown, scale, names, unknown < nh)


def null_levels(f, s, J, unknown, scale, names, pressure) -> list[tuple[str, np.ndarray]]:
    """The floating levels among the unknowns ``unknown`` (indices of s) of a right-hand
    side ``f`` (state → its rows, each scaled as the residuals; the circuit's kernel): the
    near-null space of J (those rows' Jacobian in scaled unknowns; singular values below
    `NULL_CANDIDATE` of the largest) in reduced row echelon form (sparse vectors: a sealed
    chamber pair's common level is (1, 1) on its two pressures), each kept when a shift of
    `FLOAT_SHIFT` of its scale, upward (``pressure``: mask over the unknowns of the
    pressures), changes no row by more than `FLOAT_TOL`. Returns (label: the names it moves
    joined by " + ", vector over the whole state, largest entry 1)."""
    if J.size == 0:
        return []
    _, sv, Vt = np.linalg.svd(J)
    sv = np.concatenate([sv, np.zeros(Vt.shape[0] - sv.size)])
    N = Vt[sv <= NULL_CANDIDATE * sv[0]]
    found = []
    base = f(s)
    for v in _rref(N):
        if np.sum(v[pressure]) < 0.0:
            v = -v  # a level shifted up, away from the cavitation floor
        shifted = s.copy()
        shifted[unknown] += FLOAT_SHIFT * v / np.max(np.abs(v)) * scale[unknown]
        moved = f(shifted)
        if np.max(np.abs(moved - base)) > FLOAT_TOL:
            continue
        full = np.zeros(s.size)
        full[unknown] = v * scale[unknown]
        full /= np.max(np.abs(full))
        label = [names[i] for i in np.nonzero(np.abs(full) > 1e-3)[0]]
        found.append((" + ".join(label), full))
    return found


def floating_levels(compiled, t, s, P, states) -> list[tuple[str, np.ndarray]]:
    """The floating levels among ``states`` (indices) at (t, s) with the rows of those states
    (module doc, step 5): vectors over the whole state, largest entry 1."""
    states = np.asarray(states, np.int64)
    scale = state_scales(compiled, P)
    J = jacobian(lambda x: rhs(compiled, t, x, P)[states], s, scale, states)
    norm = np.sum(np.abs(J * scale[states][None, :]), axis=1)
    norm = np.maximum(norm, 1e-12 * max(float(np.max(norm, initial=0.0)), 1e-300))
    J = J * scale[states][None, :] / norm[:, None]
    return _floating(compiled, t, s, P, J, states, states, norm, scale)


def _rref(N: np.ndarray) -> list[np.ndarray]:
    """The rows of N brought to reduced row echelon form (partial pivoting), entries below
    1e-9 of their row's largest set to zero."""
    M = N.copy()
    out = []
    for r in range(M.shape[0]):
        sub = np.abs(M[r:, :])
        if sub.size == 0 or sub.max() == 0.0:
            break
        i, j = (int(x) for x in np.unravel_index(int(np.argmax(sub)), sub.shape))
        M[[r, r + i]] = M[[r + i, r]]
        M[r] /= M[r, j]
        for k in range(M.shape[0]):
            if k != r:
                M[k] -= M[k, j] * M[r]
    for row in M:
        big = np.max(np.abs(row))
        if big > 0.0:
            row = np.where(np.abs(row) < 1e-9 * big, 0.0, row)
            out.append(row)
    return out


def _centre_levels(compiled, s, floating) -> np.ndarray:
    """A floating pressure level put at mid-pressure (module doc, step 5): half-way between
    the lowest and highest node pressures no level moves."""
    nh = len(compiled.hydraulic)
    anchored = np.ones(nh, bool)  # the nodes no floating level moves
    for _, v in floating:
        anchored &= np.abs(v[:nh]) <= 1e-12
    if not np.any(anchored):
        return s
    mid = 0.5 * (float(np.min(s[:nh][anchored])) + float(np.max(s[:nh][anchored])))
    return centre_levels(s, np.arange(nh), mid, floating)


def centre_levels(s, pressures, mid: float, floating) -> np.ndarray:
    """s with every floating level that moves only pressures (indices ``pressures``) shifted
    along itself until its weighted mean pressure is ``mid`` (Merritt's null: p_A + p_B =
    p_s + p_T for a servo's equal chambers)."""
    pressures = np.asarray(pressures, np.int64)
    others = np.ones(s.size, bool)
    others[pressures] = False
    out = s.copy()
    for _, v in floating:
        w = v[pressures]
        if np.any(np.abs(v[others]) > 1e-12) or not np.any(w):
            continue  # not a pure pressure level
        alpha = (mid * np.sum(w) - np.sum(w * out[pressures])) / np.sum(w * w)
        out[pressures] = out[pressures] + alpha * w
    return out


def check_pressure(field_name: str, what: str, p: float, floor: float, ceiling: float) -> None:
    """Refuse a static state whose absolute pressure ``p`` [Pa] lies below the cavitation
    pressure ``floor`` (or at or below zero) or above the highest source pressure
    ``ceiling`` (one line naming ``what``)."""
    if p < floor - 1e-6 * max(abs(floor), 1e5) or p <= 0.0:
        raise HydroarmError(
            field_name,
            f"no physical static state: {what} at {p / 1e5:.4g} bar absolute, below the "
            f"cavitation pressure {floor / 1e5:.4g} bar",
        )
    if p > ceiling * (1 + 1e-9):
        raise HydroarmError(
            field_name,
            f"no physical static state: {what} at {p / 1e5:.4g} bar, above the highest "
            f"source pressure {ceiling / 1e5:.4g} bar",
        )


def _check(compiled, r: SteadyState, field_name: str, pin) -> None:
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    names = [n for n, _ in compiled.state_names]
    if not np.all(np.isfinite(r.state)) or not math.isfinite(r.residual):
        raise HydroarmError(field_name, "no static state found (the solve left finite numbers)")
    if r.residual > RESIDUAL_TOL:
        d = rhs(compiled, r.t, r.state, r.P)
        worst = int(np.argmax(np.abs(d) * ~r.held / state_scales(compiled, r.P)))
        hint = ""
        if pin and not r.inputs:
            hint = " (a pinned pose needs an input freed to hold it)"
        raise HydroarmError(
            field_name,
            f"no static state with these inputs{hint}: the residual {r.residual:.2g} "
            f"(largest in {names[worst]}) stays above {RESIDUAL_TOL:g}",
        )
    floor = r.P[SYS.cavitation_pressure]
    ceiling = pressure_ceiling(compiled, r.P)
    for node, i in compiled.hydraulic.items():
        check_pressure(field_name, f"node {node!r}", r.state[i], floor, ceiling)
    st = strokes(compiled)
    for node, m in compiled.mechanical.items():
        x = r.state[nh + m]
        if node in st and not st[node][0] - 1e-9 <= x <= st[node][1] + 1e-9:
            lo, hi, cyl = st[node]
            raise HydroarmError(
                field_name,
                f"the static state puts node {node!r} at {x:g}, outside the stroke of {cyl} "
                f"({lo:g} … {hi:g})",
            )
    del nm


def reference_problems(compiled) -> list[tuple[str, str]]:
    """(field, problem) for every reference outside its actuator's stroke: a signal source
    read as a PID's reference whose measurement is a position sensor (y = g·x + y₀) on a
    node a cylinder drives, with a value (over its whole waveform) whose position
    (y − y₀)/g lies outside the stroke."""
    comps = compiled.circuit.components
    writer = {}
    for ci, c in enumerate(comps):
        for port, target in c.ports.items():
            if c.type in ("signal_source", "position_sensor") and port == "out":
                writer[target] = ci
    st = strokes(compiled)
    out = []
    for c in comps:
        if c.type != "pid" or "reference" not in c.ports:
            continue
        src = writer.get(c.ports["reference"])
        sen = writer.get(c.ports.get("measurement", ""))
        if src is None or sen is None:
            continue
        if comps[src].type != "signal_source" or comps[sen].type != "position_sensor":
            continue
        node = comps[sen].ports["body"]
        if node not in st:
            continue
        gain = compiled.values[sen]["gain"]
        offset = compiled.values[sen]["offset"]
        if gain == 0.0:
            continue
        lo, hi, cyl = st[node]
        for key, value in _source_values(compiled, src):
            x = (value - offset) / gain
            if not lo - 1e-12 <= x <= hi + 1e-12:
                out.append(
                    (
                        f"component.{comps[src].name}.{key}",
                        f"the reference {value:g} asks for position {x:g} at node {node!r}, "
                        f"outside the stroke of {cyl} ({lo:g} … {hi:g})",
                    )
                )
                break
    return out


def _source_values(compiled, ci) -> list[tuple[str, float]]:
    """(key, value) of every level a signal source takes (its offset, steps, table values,
    the sine's peaks, the ramp's end)."""
    v = compiled.values[ci]
    kind = int(v["waveform"])
    out = []
    spec = compiled.circuit.components[ci]
    if kind in (_SOURCE.STEPS, _SOURCE.TABLE):
        vals = spec.arrays.get("values", ())
        if kind == _SOURCE.STEPS:
            out.append(("offset", v["offset"]))
        out += [(f"values[{i}]", float(x)) for i, x in enumerate(vals)]
        return out
    out.append(("offset", v["offset"]))
    if kind == _SOURCE.SINE:
        out += [("amplitude", v["offset"] + a) for a in (v["amplitude"], -v["amplitude"])]
    elif kind == _SOURCE.RAMP and math.isfinite(v["end_time"]):
        out.append(("rate", v["offset"] + v["rate"] * (v["end_time"] - v["start_time"])))
    return out
