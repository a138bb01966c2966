"""The linear view of any circuit, on the system kernel (issue 29; docs/linear.md "Circuits").

`linearize_circuit` finds the operating point (`hydroarm.model.circuit_steady.steady_state`: ṡ = 0
with the inputs held at a time t, a pose optionally pinned and the input then freed to hold it), and
linearises the kernel's right-hand side there (`hydroarm.integrators.system.derivatives_at`, central
differences, steps ε^(1/3)·scale): one physics, no equation written twice. Its `CircuitLinearModel`:

* ``A, B, C, D`` from one named input (a signal source, the reference: its frozen value; or a
  component parameter ``<component>.<parameter>``) to one named output (any output column of
  a run: ``load_position_m``, ``A_pressure_bar``, ``valve_A_flow_lpm``, in the column's unit),
  over the states the kernel moves (tanks' nodes, latches and algebraic states left out);
* **floating levels** (a sealed node pair's common pressure, a held load's position: J·v = 0
  and ṡ unchanged by a large shift) reported and removed: the model is reduced to the
  states complementary to them (their pivot state dropped), so no pole at 0 is shown for
  them; an output that sees a floating level is noted;
* **the loops** (`loops`: one per controller that writes a 4/3 valve's command), each
  broken at its controller's output (the circuit rebuilt with the valves it drives reading
  an injected constant instead; the other loops closed): L = −∂u_controller/∂u_valve; gain
  and phase margins of L (`lti`), ω_h and ζ_h from L's hydraulic mode (the eigenpair
  in which the load's velocity takes the largest part), the closed loop's bandwidth. With
  one loop it is the loop; with several, ``loop="<controller>"`` picks the one whose
  margins, ω_h and Bode plot are shown, and every loop's margins are in ``loop_table``;
* **the overlap rule**: a 4/3 valve whose spool sits inside its overlap passes no flow; the
  loop is then open at that point (no margins), and the nearest operating point with flow
  (the spool displaced by its overlap, where the valve acts as a zero-lap one) is linearised
  in ``nearest``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..core.circuit.declare import ROTATIONAL, SIGNAL_OUT
from ..errors import HydroarmError
from ..model.circuit import Circuit, CircuitResult, CompiledCircuit, ComponentSpec, build
from ..model.circuit_steady import (
    FD_STEP,
    SteadyState,
    floating_levels,
    jacobian,
    rhs,
    signal_values,
    state_scales,
    steady_state,
)
from ..plotting.linear import bode_figure
from . import lti

if TYPE_CHECKING:
    import control

UNSTABLE_NOTE = (
    "the broken loop has {n} poles in the right half-plane: the margins alone do not say "
    "whether the closed loop is stable"
)
INJECTION = "loop_injection"  # the constant that replaces a valve's command (the broken loop)


def _control():
    import control

    return control


@dataclass
class CircuitLinearModel:
    """A circuit linearised about an operating point (module doc). ``A, B, C, D`` in SI per
    the output column's unit; ``states``: the states kept; ``point``: the steady state;
    ``floating``: the removed levels; ``loop_abcd``: the broken loop (None: no controller or
    the loop open at this point); ``open_loop_reason``; ``nearest``: the model at the nearest
    operating point with flow (overlap rule); ``notes``: what the report should say."""

    circuit_name: str
    input: str
    output: str
    states: tuple[str, ...]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    point: SteadyState
    point_values: dict[str, float]
    floating: list[str]
    loop_abcd: tuple[np.ndarray, np.ndarray, np.ndarray, float] | None
    loop_A_reduced: np.ndarray | None
    velocity_rows: list[int]
    open_loop_reason: str | None = None
    nearest: CircuitLinearModel | None = None
    notes: list[str] = field(default_factory=list)
    loop_name: str | None = None  # the controller whose loop ``loop_abcd`` is
    loop_table: list[dict] = field(default_factory=list)  # several loops: each one's margins

    @property
    def system(self) -> control.StateSpace:
        """The closed loop as a python-control ``StateSpace`` (input → output)."""
        return _control().ss(
            self.A,
            self.B,
            self.C,
            self.D,
            inputs=[self.input],
            outputs=[self.output],
            states=list(self.states),
        )

    @property
    def loop(self) -> control.StateSpace | None:
        return None if self.loop_abcd is None else _control().ss(*self.loop_abcd)

    @property
    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A) if self.A.size else np.zeros(0)

    def hydraulic_mode(self) -> tuple[float | None, float | None]:
        """(ω_h [rad/s], ζ_h) of the mode in which the load's velocity takes the largest
        part (`lti.participation_mode`), with the valve's command held (the broken
        loop's A; the model's own A without a loop); None where no such mode is
        identifiable."""
        A = self.loop_A_reduced if self.loop_A_reduced is not None else self.A
        return lti.participation_mode(A, self.velocity_rows)

    def margins(self) -> dict | None:
        """Gain and phase margins of the broken loop (`lti.margins`); None where the
        loop is open (overlap) or there is none."""
        if self.loop_abcd is None:
            return None
        A, b, c, d = self.loop_abcd
        return lti.margins(A, b, c, d)

    def bandwidth(self) -> float | None:
        """−3 dB bandwidth [rad/s] of input → output; None: unstable or none below 10⁶."""
        if not self.A.size or np.max(self.poles.real) >= 0:
            return None
        w = lti.bandwidth(self.A, self.B[:, 0], self.C[0], float(self.D[0, 0]))
        return w if math.isfinite(w) else None

    def freqresp(self, w) -> np.ndarray:
        """G(jω) of input → output."""
        return lti.freqresp(self.A, self.B[:, 0], self.C[0], float(self.D[0, 0]), w)

    def summary(self) -> dict:
        """Every quantity by name (None where undefined: no NaN)."""
        w_h, z_h = self.hydraulic_mode()
        m = self.margins() or {}
        out: dict = {
            "input": self.input,
            "output": self.output,
            "operating_point": dict(self.point_values),
            "poles": [complex(p) for p in self.poles],
            "hydraulic_natural_frequency_rad_s": w_h,
            "hydraulic_damping": z_h,
            "gain_margin_db": _finite(m.get("gain_margin_db")),
            "phase_margin_deg": _finite(m.get("phase_margin_deg")),
            "gain_crossover_rad_s": _finite(m.get("gain_crossover_rad_s")),
            "phase_crossover_rad_s": _finite(m.get("phase_crossover_rad_s")),
            "bandwidth_rad_s": self.bandwidth(),
            "floating_levels": list(self.floating),
            "loop_open": self.open_loop_reason,
            "loop": self.loop_name,
            "loops": [dict(x) for x in self.loop_table],
            "notes": list(self.notes),
        }
        if self.nearest is not None:
            out["nearest_with_flow"] = self.nearest.summary()
        return out

    def report(self) -> str:
        """The operating point (pressures in bar absolute), poles, ω_h, ζ_h, margins,
        bandwidth and every note, as text."""
        lines = [f"{self.circuit_name}: {self.input} → {self.output}", "operating point:"]
        for k, v in self.point_values.items():
            lines.append(f"  {k} = {v:.6g}")
        lines += _model_lines(self)
        if self.nearest is not None:
            lines.append("nearest operating point with flow:")
            for k, v in self.nearest.point_values.items():
                if k.endswith("_spool_m"):
                    lines.append(f"  {k} = {v:.6g}")
            lines += ["  " + x for x in _model_lines(self.nearest)]
        return "\n".join(lines)

    def bode_figure(self, w=None):
        """Closed-loop Bode plot (input → output) and, where there is one, the loop's."""
        if w is None:
            w = np.logspace(-1, 4, 400)
        closed = self.freqresp(w)
        title = f"{self.circuit_name}: {self.input} → {self.output}"
        if self.loop_abcd is None:
            return bode_figure(w, closed, closed, title=title, loop_label="(no loop)")
        A, b, c, d = self.loop_abcd
        return bode_figure(w, lti.freqresp(A, b, c, d, w), closed, title=title)


