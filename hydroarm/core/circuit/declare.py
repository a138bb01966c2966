"""The component interface: what a circuit component declares (issue 28; docs/components.md).

A component is one module under `hydroarm.core.circuit.components` holding

* ``DECLARATION``: a `Component` with its parameters (name, unit, default, rule,
  whether sweepable), its states (name, unit, scale) and its ports (hydraulic nodes,
  mechanical nodes, signals in and out);
* its laws, numba functions on SI floats with fixed signatures (`system` calls them):

  ``law(t, c, P, po, s, so, d, port, pn, s_all, sig, thr, cap)``  (required)
      the component's through variables at its ports, written to ``thr[c, k]`` (hydraulic:
      the flow [m³/s] the component delivers *into* the node of port k; mechanical: the
      force [N] or torque [N m] it exerts *on* the node), its storage at each port in
      ``cap[c, k]`` (hydraulic: the compliance dV/dp [m³/Pa] it adds to the node;
      mechanical: the mass [kg] or inertia [kg m²]), and the derivatives of its own states
      ``d[so + i]``;
  ``signals(t, P, po, s, so, port, pn, sig)``  (optional)
      the values of its signal outputs ``sig[port[k]]`` (and, for a pressure source, the
      pressure of its node ``pn[port[k]]``) from states and input signals only;
  ``project(t, h, P, po, s_old, s, so, port, mass)``  (optional)
      the non-smooth part of a step, applied to the new state ``s`` in place (stops, dry
      friction, latches, stroke limits);
  ``energy(t, c, P, po, s, so, d, eo, port, pn, xm, vm, sig, thr, cap, pref)``  (optional)
      the rates [W] of the component's declared energy terms but the last
      (``energies``), written to ``d[eo]``, ``d[eo + 1]`` …: called after every law and
      node sum (``d`` holds the nodes' ṗ and the accelerations) when the circuit is built
      with an energy account; the kernel gives the last term the rest of the component's
      absorbed power, so the terms add up to it exactly (docs/components.md "Energy");
  ``transmit(P, po, q, out)``  (a linkage's)
      the position of its ``slaved`` mechanical port as a function of its other mechanical
      port's position q: ``out[0] = g(q)``, ``out[1] = g'(q)``, ``out[2] = g''(q)`` and
      ``out[3]`` the lever that carries the slave's force to the master (g' by virtual work;
      the paper's printed torque arm r/n for its crank); the kernel moves the slave with the
      master and carries its forces back.

* ``derived`` (optional): `Derived` quantities, constants of the parameters alone (a
  valve's flow coefficient C_d·w·√(2/ρ), a relief valve's spring term √p_nom/k_cs), each a
  plain function whose arguments are named after the parameters (or earlier derived
  quantities) it takes. They are computed once per parameter vector, not in every call of
  a law: the kernel's entries (`with_derived`) fill
  them in their own copy of P before a run, so that a sweep's row, a fit's trial or a
  co-simulation input that changes a parameter changes them too, and the law reads them
  from P like a parameter (``P[po + par.flow_coefficient]``). They are not file keys nor
  sweep names.

Indices are generated here: ``par, st, pt = DECLARATION.indices()`` gives named tuples
(``par.cracking_pressure`` is that parameter's offset in the component's block, ``st.open``
a state's, ``pt.inlet`` a port's), which numba freezes as compile-time constants. A block
of P holds the parameters, then the derived quantities, then the arrays. File keys, sweep
and fit names (``<component>.<parameter>``), defaults, validation and the docs tables all
come from the declaration; nothing else lists them.
"""

from __future__ import annotations

import collections
import inspect
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

# port domains
HYDRAULIC = "hydraulic"  # a node with a pressure state [Pa]
TRANSLATIONAL = "translational"  # a mechanical node: position [m], velocity [m/s]
ROTATIONAL = "rotational"  # a mechanical node: angle [rad], angular velocity [rad/s]
MECHANICAL_ANY = "mechanical"  # a mechanical node of either kind (a sensor's)
SIGNAL_IN = "signal_in"  # a signal read (any unit)
SIGNAL_OUT = "signal_out"  # a signal written (any unit)
FLOW_TAP = "flow_tap"  # another component's port whose flow is read ("component.port")
DOMAINS = (HYDRAULIC, TRANSLATIONAL, ROTATIONAL, MECHANICAL_ANY, SIGNAL_IN, SIGNAL_OUT, FLOW_TAP)
MECHANICAL = (TRANSLATIONAL, ROTATIONAL, MECHANICAL_ANY)
MAX_PORTS = 8  # the most ports a component may declare (a flow tap's index is c·MAX_PORTS + k)

_RULE = re.compile(r"^\s*(>=|>|<=|<)\s*([-+0-9.eE]+|inf)\s*$")


