"""A circuit advanced piece by piece, its inputs set between the pieces (issue 29).

`CircuitStepper` is `simulate` for a caller that owns
the clock: a co-simulation master (the circuit FMU of `hydroarm.fmu`), a live
application. It takes whole fixed steps of the one system kernel
(`advance`: the loop of ``integrate`` around the one
stepper ``step``), from the state ``simulate`` starts from (the file's, or the equilibrium
with ``[initial] equilibrium = true``), so that a run with no input set gives ``simulate``'s
trajectory bit for bit at the same step, whatever pieces the run is cut into (the time
bookkeeping is `StepClock`'s: step k starts at t0 + k·h).

Inputs are what the components declare (`Input`), no
name is known here: a signal source's value (a setpoint, a lever, a pump speed), a mass's
external force, a valve's demand or a pump's speed where no signal drives them, a tank's
pressure. An input is named ``<component>.<input>``; its value is written into the
parameter vector the kernel reads (the component's own law, no other path) and held over
every step until set again (zero-order hold). Until the caller sets an input, the component
runs as its file says (a signal source its waveform); an input set before the first step
acts from the start, as the same value written into the file would.

Outputs are the columns of `CircuitResult` at the current
state, with the same names, units and numbers as ``simulate``'s (``<node>_pressure_bar``,
``<component>_flow_lpm``, ``<node>_position_m``, ``<signal>_signal``, …).

A mechanism's payloads and contacts (issue 32: a live task's grasped load, a floor) change
between calls too, without compiling anything: `CircuitStepper.set_payloads` adds
bodies to the mechanism's links (the tree's masses and inertias, made by
`compile` as for a file's own payloads, are
swapped in the stepper's own copy of the arrays the kernel takes), and
`CircuitStepper.stop_joints` stops joints where a contact puts them (an inelastic
stop: position set, velocity zero, pressures kept).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..core.circuit import declare
from ..errors import HydroarmError
from ..integrators.system import STEPPERS, advance, advance_records, start_state, stepper
from .circuit import CircuitResult, CompiledCircuit, equilibrium_state
from .mechanism import Payload
from .stepper import StepClock, finite

#: the number of each fixed-step method of a circuit (an FMU's ``solver.method``)
METHOD_CODES: dict[str, int] = {name: i for i, name in enumerate(STEPPERS)}
#: where the mechanism's tree (`TreeModel`'s fields) lies in the
#: net (`hydroarm.core.circuit.system`: net[11:21])
TREE_SLICE = slice(11, 21)


@dataclass(frozen=True)
class CircuitInput:
    """An input of a compiled circuit: ``name`` (``<component>.<input>``), its SI ``unit``
    (pint syntax; ``"*"``: any, as the signal it drives), ``doc``, the ``param`` it sets and
    its ``index`` in the parameter vector, the ``hold`` values set with it (index, value)
    and the ``signal`` that carries it (``""``: none; its start value is then the
    parameter's)."""

    name: str
    unit: str
    doc: str
    param: declare.Param
    index: int
    hold: tuple[tuple[int, float], ...]
    signal: str


def circuit_inputs(compiled: CompiledCircuit) -> list[CircuitInput]:
    """Every input of a compiled circuit (module doc), in the components' order."""
    out = []
    for c, decl in zip(compiled.circuit.components, compiled.decls, strict=True):
        for i in decl.inputs:
            if i.unless_port and i.unless_port in c.ports:
                continue  # a signal drives it
            p = decl.parameter(i.parameter)
            hold = []
            for key, v in i.hold:
                hp = decl.parameter(key)
                code = float(hp.choices.index(v)) if isinstance(v, str) else float(v)
                hold.append((compiled.parameter_index[f"{c.name}.{key}"], code))
            out.append(
                CircuitInput(
                    f"{c.name}.{i.name}",
                    p.unit,
                    i.doc,
                    p,
                    compiled.parameter_index[f"{c.name}.{i.parameter}"],
                    tuple(hold),
                    c.ports.get(i.port, "") if i.port else "",
                )
            )
    return out


class CircuitStepper(StepClock):
    """A compiled circuit advanced in fixed steps from its start, with inputs set between
    calls (module doc).

    Parameters
    ----------
    compiled : the circuit, compiled (`build`)
    method : a fixed-step method of the system kernel (default: the circuit's)
    step : internal fixed step h [s] (default: the circuit's)
    """

    def __init__(
        self, compiled: CompiledCircuit, *, method: str | None = None, step: float | None = None
    ):
        c = compiled.circuit
        method = c.method if method is None else method
        if method not in STEPPERS:
            raise HydroarmError(
                "solver.method",
                f"must be {', '.join(STEPPERS)} (a circuit stepped piece by piece takes fixed "
                f"steps), got {method!r}",
            )
        h = c.step if step is None else finite("solver.step", step)
        if not h > 0:
            raise HydroarmError("solver.step", f"must be a positive time, got {step!r}")
        self.compiled = compiled
        self.method = method
        self.step = h
        self._kernel = stepper(method)
        self._t0 = 0.0  # simulate's start
        self._k = 0
        self._requested = 0.0
        self._failed = False
        self.P = compiled.P.copy()
        self._s0 = equilibrium_state(compiled) if c.equilibrium else compiled.s0
        self._s = start_state(self._t0, self._s0, self.P, compiled.net)
        self.inputs = {i.name: i for i in circuit_inputs(compiled)}
        self._driven: set[str] = set()  # the inputs set so far
        self.net: tuple = compiled.net  # the kernel's arrays (the tree's replaced by set_payloads)
        self.payloads: tuple[Payload, ...] = ()  # bodies added to the mechanism's links

    # inputs ----------------------------------------------------------------------------
    def start_values(self) -> dict[str, float]:
        """Each input's value at the start: its signal's (a signal source's value at t0),
        else its parameter's."""
        outs = self.outputs()
        return {
            n: outs[f"{i.signal}_signal"] if i.signal else float(self.compiled.P[i.index])
            for n, i in self.inputs.items()
        }

    def set_input(self, name: str, value) -> None:
        """Set an input (``<component>.<input>``) [SI], held until set again."""
        if name not in self.inputs:
            known = ", ".join(self.inputs) or "none"
            raise HydroarmError(name, f"no input of that name (inputs: {known})")
        i = self.inputs[name]
        v = finite(name, value)
        problem = i.param.check(v)
        if problem:
            raise HydroarmError(name, problem)
        self.P[i.index] = v
        for index, held in i.hold:
            self.P[index] = held
        self._driven.add(name)
        if self._k == 0:  # the start's sources and latches, with the input (as simulate's)
            self._s = start_state(self._t0, self._s0, self.P, self.compiled.net)

    # the mechanism -----------------------------------------------------------------------
    def set_payloads(self, payloads) -> None:
        """Bodies fixed to the mechanism's links from the next step on
        (`Payload` s, beside the file's own; ``()``: the
        file's alone): the tree's masses, centres of mass and inertias are the mechanism's
        compiled with them, swapped into this stepper's net (the kernel is not compiled
        again; the compiled circuit is not changed). Each is checked as a file's payload (its
        link known, its mass not negative, its inertia a rigid body's). The outputs' energy
        and torque columns stay the file's mechanism's."""
        mech = self.compiled.circuit.mechanism
        if mech is None:
            raise HydroarmError("payload", "the circuit has no mechanism")
        extra = tuple(payloads)
        tree = replace(mech, payloads=mech.payloads + extra).compile().tree
        net = list(self.net)
        net[TREE_SLICE] = list(tree)
        self.net = tuple(net)
        self.payloads = extra

    @property
    def state(self) -> np.ndarray:
        """The state vector now (a copy; `CompiledCircuit.state_names` names its entries)."""
        return self._s.copy()

    def joint_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """The mechanism's joints' positions [rad, m] and velocities [rad/s, m/s] now, in the
        tree's order (copies)."""
        nh, nm = int(self.net[9][0]), int(self.net[9][1])
        nodes = np.asarray(self.net[21])
        return self._s[nh + nodes].copy(), self._s[nh + nm + nodes].copy()

    def stop_joints(self, positions: dict[int, float]) -> None:
        """Stop mechanism joints (tree index: position [rad, m]) there at rest: the position
        set, the velocity zero, the pressures and every other state kept (an inelastic stop
        at a contact, applied between calls). A coupled joint follows its master: stop the
        master."""
        mech = self.compiled.mechanism
        if mech is None:
            raise HydroarmError("joint", "the circuit has no mechanism")
        nh, nm = int(self.net[9][0]), int(self.net[9][1])
        for j, q in positions.items():
            if not 0 <= int(j) < mech.n or mech.master[int(j)] != int(j):
                raise HydroarmError("joint", f"{j!r} is not a free joint of the mechanism")
            node = int(self.net[21][int(j)])
            self._s[nh + node] = finite(f"joint.{mech.joint_names[int(j)]}", q)
            self._s[nh + nm + node] = 0.0

    # time ------------------------------------------------------------------------------
    def _steps(self, n: int) -> tuple[int, bool]:
        code, A, b, c = self._kernel
        net = self.net
        taken, bad = advance(code, A, b, c, self._t0, self._k, self.step, n, self._s, self.P, net)
        return int(taken), bool(bad)

    def record(self, n: int, record_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Take ``n`` whole steps, keeping the time [s] and the state after each step k
        (counted from the start) that is a multiple of ``record_every``: (T, S), the
        records `simulate` keeps of the same steps, bit for bit (a run recorded piece by
        piece, as a probe that stops once its answer is decided: `hydroarm.arm.simulate_arm`).
        A state that is not finite ends the pieces (`hydroarm.errors.HydroarmError` on
        ``solver.step``)."""
        if self._failed:
            raise HydroarmError("solver.step", "the run has left the physical bounds already")
        code, A, b, c = self._kernel
        taken, T, S, bad = advance_records(
            code, A, b, c, self._t0, self._k, self.step, int(n), int(record_every), self._s,
            self.P, self.net,
        )  # fmt: skip
        self._k += int(taken)
        self._requested = max(self._requested, self._k * self.step)
        if bad:
            self._failed = True
            raise HydroarmError("solver.step", self._failure())
        return T, S

    def _failure(self) -> str:
        return f"the state is not finite at t = {self.t:.6g} s: reduce the step ({self.step:g} s)"

    # outputs ---------------------------------------------------------------------------
    def outputs(self, names: list[str] | None = None) -> dict[str, float]:
        """Every output of `CircuitResult` at the current
        state (its names, its display units: bar, L/min, degrees), ``t_s`` left out; only
        those of ``names`` (known outputs) when given."""
        res = CircuitResult(self.compiled, np.array([self.t]), self._s[None, :], -1, self.P)
        return {k: float(v[0]) for k, v in res.columns(names).items() if k != "t_s"}

    def output_units(self) -> dict[str, str]:
        """Each output's unit in pint's syntax (`CircuitResult.display_units`)."""
        res = CircuitResult(self.compiled, np.array([self.t]), self._s[None, :], -1, self.P)
        return {k: u for k, u in res.display_units().items() if k != "t_s"}

    # state -----------------------------------------------------------------------------
    def get_state(self) -> np.ndarray:
        """The complete state as floats: t0, steps, requested time, failed, the state
        vector, the parameter vector (inputs included), which inputs are set; `set_state`
        restores it exactly."""
        driven = [float(n in self._driven) for n in self.inputs]
        head = [self._t0, float(self._k), self._requested, float(self._failed)]
        return np.concatenate([head, self._s, self.P, driven])

    def set_state(self, state) -> None:
        """Restore a state from `get_state` (of a stepper of the same circuit)."""
        s = np.asarray(state, dtype=float)
        ns, npar = self._s.size, self.P.size
        want = 4 + ns + npar + len(self.inputs)
        if s.shape != (want,):
            raise HydroarmError("state", f"must hold {want} numbers, got {s.shape}")
        self._t0, self._k, self._requested = float(s[0]), int(s[1]), float(s[2])
        self._failed = bool(s[3])
        self._s = s[4 : 4 + ns].copy()
        self.P = s[4 + ns : 4 + ns + npar].copy()
        flags = s[4 + ns + npar :]
        self._driven = {n for n, f in zip(self.inputs, flags, strict=True) if f}