def _finite(v):
    return float(v) if v is not None and math.isfinite(v) else None


def _show(v: float, unit: str, at) -> str:
    if not math.isfinite(v):
        return "none (no crossing)"
    return f"{v:.4g} {unit} (at {at:.4g} rad/s)"


def _model_lines(m: CircuitLinearModel) -> list[str]:
    lines = []
    poles = m.poles
    shown = ", ".join(
        f"{p.real:.4g}{'+' if p.imag >= 0 else '-'}{abs(p.imag):.4g}j"
        if p.imag
        else f"{p.real:.4g}"
        for p in sorted(poles, key=lambda p: (abs(p), p.imag))
    )
    lines.append(f"poles [1/s] ({len(poles)}): {shown}")
    w_h, z_h = m.hydraulic_mode()
    if w_h is not None:
        lines.append(f"hydraulic mode: ω_h = {w_h:.5g} rad/s, ζ_h = {z_h:.4g}")
    if m.open_loop_reason:
        lines.append(f"loop open: {m.open_loop_reason}")
    mg = m.margins()
    if mg is not None:
        of = f" of the loop of {m.loop_name} (the others closed)" if m.loop_table else ""
        lines.append(
            f"gain margin{of}: "
            + _show(mg["gain_margin_db"], "dB", mg["phase_crossover_rad_s"])
            + "; phase margin: "
            + _show(mg["phase_margin_deg"], "deg", mg["gain_crossover_rad_s"])
        )
        n = unstable_poles(m.loop_A_reduced) if m.loop_A_reduced is not None else 0
        if n:
            lines.append(f"  {UNSTABLE_NOTE.format(n=n)}")
    if m.loop_table:
        lines.append(
            f"loops ({len(m.loop_table)}), each broken at its controller's output, the "
            "others closed:"
        )
        width = max(len(x["loop"]) for x in m.loop_table)
        for x in m.loop_table:
            if x["loop_open"]:
                shown = f"open: {x['loop_open']}"
            else:
                gm, pm = x["gain_margin_db"], x["phase_margin_deg"]
                shown = (
                    "gain margin "
                    + _show(math.inf if gm is None else gm, "dB", x["phase_crossover_rad_s"])
                    + "; phase margin "
                    + _show(math.inf if pm is None else pm, "deg", x["gain_crossover_rad_s"])
                )
            n = x["open_loop_unstable_poles"]
            if n and not x["loop_open"]:
                shown += f" ({UNSTABLE_NOTE.format(n=n)})"
            lines.append(f"  {x['loop']:<{width}}  ({', '.join(x['valves'])}): {shown}")
    bw = m.bandwidth()
    if bw is not None:
        lines.append(f"bandwidth (−3 dB): {bw:.4g} rad/s")
    elif m.A.size and np.max(m.poles.real) >= 0:
        lines.append("bandwidth: — (the closed loop is unstable here)")
    else:
        lines.append("bandwidth: — (no finite, non-zero steady gain from the input)")
    for name in m.floating:
        lines.append(f"structural zero removed: floating level {name}")
    lines += [f"note: {x}" for x in m.notes]
    return lines