@dataclass(frozen=True)
class Param:
    """A parameter: ``name`` (the file key), SI ``unit`` (pint syntax: ``"m**3/s/Pa"``; ``""``
    dimensionless; ``"*"`` any unit, taken in SI base units: a signal's level or a gain),
    ``default`` (None: required), ``rule`` (``"> 0"``, ``">= 0"``, ``"in [0, 1]"``,
    ``"integer >= 1"``, or ``""``), ``choices`` (names of the codes 0, 1, … of a kind
    parameter, given in files by name), ``sweepable`` and a one-line ``doc``."""

    name: str
    unit: str
    default: float | str | None
    rule: str = ""
    doc: str = ""
    choices: tuple[str, ...] = ()
    sweepable: bool = True

    def check(self, value: float) -> str | None:
        """The problem with an SI value under this parameter's rule, or None."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"expected a number, got {value!r}"
        if math.isnan(value):
            return "is not a number"
        if math.isinf(value) and not self.allows_infinity:
            return f"{value!r} is not a finite number"
        if self.choices:
            if value not in range(len(self.choices)):
                return f"must be one of {', '.join(self.choices)}"
            return None
        rule = self.rule.strip()
        if rule.startswith("integer"):
            if math.isinf(value) or not float(value).is_integer():
                return f"must be a whole number, got {value!r}"
            rule = rule[len("integer") :].strip()
        if not rule:
            return None
        if rule.startswith("in ["):
            lo, hi = (float(v) for v in rule[4:].rstrip("]").split(","))
            if not lo <= value <= hi:
                return f"must be in [{lo:g}, {hi:g}], got {value:g}"
            return None
        m = _RULE.match(rule)
        if m is None:
            raise ValueError(f"bad rule {self.rule!r} of parameter {self.name}")
        op, bound = m.group(1), float(m.group(2))
        ok = {">": value > bound, ">=": value >= bound, "<": value < bound, "<=": value <= bound}
        if not ok[op]:
            return f"must be {op} {bound:g}, got {value:g}"
        return None

    @property
    def allows_infinity(self) -> bool:
        """Whether +inf is an accepted value (a limit that is off by default)."""
        return self.default == math.inf or self.default == -math.inf


@dataclass(frozen=True)
class State:
    """A state of the component: ``name``, SI ``unit``, ``scale`` (a typical magnitude, for
    error control and linearisation), ``initial`` (its value at t = 0: a number, or the name
    of a parameter that holds it) and ``doc``. ``count``: the name of an integer parameter
    when the state repeats (a line's segments), or that name less a whole number
    (``"segments - 1"``), else 1. ``held``: the law's derivative of it is always 0 and
    only the projection writes it (a line's wave history): the adaptive method holds it over
    each of its steps, out of the solver's states, and updates it after the step."""

    name: str
    unit: str
    scale: float = 1.0
    initial: float | str = 0.0
    doc: str = ""
    count: str | int = 1
    held: bool = False


@dataclass(frozen=True)
class Energy:
    """A named share of a component's absorbed power, integrated as a state [J] when the
    circuit keeps an energy account: ``name`` (``<component>.<name>`` in results) and
    ``doc``. A component that declares none has one term, ``energy``: all of its power."""

    name: str
    doc: str = ""


@dataclass(frozen=True)
class Port:
    """A port: ``name`` (the key under ``ports = {…}``), ``domain`` (module constants),
    ``optional`` (a signal input that may stay unconnected: the law then uses a parameter),
    ``compliant`` (hydraulic: the component always adds compliance to this node, so the
    node has a pressure state), ``drives`` (mechanical: the component is the node's
    actuator; one actuator per mechanical node), ``inertial`` (mechanical: the component
    gives the node its mass or inertia), ``prescribes`` (hydraulic: the component sets the
    node's pressure, a tank or pressure source) and ``doc``."""

    name: str
    domain: str
    doc: str = ""
    optional: bool = False
    compliant: bool = False
    drives: bool = False
    inertial: bool = False
    prescribes: bool = False
    slaved: bool = False


@dataclass(frozen=True)
class Input:
    """An input a co-simulation master sets between steps (an FMU input, docs/fmu.md):
    ``<component>.<name>``, held over each step. Its value [SI, the parameter's unit] is
    written to ``parameter`` in the parameter vector: the law is the component's own, no
    other path. ``hold``: other parameters set to these values while the input drives the
    component (a signal source's waveform made constant), applied once the master has set
    the input (until then the component runs as its file says); ``unless_port``: the input
    exists only while that optional signal port is unconnected (a pump's speed when no
    speed signal drives it); ``port``: a signal output that carries the input's value (its
    start value is that signal at the start; otherwise the parameter's value); ``doc``: one
    line."""

    name: str
    parameter: str
    doc: str = ""
    hold: tuple[tuple[str, float | str], ...] = ()  # a kind parameter by its choice
    unless_port: str = ""
    port: str = ""


@dataclass(frozen=True)
class Derived:
    """A quantity derived from the component's parameters alone (module doc): ``name`` (its
    field in ``par``), SI ``unit``, ``formula`` (a plain Python function, compiled into the
    kernel as it is, whose argument names are parameters of the component or derived
    quantities declared before this one) and a one-line ``doc``."""

    name: str
    unit: str
    formula: Callable[..., float]
    doc: str = ""

    @property
    def arguments(self) -> tuple[str, ...]:
        """The names the formula takes, in its order."""
        return tuple(inspect.signature(self.formula).parameters)


@dataclass(frozen=True)
class Component:
    """The declaration of one component type (module doc)."""

    type: str
    summary: str
    parameters: tuple[Param, ...]
    states: tuple[State, ...]
    ports: tuple[Port, ...]
    source: str = ""  # where the law and its defaults come from
    flow_port: str = ""  # the port whose flow is the component's "flow" output
    reads_flows: bool = False  # reads other components' flows (evaluated after them)
    arrays: tuple[Param, ...] = ()  # variable-length parameters (a table's times, values)
    inputs: tuple[Input, ...] = ()  # what a co-simulation master may set between steps
    # the shares of its absorbed power (the last: the rest; none: one term, "energy")
    energies: tuple[Energy, ...] = ()
    derived: tuple[Derived, ...] = ()  # constants of the parameters, computed once per P
    _cache: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        for group in (
            self.parameters + self.derived + self.arrays,
            self.states,
            self.ports,
            self.inputs,
            self.energies,
        ):
            names = [x.name for x in group]
            if len(set(names)) != len(names):
                raise ValueError(f"{self.type}: duplicate names in {names}")
        known = set(self.parameter_names)
        for q in self.derived:
            for name in q.arguments:
                if name not in known:
                    raise ValueError(
                        f"{self.type}: derived {q.name} takes {name!r}, neither a parameter "
                        "nor a derived quantity declared before it"
                    )
            known.add(q.name)
        for p in self.ports:
            if p.domain not in DOMAINS:
                raise ValueError(f"{self.type}.{p.name}: unknown domain {p.domain!r}")
        for i in self.inputs:
            for name in (i.parameter, *(k for k, _ in i.hold)):
                if name not in self.parameter_names:
                    raise ValueError(f"{self.type}: input {i.name} names no parameter {name!r}")
            for port in (i.unless_port, i.port):
                if port and port not in self.port_names:
                    raise ValueError(f"{self.type}: input {i.name} names no port {port!r}")

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    @property
    def energy_names(self) -> tuple[str, ...]:
        """The names of its energy terms (`Energy`; ``("energy",)`` when it declares
        none): the last takes the rest of its absorbed power."""
        return tuple(e.name for e in self.energies) or ("energy",)

    @property
    def port_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.ports)

    def parameter(self, name: str) -> Param:
        for p in self.parameters + self.arrays:
            if p.name == name:
                return p
        raise KeyError(name)

    def port(self, name: str) -> Port:
        for p in self.ports:
            if p.name == name:
                return p
        raise KeyError(name)

    def indices(self) -> tuple[Any, Any, Any]:
        """Named tuples of the offsets of parameters, states and ports (module doc). A
        repeated state's offset is that of its first element, so the repeated states are
        declared after every single one; where there are several, the law finds the offset of
        each after the first by adding up the counts before it (from its parameters). Array
        parameters follow the scalars and the derived quantities (whose offsets follow the
        scalars'): ``par.<array>`` is the offset of the array's length (a float), its values
        follow."""
        if "indices" not in self._cache:
            make: Any = collections.namedtuple
            stem = _camel(self.type)
            pnames = (
                list(self.parameter_names)
                + [q.name for q in self.derived]
                + [a.name for a in self.arrays]
            )
            snames = list(self.state_names)
            n = len(self.parameters) + len(self.derived)
            pvals = list(range(n)) + [n + i for i in range(len(self.arrays))]
            self._cache["indices"] = (
                make(f"{stem}Parameters", pnames or ["none"])(*(pvals or [0])),
                make(f"{stem}States", snames or ["none"])(*(range(len(snames)) or [0])),
                make(f"{stem}Ports", list(self.port_names) or ["none"])(
                    *(range(len(self.ports)) or [0])
                ),
            )
        return self._cache["indices"]

    def derive(self, values: dict[str, float]) -> list[float]:
        """The derived quantities' values (in declaration order) from the parameters' SI
        values, the formulas run as Python (the kernel runs the same functions compiled:
        the same IEEE operations, the same bits)."""
        known = dict(values)
        out = []
        for q in self.derived:
            try:
                v = float(q.formula(*(known[a] for a in q.arguments)))
            except (ArithmeticError, ValueError):  # the kernel's IEEE result is inf or nan
                v = math.nan
            known[q.name] = v
            out.append(v)
        return out

    def state_count(self, values: dict[str, float]) -> list[int]:
        """How many entries each declared state has for these parameter values."""
        out = []
        repeated = False
        for s in self.states:
            if isinstance(s.count, int):
                n = s.count
            else:
                name, _, less = s.count.partition("-")
                n = int(values[name.strip()]) - (int(less) if less.strip() else 0)
            if s.count != 1:
                repeated = True
            elif repeated:
                raise ValueError(f"{self.type}: the repeated states must be declared last")
            out.append(n)
        return out


def _camel(name: str) -> str:
    return "".join(w.capitalize() for w in name.split("_"))