# ------------------------------------------------------------------ names ---
def default_input(compiled: CompiledCircuit) -> str:
    """The signal source read as a PID's reference, else the first signal source."""
    comps = compiled.circuit.components
    sources = {c.ports["out"]: c.name for c in comps if c.type == "signal_source"}
    for c in comps:
        if c.type == "pid" and c.ports.get("reference") in sources:
            return sources[c.ports["reference"]]
    if sources:
        return next(iter(sources.values()))
    raise HydroarmError("--input", "the circuit has no signal source: name a parameter")


def default_output(compiled: CompiledCircuit) -> str:
    """The position of the node a PID's sensor measures, else of the first mechanical node,
    else the first node pressure not held by a tank."""
    comps = compiled.circuit.components
    sensed = {c.ports["out"]: c.ports["body"] for c in comps if c.type == "position_sensor"}
    for c in comps:
        if c.type == "pid" and c.ports.get("measurement") in sensed:
            return _position_column(compiled, sensed[c.ports["measurement"]])
    if compiled.mechanical:
        return _position_column(compiled, next(iter(compiled.mechanical)))
    for name, i in compiled.hydraulic.items():
        if compiled.fixed[i] == 0:
            return f"{name}_pressure_bar"
    raise HydroarmError("--output", "the circuit has no output to choose: name one")


def _position_column(compiled, node: str) -> str:
    rot = compiled.mech_domain[node] == ROTATIONAL
    return f"{node}_angle_deg" if rot else f"{node}_position_m"


def _node_of_output(compiled, output: str) -> str | None:
    for node in compiled.mechanical:
        if output == _position_column(compiled, node):
            return node
    return None


# ---------------------------------------------------------- the linear view ---
def _input_index(compiled: CompiledCircuit, name: str) -> tuple[int, bool]:
    """(index in P, whether a signal source) of an input name."""
    for i, c in enumerate(compiled.circuit.components):
        if c.name == name:
            if c.type != "signal_source":
                raise HydroarmError(
                    "--input", f"{name!r} is a {c.type}: name a signal source or a parameter"
                )
            return compiled.poff[i] + compiled.decls[i].parameter_names.index("offset"), True
    if name in compiled.parameter_index:
        return compiled.parameter_index[name], False
    sources = [c.name for c in compiled.circuit.components if c.type == "signal_source"]
    raise HydroarmError(
        "--input",
        f"{name!r}: not a signal source ({', '.join(sources) or 'none'}) nor a parameter "
        "(<component>.<parameter>)",
    )


def _outputs_at(compiled, S: np.ndarray, P: np.ndarray, output: str, t: float) -> np.ndarray:
    res = CircuitResult(compiled, np.full(S.shape[0], t), S, -1, P)
    return np.asarray(res.output(output), float)


def _in_overlap(compiled, point: SteadyState) -> list[tuple[str, float, float]]:
    """(valve, spool [m], overlap [m]) of every 4/3 valve whose spool sits inside its
    overlap (no flow through any edge)."""
    out = []
    names = [n for n, _ in compiled.state_names]
    for i, c in enumerate(compiled.circuit.components):
        if c.type != "valve_4_3":
            continue
        lap = compiled.values[i]["overlap"]
        x = float(point.state[names.index(f"{c.name}.spool")])
        if lap > 0.0 and abs(x) < lap:
            out.append((c.name, x, lap))
    return out


@dataclass(frozen=True)
class Loop:
    """A control loop of a circuit: the ``controller`` (the component that writes the
    command of a 4/3 valve; not a signal source), the ``valves`` its output drives and that
    ``signal``'s name."""

    controller: str
    valves: tuple[str, ...]
    signal: str


def loops(compiled: CompiledCircuit) -> list[Loop]:
    """The loops of a circuit: one per component that writes the command of a 4/3 valve
    (a PID, say; a signal source driving a valve closes no loop), in the file's order."""
    comps = compiled.circuit.components
    writer: dict[str, str] = {}
    for c, decl in zip(comps, compiled.decls, strict=True):
        for port, target in c.ports.items():
            if decl.port(port).domain == SIGNAL_OUT:
                writer[target] = c.name
    kind = {c.name: c.type for c in comps}
    out: dict[str, Loop] = {}
    for v in comps:
        if v.type != "valve_4_3" or "command" not in v.ports:
            continue
        signal = v.ports["command"]
        w = writer.get(signal)
        if w is None or kind[w] == "signal_source":
            continue
        old = out.get(w)
        out[w] = Loop(w, (*old.valves, v.name) if old else (v.name,), signal)
    return list(out.values())


def _loop_named(compiled: CompiledCircuit, name: str | None) -> tuple[list[Loop], Loop | None]:
    """(every loop, the one to break): ``name`` a controller's (checked: one line naming the
    loops), or None: the only loop where there is one, else none (each in a table)."""
    found = loops(compiled)
    if name is None:
        return found, found[0] if len(found) == 1 else None
    for lp in found:
        if lp.controller == name:
            return found, lp
    shown = ", ".join(lp.controller for lp in found) or "none: no controller drives a valve"
    raise HydroarmError(
        "--loop", f"{name!r} is not a controller that drives a 4/3 valve (loops: {shown})"
    )


def broken_circuit(compiled: CompiledCircuit, point: SteadyState, loop: Loop):
    """The circuit with ``loop`` broken at its controller's output: every 4/3 valve that
    reads it reads an injected constant instead, held at the controller's output at the
    operating point: (compiled, P, injection index, the controller's signal name)."""
    circuit = compiled.circuit
    command = loop.signal
    sig = signal_values(compiled, point.t, point.state, point.P)
    new = []
    for c in circuit.components:
        if c.name in loop.valves:
            ports = dict(c.ports)
            ports["command"] = INJECTION
            c = ComponentSpec(c.type, c.name, ports, c.values, c.arrays)
        new.append(c)
    new.append(ComponentSpec("signal_source", INJECTION, {"out": INJECTION}, {}, {}))
    broken = build(circuit.replace(components=tuple(new)))
    assert [n for n, _ in broken.state_names] == [n for n, _ in compiled.state_names]
    P = broken.P.copy()
    P[: point.P.size] = point.P
    k = broken.poff[-1] + broken.decls[-1].parameter_names.index("offset")
    P[k] = sig[command]
    return broken, P, k, command


@dataclass
class _BrokenLoop:
    """One loop broken at an operating point: ``abcd`` (None where the loop is open, its
    valve in its overlap: ``reason``), the reduced A of the broken loop and its velocity
    rows."""

    loop: Loop
    abcd: tuple[np.ndarray, np.ndarray, np.ndarray, float] | None
    A_reduced: np.ndarray
    velocity_rows: list[int]
    reason: str | None

    def summary(self) -> dict:
        m = lti.margins(*self.abcd) if self.abcd is not None else {}
        return {
            "loop": self.loop.controller,
            "valves": list(self.loop.valves),
            "gain_margin_db": _finite(m.get("gain_margin_db")),
            "phase_margin_deg": _finite(m.get("phase_margin_deg")),
            "gain_crossover_rad_s": _finite(m.get("gain_crossover_rad_s")),
            "phase_crossover_rad_s": _finite(m.get("phase_crossover_rad_s")),
            "loop_open": self.reason,
            "open_loop_unstable_poles": unstable_poles(self.A_reduced),
        }


def unstable_poles(A: np.ndarray) -> int:
    """Poles of a broken loop in the right half-plane (real part above 1e-9 of the
    spectral radius: the zero left by a controller's integral is not counted). With any,
    the gain and phase margins alone do not say whether the closed loop is stable (the
    Nyquist criterion counts the encirclements instead)."""
    if not A.size:
        return 0
    lam = np.linalg.eigvals(A)
    return int(np.sum(lam.real > 1e-9 * max(1.0, float(np.max(np.abs(lam))))))


def break_loop(compiled, point, loop: Loop, t, s, scale, dyn, overlap) -> _BrokenLoop:
    """``loop`` broken at its controller's output (the other loops closed), linearised
    about ``point``: L = −∂u_controller/∂u_injected over the states the kernel moves."""
    broken, Pb, k_inj, command = broken_circuit(compiled, point, loop)
    Jl = jacobian(lambda x: rhs(broken, t, x, Pb)[dyn], s, scale, dyn)
    ui = Pb[k_inj]
    hi = FD_STEP * max(abs(ui), 1e-6)
    Pp, Pm = Pb.copy(), Pb.copy()
    Pp[k_inj] += hi
    Pm[k_inj] -= hi
    bl = (rhs(broken, t, s, Pp) - rhs(broken, t, s, Pm))[dyn] / (2 * hi)

    def cmd(x, PP=Pb):
        return signal_values(broken, t, x, PP)[command]

    cl = np.array(
        [
            -(cmd(_shift(s, i, FD_STEP * scale[i])) - cmd(_shift(s, i, -FD_STEP * scale[i])))
            / (2 * FD_STEP * scale[i])
            for i in dyn
        ]
    )
    loop_levels = floating_levels(broken, t, s, Pb, dyn)
    loop_A, _, _, rest_l, _ = lti.reduce_levels(
        Jl, bl[:, None], cl[None, :], dyn, [v for _, v in loop_levels]
    )
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    velocity = [j for j, i in enumerate(dyn[rest_l]) if nh + nm <= i < nh + 2 * nm]
    mine = [o for o in overlap if o[0] in loop.valves]
    if mine:
        name, x, lap = mine[0]
        reason = (
            f"the spool of {name} at {x * 1e6:.3g} µm sits inside its ±{lap * 1e6:.3g} µm "
            "overlap: no flow gain, so no feedback acts here"
        )
        return _BrokenLoop(loop, None, loop_A, velocity, reason)
    return _BrokenLoop(loop, (Jl, bl[:, None], cl[None, :], 0.0), loop_A, velocity, None)


def linearize_circuit(
    compiled: CompiledCircuit | Circuit,
    input: str | None = None,
    output: str | None = None,
    position: float | None = None,
    t: float | None = None,
    loop: str | None = None,
    _nearest: bool = True,
) -> CircuitLinearModel:
    """The linear view of a circuit about its operating point (module doc). ``input``: a
    signal source or ``<component>.<parameter>`` (default `default_input`); ``output``:
    an output column (default `default_output`); ``position``: the pose [m, rad] of the
    output's mechanical node (or the only one) held at rest, the input (a signal source) then
    solved for; ``t``: the time whose inputs hold (default the end of the run); ``loop``: the
    controller whose loop to break (the others closed; default: the only loop, and with
    several each one's margins in ``loop_table``)."""
    if isinstance(compiled, Circuit):
        compiled = build(compiled)
    circuit = compiled.circuit
    input = default_input(compiled) if input is None else input
    output = default_output(compiled) if output is None else output
    k_in, is_source = _input_index(compiled, input)
    every_loop, chosen = _loop_named(compiled, loop)
    t = circuit.duration if t is None else t
    pin = {}
    if position is not None:
        node = _node_of_output(compiled, output)
        if node is None:
            if len(compiled.mechanical) != 1:
                raise HydroarmError(
                    "--position", "which node? name its position as --output (<node>_position_m)"
                )
            node = next(iter(compiled.mechanical))
        pin[node] = position
    free = [input] if (pin and is_source) else []
    point = steady_state(
        compiled, t, pin, free, field_name="--position" if pin else "operating point"
    )
    s, P = point.state, point.P
    # the output exists? (one line naming the close ones)
    y0 = _outputs_at(compiled, s[None, :], P, output, t)[0]
    dyn = np.nonzero(~point.held)[0]
    scale = state_scales(compiled, P)
    J = jacobian(lambda x: rhs(compiled, t, x, P)[dyn], s, scale, dyn)
    u0 = P[k_in]
    hu = FD_STEP * max(abs(u0), 1e-3)

    def with_input(u):
        PP = P.copy()
        PP[k_in] = u
        return PP

    B = (
        (rhs(compiled, t, s, with_input(u0 + hu)) - rhs(compiled, t, s, with_input(u0 - hu)))[dyn]
        / (2 * hu)
    )[:, None]
    S = np.repeat(s[None, :], 2 * dyn.size, axis=0)
    for j, i in enumerate(dyn):
        S[2 * j, i] += FD_STEP * scale[i]
        S[2 * j + 1, i] -= FD_STEP * scale[i]
    Y = _outputs_at(compiled, S, P, output, t)
    C = ((Y[0::2] - Y[1::2]) / (2 * FD_STEP * scale[dyn]))[None, :]
    yp = _outputs_at(compiled, s[None, :], with_input(u0 + hu), output, t)[0]
    ym = _outputs_at(compiled, s[None, :], with_input(u0 - hu), output, t)[0]
    D = np.array([[(yp - ym) / (2 * hu)]])
    levels = floating_levels(compiled, t, s, P, dyn)
    A_r, B_r, C_r, rest, pivots = lti.reduce_levels(J, B, C, dyn, [v for _, v in levels])
    names = [compiled.state_names[i][0] for i in dyn]
    notes: list[str] = []
    for (label, v), piv in zip(levels, pivots, strict=True):
        if abs(float(C[0] @ v[dyn])) > 1e-9 * max(float(np.max(np.abs(C))), 1e-300):
            notes.append(f"{output} sees the floating level {label}: its drift is left out")
        del piv
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    velocity_cols = [j for j, i in enumerate(dyn[rest]) if nh + nm <= i < nh + 2 * nm]
    # the loops, each broken at its controller's output (the others closed)
    overlap = _in_overlap(compiled, point)
    loop_abcd = None
    loop_A = None
    reason = None
    nearest = None
    table = []
    for lp in every_loop:
        if lp is not chosen and len(every_loop) < 2:
            continue
        got = break_loop(compiled, point, lp, t, s, scale, dyn, overlap)
        if len(every_loop) > 1:
            table.append(got.summary())
        if lp is chosen:
            loop_abcd, loop_A, reason = got.abcd, got.A_reduced, got.reason
            velocity_cols = got.velocity_rows
    if chosen is None and overlap:
        name, x, lap = overlap[0]
        reason = (
            f"the spool of {name} at {x * 1e6:.3g} µm sits inside its ±{lap * 1e6:.3g} µm overlap"
        )
    if overlap and _nearest:
        name, x, lap = overlap[0]
        zero_lap = circuit.with_values({f"{name}.overlap": 0.0})
        nearest = linearize_circuit(zero_lap, input, output, position, t, loop, _nearest=False)
        side = 1.0 if x >= 0 else -1.0
        nearest.point_values[f"{name}_spool_m"] = (
            nearest.point_values.get(f"{name}_spool_m", 0.0) + side * lap
        )
        nearest.notes.append(
            f"the spool displaced by its overlap ({side * lap * 1e3:+.4g} mm): there the valve "
            "meters as a zero-lap valve, linearised as one"
        )
    values = _point_values(compiled, point)
    model = CircuitLinearModel(
        circuit_name=circuit.name,
        input=input,
        output=output,
        states=tuple(names[i] for i in rest),
        A=A_r,
        B=B_r,
        C=C_r,
        D=D,
        point=point,
        point_values=values,
        floating=[label for label, _ in levels],
        loop_abcd=loop_abcd,
        loop_A_reduced=loop_A,
        velocity_rows=velocity_cols,
        open_loop_reason=reason,
        nearest=nearest,
        notes=notes,
        loop_name=None if chosen is None else chosen.controller,
        loop_table=table,
    )
    values[f"{output} (output)"] = float(y0)
    return model


def _shift(s, i, h):
    out = s.copy()
    out[i] += h
    return out


def _point_values(compiled, point: SteadyState) -> dict[str, float]:
    """The operating point by name: node pressures in bar absolute, positions, the freed
    inputs, component states."""
    out: dict[str, float] = {}
    for (stem, unit), v, held in zip(compiled.state_names, point.state, point.held, strict=True):
        key = stem.replace(".", "_")
        if unit == "Pa":
            out[f"{key}_bar"] = float(v) * 1e-5
        elif unit == "rad":
            out[f"{key}_deg"] = math.degrees(float(v))
        elif not held or stem.endswith(".pressure"):
            suffix = {"m": "_m", "m/s": "_m_s", "rad/s": "_rad_s"}.get(unit, "")
            out[f"{key}{suffix}"] = float(v)
    for name, v in point.inputs.items():
        out[f"{name} (input held)"] = float(v)
    return out
