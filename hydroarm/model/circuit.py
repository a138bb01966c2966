"""Circuits of any shape: components joined at named nodes (issue 28; docs/components.md).

A `Circuit` is validated data in SI: its components (type, name, ports, parameter
values), its initial node pressures and its solver settings. `build` compiles it into
the fixed arrays of the system kernel (`hydroarm.core.circuit.system`), checking the
topology first (every error one line naming the field, before any work):

* an unknown component type, port or parameter, a required port or parameter missing, a
  value against its rule;
* a node connected in two domains (hydraulic and mechanical, say);
* a hydraulic node with no compliance (an algebraic loop: add a ``volume``) or held by two
  tanks; a mechanical node with no mass, with two, or driven by two actuators;
* a signal read but never written, written twice, or a loop of signals through components
  with no state between them.

`simulate` runs it on the one stepper family (`hydroarm.integrators.system`) and
returns a `CircuitResult` whose outputs are named after the circuit: every node's
pressure (``<node>_pressure_bar``), every mechanical node's position and velocity, every
component's flow (``<component>_flow_lpm``) and power (``<component>_power_w``), every
signal and every component state.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ..core.circuit import declare
from ..core.circuit.components import KIND, TYPES
from ..core.circuit.dispatch import HAS_ENERGY, HAS_PROJECT, HAS_SIGNALS, HAS_TRANSMIT
from ..core.circuit.system import (
    D_FLOW_TAP,
    D_HYDRAULIC,
    D_MECHANICAL,
    D_NONE,
    D_SIGNAL_IN,
    D_SIGNAL_OUT,
    MAX_PORTS,
    N_SYSTEM_PARAMETERS,
    SYSTEM,
    record_outputs,
)
from ..core.tree import TreeModel
from ..display import Summarised, span
from ..errors import HydroarmError
from ..files import atomic_write_text
from ..integrators.adaptive import integrate_circuit_adaptive, state_atol
from ..integrators.observers import (
    ONLINE_STATISTICS,
    SOURCE_FLOW,
    SOURCE_MECHANICAL,
    SOURCE_POWER,
    SOURCE_SIGNAL,
    SOURCE_STATE,
)
from ..integrators.observers import observe_many as run_observers
from ..integrators.system import STEPPERS, integrate, run_many, stepper
from ..plotting.circuit import plot_outputs
from .circuit_steady import reference_problems, steady_state
from .mechanism import CompiledMechanism, Mechanism

_DOMAIN_CODE = {
    declare.HYDRAULIC: D_HYDRAULIC,
    declare.TRANSLATIONAL: D_MECHANICAL,
    declare.ROTATIONAL: D_MECHANICAL,
    declare.MECHANICAL_ANY: D_MECHANICAL,
    declare.SIGNAL_IN: D_SIGNAL_IN,
    declare.SIGNAL_OUT: D_SIGNAL_OUT,
    declare.FLOW_TAP: D_FLOW_TAP,
}
DEFAULT_INITIAL_PRESSURE = 1.0e5  # [Pa] every node's pressure at t = 0 unless given


@dataclass(frozen=True)
class ComponentSpec:
    """One component of a circuit: its ``type`` (a registered component), its unique
    ``name``, its ``ports`` (port name → node or signal name; a flow tap: ``"comp.port"``),
    its parameter ``values`` in SI (the rest take their defaults; a kind parameter by its
    choice's name) and its ``arrays`` (a table's times and values, SI)."""

    type: str
    name: str
    ports: Mapping[str, str]
    values: Mapping[str, float | str] = field(default_factory=dict)
    arrays: Mapping[str, tuple[float, ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class Circuit:
    """A circuit: components, initial node pressures [Pa] and the run's settings."""

    name: str
    components: tuple[ComponentSpec, ...]
    system: Mapping[str, float] = field(default_factory=dict)
    initial_pressure: float = DEFAULT_INITIAL_PRESSURE
    initial: Mapping[str, float] = field(default_factory=dict)  # node -> pressure [Pa]
    equilibrium: bool = False  # start from the static state at the initial pose and inputs
    mechanism: Mechanism | None = None  # links and joints whose joints are mechanical nodes
    initial_joints: Mapping[str, float] = field(default_factory=dict)  # joint -> rad or m
    method: str = "rk4"
    step: float = 1.0e-5
    duration: float = 1.0
    record_every: int = 100

    def replace(self, **changes: Any) -> Circuit:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def with_values(self, values: Mapping[str, float]) -> Circuit:
        """A copy with parameters set by their names ``<component>.<parameter>``."""
        comps = {c.name: dict(c.values) for c in self.components}
        system = dict(self.system)
        for key, v in values.items():
            comp, _, pname = key.partition(".")
            if comp == "system":
                system[pname] = v
            elif comp in comps:
                comps[comp][pname] = v
            else:
                raise HydroarmError(key, "no component of that name")
        new = tuple(
            ComponentSpec(c.type, c.name, c.ports, comps[c.name], c.arrays) for c in self.components
        )
        return self.replace(components=new, system=system)


@dataclass(frozen=True)
class Node:
    """A node of a compiled circuit: ``name``, ``domain`` and its index in its domain."""

    name: str
    domain: str
    index: int


class CompiledCircuit:
    """A circuit compiled into the kernel's arrays (module doc): ``net``, the parameter
    vector ``P``, the initial state ``s0`` and the names of everything in them.

    ``energy``: keep an energy account, one state [J] a declared energy term of each
    component (and one for a mechanism), ``<component>.<term>_energy`` after every other
    state, integrated by the stepper with the rest (`hydroarm.core.circuit.system`,
    docs/components.md "Energy"); pressures count from ``energy_reference_pressure``
    [Pa]. Without it the net, the states and every result are as before, bit for bit."""

    def __init__(
        self, circuit: Circuit, energy: bool = False, energy_reference_pressure: float = 0.0
    ) -> None:
        self.circuit = circuit
        self.energy_reference_pressure = float(energy_reference_pressure)
        self.s0: np.ndarray = np.zeros(0)  # the initial state (`_states`)
        self.n_dynamic = 0  # the states but the energy account's
        # "<component>.<term>" -> its energy state (with energy=True, `_energy_states`)
        self.energy_states: dict[str, int] = {}
        _check_types(circuit)
        self.decls = [TYPES[c.type].DECLARATION for c in circuit.components]
        self.mechanism: CompiledMechanism | None = (
            circuit.mechanism.compile() if circuit.mechanism is not None else None
        )
        self._nodes()
        self._parameters()
        self._mechanics()
        self._states()
        self._orders()
        energy_table = self._energy_states() if energy else np.zeros((0, 7), np.int64)
        nc = len(circuit.components)
        self.net = (
            np.array([KIND[c.type] for c in circuit.components], np.int64),
            np.array(self.poff, np.int64),
            np.array(self.soff, np.int64),
            self.ports,
            self.domains,
            np.array(self.sig_order, np.int64),
            np.array(self.law_order, np.int64),
            np.array(self.proj_list, np.int64),
            self.fixed,
            np.array(
                [len(self.hydraulic), len(self.mechanical), len(self.signals), nc, len(self.s0)],
                np.int64,
            ),
            np.array([len(d.ports) for d in self.decls], np.int64),
            *self.tree,
            self.tree_nodes,
            self.joint_limits,
            self.slaves,
            self.couplings,
            self.coupling_laws,
            *self._scatter(),
            self._table(self.law_order),
            self._table(self.sig_order),
            self._table(self.proj_list),
            energy_table,
            np.array([self.energy_reference_pressure]),
        )

    def _energy_states(self) -> np.ndarray:
        """net[31]: the energy account's rows (component, kind, parameter offset, state
        offset, ports, first energy state, terms), a last row (−1, 0, 0, 0, 0, its state, 1)
        for a mechanism; the energy states appended to ``s0`` (at 0 J) and their names to
        ``state_names`` (`energy_states`: name → state index)."""
        comps = self.circuit.components
        s0 = list(self.s0)
        self.n_dynamic = len(s0)
        self.energy_states = {}
        rows = []
        for ci, (c, decl) in enumerate(zip(comps, self.decls, strict=True)):
            terms = decl.energy_names
            if HAS_ENERGY[c.type] != (len(terms) > 1):
                raise ValueError(f"{c.type}: an energy law needs two or more energy terms")
            rows.append(
                (
                    ci,
                    KIND[c.type],
                    self.poff[ci],
                    self.soff[ci],
                    len(decl.ports),
                    len(s0),
                    len(terms),
                )
            )
            for term in terms:
                self.energy_states[f"{c.name}.{term}"] = len(s0)
                s0.append(0.0)
        if self.mechanism is not None:
            rows.append((-1, 0, 0, 0, 0, len(s0), 1))
            self.energy_states["mechanism.energy"] = len(s0)
            s0.append(0.0)
        for key in self.energy_states:
            stem = key if key.endswith(".energy") else f"{key}_energy"
            self.state_names.append((stem, "J"))
        self.s0 = np.array(s0, np.float64)
        return np.array(rows, np.int64).reshape(-1, 7)

    def _table(self, order: list[int]) -> np.ndarray:
        """net[28] (the laws), net[29] (the signals), net[30] (the projections): a row a
        component in the order they run: (component, kind code, parameter offset, state
        offset, ports). The kernel's loops over the components take one table, not five
        arrays: a call passes every field of every array argument
        (`all_laws`)."""
        comps = self.circuit.components
        rows = [
            (c, KIND[comps[c].type], self.poff[c], self.soff[c], len(self.decls[c].ports))
            for c in order
        ]
        return np.array(rows, np.int64).reshape(-1, 5)

    def _scatter(self) -> tuple[np.ndarray, np.ndarray]:
        """net[26], net[27]: the (component, port, node) of every hydraulic and every
        mechanical port, sorted by node and, within a node, in the order the laws run (law
        order, then port order): the order in which the kernel adds the laws' through
        variables and storages to each node's sums, each law adding its own ports
        (`hydroarm.core.circuit.dispatch`, ``law_of``), the order the sums always took."""
        lists: dict[int, list[tuple[int, int, int]]] = {D_HYDRAULIC: [], D_MECHANICAL: []}
        for c in self.law_order:
            for k in range(len(self.decls[c].ports)):
                dom = int(self.domains[c, k])
                if dom in lists:
                    lists[dom].append((c, k, int(self.ports[c, k])))
        return tuple(  # type: ignore[return-value]
            np.array(sorted(lists[d], key=lambda e: e[2]), np.int64).reshape(-1, 3)
            for d in (D_HYDRAULIC, D_MECHANICAL)
        )

    # ---------------------------------------------------------------- topology ---
    def _nodes(self) -> None:
        circuit = self.circuit
        comps = circuit.components
        names = {c.name for c in comps}
        domain_of: dict[str, tuple[str, str]] = {}  # node -> (domain family, first user)
        self.hydraulic: dict[str, int] = {}
        self.mechanical: dict[str, int] = {}
        self.mech_domain: dict[str, str] = {}
        self.signals: dict[str, int] = {}
        self.ports = np.full((len(comps), MAX_PORTS), -1, np.int64)
        self.domains = np.full((len(comps), MAX_PORTS), D_NONE, np.int64)
        mech = self.mechanism
        for name, kind in zip(mech.joint_names, mech.joint_types, strict=True) if mech else ():
            if name in names:
                raise HydroarmError(
                    f"component.{name}.name", "a component named as a joint of the mechanism"
                )
            self.mechanical[name] = len(self.mechanical)
            self.mech_domain[name] = (
                declare.TRANSLATIONAL if kind == "prismatic" else declare.ROTATIONAL
            )
            domain_of[name] = ("mechanical", f"mechanism.joint.{name}")
        writers: dict[str, str] = {}
        readers: dict[str, list[str]] = {}
        taps: list[tuple[int, int, str, str]] = []
        for ci, (c, decl) in enumerate(zip(comps, self.decls, strict=True)):
            field_ = f"component.{c.name}.ports"
            for pname in c.ports:
                if pname not in decl.port_names:
                    raise HydroarmError(
                        f"{field_}.{pname}",
                        f"unknown port of a {c.type} (ports: {', '.join(decl.port_names)})",
                    )
            for k, port in enumerate(decl.ports):
                target = c.ports.get(port.name)
                if target is None:
                    if port.optional:
                        continue
                    raise HydroarmError(f"{field_}.{port.name}", "not connected")
                if not isinstance(target, str) or not target.strip():
                    raise HydroarmError(f"{field_}.{port.name}", "must name a node")
                self.domains[ci, k] = _DOMAIN_CODE[port.domain]
                if port.domain == declare.FLOW_TAP:
                    taps.append((ci, k, target, f"{field_}.{port.name}"))
                    continue
                family = (
                    "signal"
                    if port.domain in (declare.SIGNAL_IN, declare.SIGNAL_OUT)
                    else ("mechanical" if port.domain in declare.MECHANICAL else "hydraulic")
                )
                if target in names and family != "signal":
                    pass  # a node may share a component's name
                seen = domain_of.setdefault(target, (family, f"{c.name}.{port.name}"))
                if seen[0] != family:
                    raise HydroarmError(
                        f"{field_}.{port.name}",
                        f"{target!r} is a {seen[0]} node (at {seen[1]}), not a {family} one",
                    )
                if family == "hydraulic":
                    self.ports[ci, k] = self.hydraulic.setdefault(target, len(self.hydraulic))
                elif family == "mechanical":
                    self.ports[ci, k] = self.mechanical.setdefault(target, len(self.mechanical))
                    if port.domain != declare.MECHANICAL_ANY:
                        had = self.mech_domain.setdefault(target, port.domain)
                        if had != port.domain:
                            raise HydroarmError(
                                f"{field_}.{port.name}",
                                f"{target!r} is a {had} node, not a {port.domain} one",
                            )
                else:
                    self.ports[ci, k] = self.signals.setdefault(target, len(self.signals))
                    if port.domain == declare.SIGNAL_OUT:
                        if target in writers:
                            raise HydroarmError(
                                f"{field_}.{port.name}",
                                f"signal {target!r} is already written by {writers[target]}",
                            )
                        writers[target] = c.name
                    else:
                        readers.setdefault(target, []).append(f"{c.name}.{port.name}")
        for sig, who in readers.items():
            if sig not in writers:
                raise HydroarmError(
                    f"component.{who[0].replace('.', '.ports.')}",
                    f"signal {sig!r} is read but no component writes it",
                )
        for node in self.mechanical:
            self.mech_domain.setdefault(node, declare.TRANSLATIONAL)
        index = {c.name: i for i, c in enumerate(comps)}
        for ci, k, target, fld in taps:
            cname, _, pname = target.partition(".")
            if cname not in index:
                raise HydroarmError(fld, f"{target!r}: no component {cname!r}")
            tdecl = self.decls[index[cname]]
            if pname not in tdecl.port_names or tdecl.port(pname).domain != declare.HYDRAULIC:
                hyd = [p.name for p in tdecl.ports if p.domain == declare.HYDRAULIC]
                raise HydroarmError(
                    fld, f"{target!r}: not a hydraulic port (of {cname}: {', '.join(hyd)})"
                )
            self.ports[ci, k] = index[cname] * MAX_PORTS + tdecl.port_names.index(pname)
        self.writers = writers
        self._check_nodes()

    def _check_nodes(self) -> None:
        comps = self.circuit.components
        self.fixed = np.zeros(len(self.hydraulic), np.int64)
        compliant = np.zeros(len(self.hydraulic), bool)
        inertial: dict[int, list[str]] = {}
        drives: dict[int, list[str]] = {}
        for ci, (c, decl) in enumerate(zip(comps, self.decls, strict=True)):
            for k, port in enumerate(decl.ports):
                i = self.ports[ci, k]
                if i < 0 or port.domain == declare.FLOW_TAP:
                    continue
                if port.domain == declare.HYDRAULIC:
                    if port.prescribes:
                        if self.fixed[i]:
                            other = comps[self.fixed[i] - 1].name
                            raise HydroarmError(
                                f"component.{c.name}.ports.{port.name}",
                                f"node {c.ports[port.name]!r} is already held by {other}",
                            )
                        self.fixed[i] = ci + 1
                    compliant[i] |= port.compliant
                elif port.domain in declare.MECHANICAL:
                    if port.inertial:
                        inertial.setdefault(i, []).append(c.name)
                    if port.drives:
                        drives.setdefault(i, []).append(c.name)
        for name, i in self.hydraulic.items():
            if not compliant[i] and not self.fixed[i]:
                raise HydroarmError(
                    f"node.{name}",
                    "no compliance at this node (an algebraic loop): add a "
                    f'[[component]] type = "volume" with ports = {{port = "{name}"}}, or join '
                    "it to a cylinder chamber, a line or a tank",
                )
        nt = self.mechanism.n if self.mechanism is not None else 0
        slaved = {
            int(self.ports[ci, k])
            for ci, decl in enumerate(self.decls)
            for k, p in enumerate(decl.ports)
            if p.slaved
        }
        for name, i in self.mechanical.items():
            who = inertial.get(i, [])
            if not who and i >= nt and i not in slaved:
                raise HydroarmError(
                    f"node.{name}", "no mass or inertia moves this mechanical node: add one"
                )
            if len(who) > 1:
                raise HydroarmError(
                    f"node.{name}", f"moved by two masses ({', '.join(who)}); join them into one"
                )
            if len(drives.get(i, [])) > 1:
                raise HydroarmError(
                    f"node.{name}",
                    f"two components drive one mechanical degree of freedom "
                    f"({', '.join(drives[i])}); two cylinders side by side are one cylinder "
                    "with the summed areas",
                )
        self.inertial = {i: who[0] for i, who in inertial.items()}

    def _mechanics(self) -> None:
        """The mechanism's arrays (its joints are the first mechanical nodes) and the
        linkages' slaves, masters first; a slave's master needs a mass, a tree joint or a
        master of its own, and no node is positioned twice or in a loop."""
        comps = self.circuit.components
        mech = self.mechanism
        nt = mech.n if mech is not None else 0
        if mech is not None:
            self.tree = mech.tree
            self.joint_limits = mech.kernel_limits()
            self.couplings = mech.couplings
            self.coupling_laws = mech.coupling_laws
        else:
            z = np.zeros((0, 3))
            self.tree = TreeModel(
                np.zeros(0, np.int64), np.zeros(0, np.int64), z, np.zeros((0, 3, 3)), z,
                np.zeros(0), z, np.zeros((0, 3, 3)), np.zeros(3), np.zeros((0, 6, 6)),
            )  # fmt: skip
            self.joint_limits = np.zeros((0, 4))
            self.couplings = np.zeros((0, 2), np.int64)
            self.coupling_laws = np.zeros((0, 2))
        self.tree_nodes = np.arange(nt, dtype=np.int64)
        master_of: dict[int, tuple[int, int]] = {}  # slave node -> (master node, component)
        for ci, (c, decl) in enumerate(zip(comps, self.decls, strict=True)):
            if not HAS_TRANSMIT[c.type]:
                continue
            mech_ports = [k for k, p in enumerate(decl.ports) if p.domain in declare.MECHANICAL]
            slave_k = next(k for k in mech_ports if decl.ports[k].slaved)
            master_k = next(k for k in mech_ports if not decl.ports[k].slaved)
            sl, ma = int(self.ports[ci, slave_k]), int(self.ports[ci, master_k])
            fld = f"component.{c.name}.ports.{decl.ports[slave_k].name}"
            if sl == ma:
                raise HydroarmError(fld, "a linkage between a node and itself")
            if sl < nt:
                raise HydroarmError(
                    fld, f"{c.ports[decl.ports[slave_k].name]!r} is a joint of the mechanism: "
                    "a joint is the linkage's master (its joint port)",
                )  # fmt: skip
            if sl in master_of:
                other = comps[master_of[sl][1]].name
                raise HydroarmError(fld, f"this node is already positioned by {other}")
            master_of[sl] = (ma, ci)
        order: list[int] = []

        def place(node: int, path: list[int]) -> None:
            if node in order or node not in master_of:
                return
            if node in path:
                raise HydroarmError(
                    f"component.{comps[master_of[node][1]].name}",
                    "linkages position each other in a loop",
                )
            place(master_of[node][0], path + [node])
            order.append(node)

        for node in sorted(master_of):
            place(node, [])
        self.slaves = np.array(
            [(n, master_of[n][0], master_of[n][1]) for n in order], np.int64
        ).reshape(len(order), 3)
        names = list(self.mechanical)
        self._check_dead_centres(order, master_of)
        self._check_coupled_drives(master_of)
        for n in order:  # a chain of linkages must end at a mass or a joint
            root = n
            while root in master_of:
                root = master_of[root][0]
            if root >= nt and root not in self.inertial:
                raise HydroarmError(
                    f"node.{names[root]}",
                    "no mass or inertia moves this mechanical node: add one",
                )

    def _check_coupled_drives(self, master_of: dict) -> None:
        """A coupled joint and its master are one degree of freedom: actuators driving two
        joints of one coupled group (directly or through linkages) are refused, as two
        actuators driving one node are."""
        mech = self.mechanism
        if mech is None or not mech.couplings.size:
            return
        names = list(self.mechanical)
        driven: dict[int, dict[int, str]] = {}  # free joint -> {joint: its actuator}
        for ci, (c, decl) in enumerate(zip(self.circuit.components, self.decls, strict=True)):
            for k, port in enumerate(decl.ports):
                if not (port.drives and port.domain in declare.MECHANICAL):
                    continue
                node = int(self.ports[ci, k])
                while node in master_of:
                    node = master_of[node][0]
                if node >= mech.n:
                    continue
                group = driven.setdefault(int(mech.master[node]), {})
                for joint, who in group.items():
                    if joint != node:
                        how = "; ".join(
                            f"{names[x]!r} follows {names[mech.master[x]]!r}"
                            for x in (node, joint)
                            if mech.master[x] != x
                        )
                        raise HydroarmError(
                            f"component.{c.name}",
                            f"drives joint {names[node]!r}, which {who} drives too through "
                            f"the coupling ({how}): a coupled joint has no degree of freedom "
                            "of its own; drive one joint of the coupled group",
                        )
                group.setdefault(node, c.name)

    def _master_range(self, node: int) -> tuple[float, float]:
        """The range a linkage's master node moves in: a joint's limits (a free joint's
        narrowed by the joints coupled to it; a coupled joint's as its master puts it), or
        the end stops of the mass or inertia that moves it (±inf: none)."""
        mech = self.mechanism
        if mech is not None and node < mech.n:
            m, r, o = int(mech.master[node]), float(mech.ratio[node]), float(mech.offset[node])
            low, high = float(self.joint_limits[m, 2]), float(self.joint_limits[m, 3])
            if m == node:
                return low, high
            if r == 0.0:
                return o, o
            a, b = r * low + o, r * high + o
            return min(a, b), max(a, b)
        owner = self.inertial.get(node)
        for c in self.circuit.components:
            if c.name == owner:
                for lo, hi in (("angle_min", "angle_max"), ("position_min", "position_max")):
                    if lo in c.values or hi in c.values:
                        return (
                            float(c.values.get(lo, -math.inf)),
                            float(c.values.get(hi, math.inf)),
                        )
        return -math.inf, math.inf

    def _check_dead_centres(self, order: list[int], master_of: dict) -> None:
        """A linkage whose ratio g' vanishes, changes sign or is not finite (a toggle, a
        four-bar that cannot be assembled) inside its master's range (a crank or a pivot
        cylinder past dead centre) is refused; a master without limits is checked over a
        whole turn about its initial position. A chain's inner linkage is checked over the
        positions its master takes as the chain's root master moves in its range. A
        rotational slave whose angle (taken within ±180° of its zero) would jump by a turn
        there is refused too."""
        comps = self.circuit.components
        names = list(self.mechanical)
        out = np.zeros(4)
        grids: dict[int, np.ndarray] = {}  # node -> its positions over its root's grid
        ranges: dict[int, tuple[float, float]] = {}  # root master -> its range
        for n in order:  # masters before slaves
            ma, ci = master_of[n]
            root = ma
            while root in master_of:
                root = master_of[root][0]
            if root not in ranges:
                lo, hi = self._master_range(root)
                if not (math.isfinite(lo) and math.isfinite(hi)):
                    q0 = self._initial_position(root)
                    lo, hi = max(lo, q0 - math.pi), min(hi, q0 + math.pi)
                ranges[root] = (lo, hi)
                grids[root] = np.linspace(lo, hi, 721)
            lo, hi = ranges[root]
            root_grid = grids[root]
            rot = self.mech_domain[names[root]] == declare.ROTATIONAL
            show = (lambda v: f"{math.degrees(v):.4g} deg") if rot else (lambda v: f"{v:.4g} m")
            module = TYPES[comps[ci].type]
            P = np.array([self.values[ci][p.name] for p in self.decls[ci].parameters])
            position = np.empty(root_grid.size)
            ratio = np.empty(root_grid.size)
            for i, q in enumerate(grids[ma]):
                module.transmit(P, 0, float(q), out)
                position[i], ratio[i] = out[0], out[1]
            grids[n] = position
            finite = np.isfinite(ratio) & np.isfinite(position)
            bad = np.nonzero(~finite | (ratio == 0.0) | (np.sign(ratio) != np.sign(ratio[0])))[0]
            if bad.size:
                what = (
                    "passes its dead centre (ratio 0)"
                    if finite[bad[0]]
                    else "reaches a toggle or cannot be assembled (ratio infinite)"
                )
                raise HydroarmError(
                    f"component.{comps[ci].name}",
                    f"the linkage {what} at {names[root]} = {show(root_grid[bad[0]])}, inside "
                    f"the range {show(lo)} to {show(hi)} it may move in: change its geometry "
                    "or the limits",
                )
            # a rotational slave taken within ±180° of its zero (a four-bar's rocker) turned
            # through that cut: its angle jumps by a turn, far from the motion g'·Δq (by the
            # trapezoid) that a gear's large ratio may give between two points of the grid
            moved = 0.5 * (ratio[1:] + ratio[:-1]) * np.diff(grids[ma])
            jump = np.nonzero(np.abs(np.diff(position) - moved) > math.pi)[0]
            if jump.size and self.mech_domain[names[n]] == declare.ROTATIONAL:
                raise HydroarmError(
                    f"component.{comps[ci].name}",
                    f"the slave {names[n]} passes 180 deg from its zero (its angle would jump "
                    f"by a turn) at {names[root]} = {show(root_grid[jump[0] + 1])}, inside the "
                    f"range {show(lo)} to {show(hi)} it may move in: move the slave's zero "
                    "(a four-bar's output_angle_offset) or the limits",
                )

    def _initial_position(self, node: int) -> float:
        mech = self.mechanism
        if mech is not None and node < mech.n and mech.master[node] != node:
            q = self._initial_position(int(mech.master[node]))
            return float(mech.ratio[node] * q + mech.offset[node])
        name = list(self.mechanical)[node]
        if name in self.circuit.initial_joints:
            return float(self.circuit.initial_joints[name])
        owner = self.inertial.get(node)
        for c in self.circuit.components:
            if c.name == owner:
                for key in ("initial_angle", "initial_position"):
                    if key in c.values:
                        return float(c.values[key])
        return 0.0

    # -------------------------------------------------------------- parameters ---
    def _parameters(self) -> None:
        circuit = self.circuit
        values: list[float] = []
        self.parameter_index: dict[str, int] = {}
        self.values: list[dict[str, float]] = []
        for p in SYSTEM.parameters:
            v = _value(f"system.{p.name}", p, circuit.system.get(p.name, p.default))
            self.parameter_index[f"system.{p.name}"] = len(values)
            values.append(v)
        for key in circuit.system:
            if key not in SYSTEM.parameter_names:
                raise HydroarmError(
                    f"system.{key}", f"unknown key (allowed: {', '.join(SYSTEM.parameter_names)})"
                )
        assert len(values) == N_SYSTEM_PARAMETERS
        self.poff: list[int] = []
        for c, decl in zip(circuit.components, self.decls, strict=True):
            self.poff.append(len(values))
            known = set(decl.parameter_names) | {a.name for a in decl.arrays}
            for key in c.values:
                if key not in known:
                    raise HydroarmError(
                        f"component.{c.name}.{key}",
                        f"unknown parameter of a {c.type} (parameters: {', '.join(sorted(known))})",
                    )
            vals: dict[str, float] = {}
            for p in decl.parameters:
                fld = f"component.{c.name}.{p.name}"
                v = _value(fld, p, c.values.get(p.name, p.default))
                vals[p.name] = v
                self.parameter_index[f"{c.name}.{p.name}"] = len(values)
                values.append(v)
            values.extend(decl.derive(vals))  # the kernel computes them again, once a run
            for a in decl.arrays:
                arr = tuple(c.arrays.get(a.name, ()))
                values.append(float(len(arr)))
                values.extend(float(x) for x in arr)
            self.values.append(vals)
        self.P = np.array(values, np.float64)

    def _states(self) -> None:
        circuit = self.circuit
        nh, nm = len(self.hydraulic), len(self.mechanical)
        s0: list[float] = [circuit.initial_pressure] * nh + [0.0] * (2 * nm)
        self.state_names: list[tuple[str, str]] = []  # (column stem, unit)
        for name in self.hydraulic:
            self.state_names.append((f"{name}.pressure", "Pa"))
        for name in circuit.initial:
            if name not in self.hydraulic:
                raise HydroarmError(
                    f"initial.{name}",
                    "no hydraulic node of that name"
                    + (f" (nodes: {', '.join(self.hydraulic)})" if self.hydraulic else ""),
                )
            s0[self.hydraulic[name]] = circuit.initial[name]
        for name in self.mechanical:
            rot = self.mech_domain[name] == declare.ROTATIONAL
            self.state_names.append(
                (f"{name}.angle" if rot else f"{name}.position", "rad" if rot else "m")
            )
        for name in self.mechanical:
            rot = self.mech_domain[name] == declare.ROTATIONAL
            self.state_names.append(
                (
                    f"{name}.angular_velocity" if rot else f"{name}.velocity",
                    "rad/s" if rot else "m/s",
                )
            )
        mech = self.mechanism
        for name, value in circuit.initial_joints.items():
            if mech is None or name not in mech.joint_names:
                known = ", ".join(mech.joint_names) if mech else "none"
                raise HydroarmError(
                    f"initial.{name}", f"no joint of the mechanism of that name (joints: {known})"
                )
            j = mech.index(name)
            if mech.master[j] != j:
                free = mech.joint_names[mech.master[j]]
                raise HydroarmError(
                    f"initial.{name}",
                    f"the joint follows {free!r} (mechanism.coupling): give {free!r}'s initial "
                    "position instead",
                )
            lo, hi = self.joint_limits[j, 2], self.joint_limits[j, 3]
            if not lo <= value <= hi:
                narrowed = (lo, hi) != (mech.lower[j], mech.upper[j])
                why = "; narrowed by the joints coupled to it" if narrowed else ""
                raise HydroarmError(
                    f"initial.{name}",
                    f"{value:g} is outside the joint's limits [{lo:g}, {hi:g}] (SI: rad or m{why})",
                )
            s0[nh + self.mechanical[name]] = value
        comp_index = {c.name: i for i, c in enumerate(circuit.components)}
        # (state, parameter) pairs: the states whose initial value is a parameter's
        self.initial_from: list[tuple[int, int]] = []
        for i, owner in self.inertial.items():
            vals = self.values[comp_index[owner]]
            for j, key in ((nh + i, "initial_position"), (nh + i, "initial_angle"),
                           (nh + nm + i, "initial_velocity")):  # fmt: skip
                if mech is not None and i < mech.n and mech.master[i] != i:
                    if key in circuit.components[comp_index[owner]].values:
                        free = mech.joint_names[mech.master[i]]
                        raise HydroarmError(
                            f"component.{owner}.{key}",
                            f"its node {mech.joint_names[i]!r} follows {free!r} "
                            f"(mechanism.coupling): give {free!r}'s initial position instead",
                        )
                    continue
                if key in vals:
                    s0[j] = vals[key]
                    self.initial_from.append((j, self.parameter_index[f"{owner}.{key}"]))
        self.soff: list[int] = []
        self.held: list[int] = []  # the held states (`declare.State`)
        for c, decl, vals in zip(circuit.components, self.decls, self.values, strict=True):
            self.soff.append(len(s0))
            for st, n in zip(decl.states, decl.state_count(vals), strict=True):
                init = vals[st.initial] if isinstance(st.initial, str) else st.initial
                for j in range(n):
                    if isinstance(st.initial, str):
                        pi = self.parameter_index[f"{c.name}.{st.initial}"]
                        self.initial_from.append((len(s0), pi))
                    s0.append(init)
                    suffix = f"{j}" if n > 1 else ""
                    self.state_names.append((f"{c.name}.{st.name}{suffix}", st.unit))
                    if st.held:
                        self.held.append(len(s0) - 1)
        self.s0 = self.couple_states(np.array(s0, np.float64))
        self.n_dynamic = len(s0)

    def _orders(self) -> None:
        comps = self.circuit.components
        has_sig = [HAS_SIGNALS[c.type] for c in comps]
        # signal dependencies: a component with signals waits for the writers of its inputs
        deps: dict[int, set[int]] = {}
        index = {c.name: i for i, c in enumerate(comps)}
        for ci, (c, decl) in enumerate(zip(comps, self.decls, strict=True)):
            if not has_sig[ci]:
                continue
            deps[ci] = set()
            for port in decl.ports:
                if port.domain == declare.SIGNAL_IN and port.name in c.ports:
                    writer = self.writers.get(c.ports[port.name])
                    if writer is not None:
                        deps[ci].add(index[writer])
        order: list[int] = []
        state: dict[int, int] = {}

        def visit(i: int, path: list[int]) -> None:
            if state.get(i) == 2:
                return
            if state.get(i) == 1:
                loop = [comps[j].name for j in path[path.index(i) :]] + [comps[i].name]
                raise HydroarmError(
                    f"component.{comps[i].name}",
                    "a loop of signals with no state between them: " + " -> ".join(loop),
                )
            state[i] = 1
            for j in sorted(deps.get(i, ())):
                if j in deps:
                    visit(j, path + [i])
            state[i] = 2
            order.append(i)

        for i in sorted(deps):
            visit(i, [])
        self.sig_order = order
        first = [i for i, d in enumerate(self.decls) if not d.reads_flows]
        self.law_order = first + [i for i, d in enumerate(self.decls) if d.reads_flows]
        self.proj_list = [i for i, c in enumerate(comps) if HAS_PROJECT[c.type]]

    # ---------------------------------------------------------------- outputs ---
    def parameter_vector(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        """P with some parameters (``<component>.<parameter>``) changed, in SI."""
        P = self.P.copy()
        for key, v in (values or {}).items():
            if key not in self.parameter_index:
                raise HydroarmError(key, "no such parameter (see the circuit's parameter names)")
            P[self.parameter_index[key]] = v
        if values:
            self.refresh_derived(P)
        return P

    def refresh_derived(self, P: np.ndarray) -> np.ndarray:
        """P's derived quantities (`Derived`) from its
        parameters, in place (a row, or a table's rows); returned. The kernel computes them
        in its own copy before every run, so a table need not be refreshed to run right;
        this keeps a P built here self-consistent for whoever reads it."""
        for c, decl in enumerate(self.decls):
            if not decl.derived:
                continue
            po = self.poff[c]
            n = len(decl.parameters)
            for row in P.reshape(-1, P.shape[-1]):
                vals = {p.name: float(row[po + i]) for i, p in enumerate(decl.parameters)}
                row[po + n : po + n + len(decl.derived)] = decl.derive(vals)
        return P

    def initial_states(self, table: np.ndarray) -> np.ndarray:
        """The initial state of every row of a parameter table (rows of P): ``s0`` with the
        states that start at a parameter's value (a mass's ``initial_position``, a
        component state's declared initial parameter) taken from the row."""
        S0 = np.repeat(self.s0[None, :], table.shape[0], axis=0)
        for j, pi in self.initial_from:
            S0[:, j] = table[:, pi]
        return self.couple_states(S0)

    def couple_states(self, S: np.ndarray) -> np.ndarray:
        """States (one, or rows) with each coupled joint's position and velocity set from
        its master's, q_s = ratio·q_m + offset, q̇_s = ratio·q̇_m (as the kernel sets them),
        in place; returned."""
        nh, nm = len(self.hydraulic), len(self.mechanical)
        for (sl, ma), (r, o) in zip(self.couplings, self.coupling_laws, strict=True):
            S[..., nh + sl] = r * S[..., nh + ma] + o
            S[..., nh + nm + sl] = r * S[..., nh + nm + ma]
        return S

    @property
    def sweepable(self) -> list[str]:
        """The names of every parameter a sweep, fit or study may vary."""
        out = [f"system.{p.name}" for p in SYSTEM.parameters if p.sweepable]
        for c, decl in zip(self.circuit.components, self.decls, strict=True):
            out += [f"{c.name}.{p.name}" for p in decl.parameters if p.sweepable]
        return out


def _check_types(circuit: Circuit) -> None:
    seen: set[str] = set()
    if not circuit.components and circuit.mechanism is None:
        raise HydroarmError("component", "a circuit needs at least one component")
    for c in circuit.components:
        if not isinstance(c.name, str) or not c.name.isidentifier():
            raise HydroarmError(
                "component.name", f"{c.name!r}: a name is letters, digits and _ (not first)"
            )
        if c.name in seen or c.name == "system":
            raise HydroarmError(f"component.{c.name}.name", "a second component of this name")
        seen.add(c.name)
        if c.type not in TYPES:
            close = difflib.get_close_matches(str(c.type), list(TYPES), n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise HydroarmError(
                f"component.{c.name}.type",
                f"unknown component type {c.type!r}{hint} (known: {', '.join(TYPES)})",
            )
        if len(TYPES[c.type].DECLARATION.ports) > MAX_PORTS:
            raise HydroarmError(f"component.{c.name}", f"more than {MAX_PORTS} ports")


def _value(field_: str, p: declare.Param, v: Any) -> float:
    if v is None:
        raise HydroarmError(field_, "is missing (it has no default)")
    if p.choices:
        if isinstance(v, str):
            if v not in p.choices:
                raise HydroarmError(field_, f"must be one of {', '.join(p.choices)}, got {v!r}")
            return float(p.choices.index(v))
    problem = p.check(v)
    if problem:
        raise HydroarmError(field_, problem)
    return float(v)


# ----------------------------------------------------------------------------- runs ---
def _run_size(circuit: Circuit) -> int:
    if circuit.method not in (*STEPPERS, "adaptive"):
        known = ", ".join((*STEPPERS, "adaptive"))
        raise HydroarmError("solver.method", f"{circuit.method!r}: one of {known}")
    n = int(round(circuit.duration / circuit.step))
    if n < 2:
        raise HydroarmError("solver.duration", "shorter than two steps")
    return n


def build(
    circuit: Circuit, energy: bool = False, energy_reference_pressure: float = 0.0
) -> CompiledCircuit:
    """The circuit compiled and checked (module doc); a reference that asks a position
    outside its actuator's stroke is refused (`reference_problems`).
    ``energy``: with an energy account (`CompiledCircuit`)."""
    compiled = CompiledCircuit(circuit, energy, energy_reference_pressure)
    for field_, problem in reference_problems(compiled):
        raise HydroarmError(field_, problem)
    return compiled


def equilibrium_state(compiled: CompiledCircuit) -> np.ndarray:
    """The static state at t = 0 for the initial pose (every mass or inertia with an
    ``initial_position``/``initial_angle`` given is pinned there; the others settle) and
    the inputs at t = 0 (`steady_state`); a mechanism's joints with
    an ``[initial]`` angle are pinned there too.

    The solve (a settling run: seconds for a mechanism) is kept for the last few compiled
    circuits of the same content (`_content_key`: every array of the kernel's net, the
    parameters, the start state and the pinned pose), so that the steppers an FMU export
    starts for the same file (its checks, its variables, the model description) solve it
    once; a copy is returned."""
    pin = dict(compiled.circuit.initial_joints)
    for c in compiled.circuit.components:
        for key in ("initial_position", "initial_angle"):
            if key in c.values:
                body = c.ports.get("body")
                if body is not None:
                    pin[body] = float(c.values[key])
    digest = _content_key(compiled, pin)
    state = _EQUILIBRIA.get(digest)
    if state is None:
        state = steady_state(compiled, 0.0, pin, field_name="initial.equilibrium").state
        _EQUILIBRIA[digest] = state
        while len(_EQUILIBRIA) > _EQUILIBRIA_KEPT:
            del _EQUILIBRIA[next(iter(_EQUILIBRIA))]
    return state.copy()


_EQUILIBRIA: dict[bytes, np.ndarray] = {}  # content key -> static state (oldest first)
_EQUILIBRIA_KEPT = 8


def _content_key(compiled: CompiledCircuit, pin: dict) -> bytes:
    """A digest of everything the static solve reads: the net's arrays (kinds, ports,
    orders, the mechanism's tree), the parameter vector, the start state, the pose and the
    solver (its settling run steps with the circuit's method, step and duration)."""
    c = compiled.circuit
    h = hashlib.sha256(repr((c.method, c.step, c.duration)).encode())
    for a in (*compiled.net, compiled.P, compiled.s0):
        arr = np.ascontiguousarray(a)
        h.update(f"{arr.dtype.str}{arr.shape}".encode())
        h.update(arr.tobytes())
    h.update(repr(sorted(pin.items())).encode())
    return h.digest()


MAX_EQUILIBRIUM_ROWS = 2000  # rows of a study whose equilibrium starts are solved one by one


def row_initial_states(
    compiled: CompiledCircuit, names: list, values: np.ndarray, table: np.ndarray
) -> np.ndarray:
    """Each row of a study's parameter table started as `simulate` starts the same
    circuit alone: `CompiledCircuit.initial_states`, or with ``equilibrium`` the
    static state solved for each row (``names``/``values``: the varied parameters), at most
    `MAX_EQUILIBRIUM_ROWS` rows."""
    if not compiled.circuit.equilibrium:
        return compiled.initial_states(table)
    n = table.shape[0]
    if n > MAX_EQUILIBRIUM_ROWS:
        raise HydroarmError(
            "initial.equilibrium",
            f"is solved for each row, and the study has {n} rows (at most "
            f"{MAX_EQUILIBRIUM_ROWS}); start from the file's state or run fewer rows",
        )
    out = np.empty((n, compiled.s0.size))
    for r in range(n):
        row = compiled.circuit.with_values({k: float(values[r, i]) for i, k in enumerate(names)})
        out[r] = equilibrium_state(build(row))
    return out


#: the adaptive method's longest step, in the file's fixed steps (the time scale its fastest
#: dynamics are resolved at): Radau's error estimate, damped on the stiff states, misses
#: what the right-hand side's kinks (orifices, openings at their ends) do over a long step
#: (measured against rk4 at a 40th of the step: counterbalance.toml, 0.2 s, 1.5e-4 of a
#: column's range uncapped, 5e-7 capped at 10 steps; hydraulic_leg.toml 2.8e-5 and 1.2e-5;
#: position_servo.toml 3e-8 and 2e-7, each at rk4's own error)
ADAPTIVE_MAX_STEPS = 10


def simulate(circuit: Circuit | CompiledCircuit) -> CircuitResult:
    """Run a circuit from its initial state for its duration (`hydroarm.integrators.system`),
    recording every ``record_every``-th step."""
    compiled = circuit if isinstance(circuit, CompiledCircuit) else build(circuit)
    c = compiled.circuit
    n = _run_size(c)
    s0 = compiled.s0
    if c.equilibrium:
        s0 = s0.copy()
        if compiled.energy_states:  # the static state of the same circuit, at 0 J
            s0[: compiled.n_dynamic] = equilibrium_state(CompiledCircuit(c))
        else:
            s0 = equilibrium_state(compiled)
    if c.method == "adaptive":  # the reference: Radau on the same right-hand side
        t = np.arange(n // c.record_every + 1) * (c.record_every * c.step)
        # per-unit absolute tolerances; steps of at most ADAPTIVE_MAX_STEPS fixed steps
        atol = state_atol([unit for _, unit in compiled.state_names], s0)
        S = integrate_circuit_adaptive(
            s0,
            t,
            compiled.P,
            compiled.net,
            atol=atol,
            max_step=ADAPTIVE_MAX_STEPS * c.step,
            held=compiled.held,
            held_step=c.step,
        )
        return CircuitResult(compiled, t, S, -1, compiled.P)
    code, A, b, cc = stepper(c.method)
    t, S, bad = integrate(
        code, A, b, cc, s0, 0.0, c.step, n, c.record_every, compiled.P, compiled.net
    )
    return CircuitResult(compiled, t, S, int(bad), compiled.P)


def simulate_many(compiled: CompiledCircuit, table: np.ndarray, S0: np.ndarray | None = None):
    """Run every row of a parameter table (rows of P) on the batch engine: (t, states
    (rows × records × states), bad_step per row). Row i equals `simulate` of that P."""
    c = compiled.circuit
    n = _run_size(c)
    if c.method == "adaptive":
        raise HydroarmError("solver.method", "the batch engine runs fixed-step methods only")
    code, A, b, cc = stepper(c.method)
    if S0 is None:
        S0 = np.repeat(compiled.s0[None, :], table.shape[0], axis=0)
    return run_many(code, A, b, cc, S0, 0.0, c.step, n, c.record_every, table, compiled.net)


def column_unit(unit: str) -> tuple[str, float]:
    """(suffix, factor) of a SI unit in column names (pressures in bar, angles in degrees)."""
    if unit == "Pa":
        return "bar", 1e-5
    if unit == "rad":
        return "deg", 180.0 / math.pi
    if unit in ("", "*"):
        return "", 1.0
    if unit in ("m/s", "rad/s"):
        return unit.replace("/", "_"), 1.0
    text = unit.replace("**0.5", "_sqrt").replace("**", "").replace("*", "_")
    return text.replace("/", "_per_").replace(".", "p").lower(), 1.0  # as _pa, _n, _j


#: `output_sources` of each compiled circuit, made once (a stepper reads its outputs every
#: frame of a live page: 0.5 ms a call made anew for the arm's mechanism)
_SOURCES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def output_sources(compiled: CompiledCircuit) -> dict[str, tuple[int, int, int, float, str, str]]:
    """Every output of a circuit by name (`CircuitResult.columns` but ``t_s``): what
    the kernel quantity it reads is (`SOURCE_STATE`
    …), its indices (i, k), the factor to its display unit, its unit as its name ends and
    in pint's syntax. The one definition of the outputs: the recorded columns and the
    observers (`observe_many`) read it. (Made once per compiled circuit, whose structure
    does not change; a copy is returned.)"""
    known = _SOURCES.get(compiled)
    if known is None:
        known = _SOURCES[compiled] = _output_sources(compiled)
    return dict(known)


def _output_sources(compiled: CompiledCircuit) -> dict[str, tuple[int, int, int, float, str, str]]:
    cc = compiled
    out: dict[str, tuple[int, int, int, float, str, str]] = {}
    for j, (stem, unit) in enumerate(cc.state_names):
        suffix, f = column_unit(unit)
        name = stem.replace(".", "_") + (f"_{suffix}" if suffix else "")
        shown = {"Pa": "bar", "rad": "deg", "*": ""}.get(unit, unit)
        out[name] = (SOURCE_STATE, j, 0, f, suffix, shown)
    for name, i in cc.signals.items():
        out[f"{name}_signal"] = (SOURCE_SIGNAL, i, 0, 1.0, "", "")
    mechanism = cc.mechanism
    if mechanism is not None:  # each joint's torque (force) from the components on it
        for j, (name, kind) in enumerate(
            zip(mechanism.joint_names, mechanism.joint_types, strict=True)
        ):
            if kind == "prismatic":
                out[f"{name}_force_n"] = (SOURCE_MECHANICAL, j, 0, 1.0, "n", "N")
            else:
                out[f"{name}_torque_n_m"] = (SOURCE_MECHANICAL, j, 0, 1.0, "n_m", "N*m")
    nm = len(cc.mechanical)
    for k, (_, _, ci) in enumerate(cc.slaves):
        name = cc.circuit.components[ci].name
        out[f"{name}_ratio"] = (SOURCE_MECHANICAL, nm + k, 0, 1.0, "", "")
    for ci, (c, decl) in enumerate(zip(cc.circuit.components, cc.decls, strict=True)):
        hyd = [k for k, p in enumerate(decl.ports) if p.domain == declare.HYDRAULIC]
        if decl.flow_port:
            k = decl.port_names.index(decl.flow_port)
            out[f"{c.name}_flow_lpm"] = (SOURCE_FLOW, ci, k, 6.0e4, "lpm", "L/min")
        if len(hyd) > 2:
            for k in hyd:
                name = f"{c.name}_{decl.ports[k].name}_flow_lpm"
                out[name] = (SOURCE_FLOW, ci, k, 6.0e4, "lpm", "L/min")
        for k, p in enumerate(decl.ports):
            if p.domain in (declare.TRANSLATIONAL, declare.ROTATIONAL) and p.drives:
                rot = p.domain == declare.ROTATIONAL
                name = f"{c.name}_{'torque_n_m' if rot else 'force_n'}"
                units = ("n_m", "N*m") if rot else ("n", "N")
                out[name] = (SOURCE_FLOW, ci, k, 1.0, *units)
        out[f"{c.name}_power_w"] = (SOURCE_POWER, ci, 0, 1.0, "w", "W")
    return out


#: rows × metrics of one observed batch (their values, 8 bytes each: 160 MB; a running row
#: holds its metrics' accumulators, `BYTES_PER_METRIC`)
MAX_OBSERVED = 2 * 10**7


def observe_many(
    compiled: CompiledCircuit,
    table: np.ndarray,
    S0: np.ndarray,
    metrics: list[tuple[str, str, float, float]],
    every: int = 1,
):
    """Every row of a parameter table (rows of P, initial states S0) run on the observer
    loop (`hydroarm.integrators.observers`) for the circuit's duration, measuring each
    metric (output, statistic, after, before) at every ``every``-th step and the start (1:
    every step; the circuit's ``record_every``: the samples `simulate_many` records, the
    statistics those of its traces): (values (rows × metrics), bad_step per row). Row i's
    values equal those of the same row run alone, bit for bit; the memory a row holds does
    not grow with the steps. The statistics are `ONLINE_STATISTICS`."""
    values, bad, _, _ = probe_many(compiled, table, S0, metrics, every)
    return values, bad


def probe_many(
    compiled: CompiledCircuit,
    table: np.ndarray,
    S0: np.ndarray,
    metrics: list[tuple[str, str, float, float]],
    every: int = 1,
    probes: tuple[str, ...] = (),
):
    """`observe_many`, the outputs ``probes`` kept at every sample besides: (values, bad
    step per row, t (samples), traces (rows × samples × probes)). The samples are the start
    and every ``every``-th step, those `simulate_many` records at ``record_every = every``:
    a probe's trace is that output's recorded column, bit for bit (the trace a statistic of
    a trace only, `TRACE_ONLY`, is read from), and a row holds those probes' samples, not
    its states. A failed row's trace is NaN from its bad step."""
    c = compiled.circuit
    n = _run_size(c)
    if c.method == "adaptive":
        raise HydroarmError("solver.method", "the observers run fixed-step methods only")
    if isinstance(every, bool) or not isinstance(every, int | np.integer) or every < 1:
        raise HydroarmError("every", f"must be a whole number of steps >= 1, got {every!r}")
    if table.shape[0] * len(metrics) > MAX_OBSERVED:
        raise HydroarmError(
            "metrics",
            f"{table.shape[0]} rows × {len(metrics)} metrics are above the budget of "
            f"{MAX_OBSERVED} observed values",
        )
    known = output_sources(compiled)
    names = list(dict.fromkeys([*(m[0] for m in metrics), *probes]))
    for o in probes:
        if o not in known:
            raise HydroarmError("output", f"{o!r}: no such output")
    for o, stat, *_ in metrics:
        if o not in known:
            raise HydroarmError("output", f"{o!r}: no such output")
        if stat not in ONLINE_STATISTICS:
            raise HydroarmError("statistic", f"{stat!r}: no observer (one of the traces')")
    sources = np.array([known[o][:3] for o in names], np.int64).reshape(-1, 3)
    factors = np.array([known[o][3] for o in names], float)
    spec = np.array([(names.index(o), ONLINE_STATISTICS[st]) for o, st, *_ in metrics], np.int64)
    windows = np.array([(a, b, 0.0, 0.0) for *_, a, b in metrics], float).reshape(-1, 4)
    code, A, b, cc = stepper(c.method)
    samples = n // int(every) + 1
    t = 0.0 + (np.arange(samples) * int(every)) * c.step  # run_many's record times
    traces = np.full((table.shape[0], samples, len(probes)), np.nan)
    probe = np.array([names.index(o) for o in probes], np.int64)
    values, bad = run_observers(
        code, A, b, cc, S0, 0.0, c.step, n, table, compiled.net, sources,
        factors, spec.reshape(-1, 2), windows, int(every), probe, traces,
    )  # fmt: skip
    return values, bad, t, traces


class CircuitResult(Summarised):
    """A circuit's run: times ``t`` [s], states (records × states), the first non-finite
    step ``bad_step`` (−1: none); outputs by name through `to_pandas`, `output`,
    `energy` and `plot`."""

    def _summary(self) -> list[tuple[str, str]]:
        c = self.compiled.circuit
        return [
            ("circuit", c.name),
            ("run", span(self.t)),
            ("components", str(len(c.components))),
            ("columns", str(len(self.columns()) - 1)),
        ]

    def _trace_columns(self):
        return {k: v for k, v in self.columns().items() if k != "t_s"}, {}

    def __init__(self, compiled: CompiledCircuit, t, states, bad_step: int, P) -> None:
        self.compiled = compiled
        self.t = np.asarray(t)
        self.states = np.asarray(states)
        self.bad_step = bad_step
        self.P = P

    @cached_property
    def _quantities(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(flows (records × components × ports), power (records × components), signals,
        node pressures as the components see them) at every record."""
        cc = self.compiled
        nrec = len(self.t)
        nc = len(cc.circuit.components)
        flows = np.zeros((nrec, nc, MAX_PORTS))
        power = np.zeros((nrec, nc))
        sigs = np.zeros((nrec, max(len(cc.signals), 1)))
        mech = np.zeros((nrec, len(cc.mechanical) + len(cc.slaves) + 1))
        record_outputs(self.t, self.states, self.P, cc.net, flows, power, sigs, mech)
        return flows, power, sigs, mech

    def columns(self, names: list[str] | None = None) -> dict[str, np.ndarray]:
        """Every output by name (module doc), in display units (bar, L/min, degrees); only
        those of ``names`` (known outputs, ``t_s`` not among them) when given (a stepper
        reading a few each frame)."""
        if names is None:
            return {k: v for k, (v, _, _) in self._columns.items()}
        sources = output_sources(self.compiled)
        return {n: self._column(*sources[n][:4]) for n in names}

    def units(self) -> dict[str, str]:
        """Every output's unit as its name ends (``bar``, ``lpm``, ``m_s``; ``""``: none)."""
        return {k: u for k, (_, u, _) in self._columns.items()}

    def display_units(self) -> dict[str, str]:
        """Every output's unit in pint's syntax, the unit its values are in (``bar``,
        ``L/min``, ``deg``, ``m/s``, ``m**3/s``; ``""``: a signal, any unit or none)."""
        return {k: u for k, (_, _, u) in self._columns.items()}

    def _column(self, what: int, i: int, k: int, f: float) -> np.ndarray:
        """One output's column from its source (`output_sources`)."""
        if what == SOURCE_STATE:
            return self.states[:, i] * f
        flows, power, sigs, mech = self._quantities
        if what == SOURCE_SIGNAL:
            return sigs[:, i]
        if what == SOURCE_MECHANICAL:
            return mech[:, i]
        if what == SOURCE_FLOW:
            return flows[:, i, k] * f if f != 1.0 else flows[:, i, k]
        return power[:, i]

    @cached_property
    def _columns(self) -> dict[str, tuple[np.ndarray, str, str]]:
        out: dict[str, tuple[np.ndarray, str, str]] = {"t_s": (self.t, "s", "s")}
        for name, (what, i, k, f, suffix, shown) in output_sources(self.compiled).items():
            out[name] = (self._column(what, i, k, f), suffix, shown)
        return out

    def output(self, name: str) -> np.ndarray:
        """One output column by its name (``supply_pressure_bar``, ``cv1_flow_lpm``)."""
        cols = self.columns()
        if name not in cols:
            close = difflib.get_close_matches(name, list(cols), n=3)
            raise HydroarmError(
                "output",
                f"{name!r}: no such output"
                + (f" (did you mean {', '.join(close)}?)" if close else ""),
            )
        return cols[name]

    def to_pandas(self):
        """The outputs as a DataFrame indexed by nothing, one column an output."""
        import pandas as pd

        return pd.DataFrame(self.columns())

    def to_csv(self, path) -> None:
        """Write the outputs as CSV (atomically)."""
        atomic_write_text(path, self.to_pandas().to_csv(index=False, float_format="%.10g"))

    def energy(self) -> dict[str, float]:
        """Energy each component absorbed over the run, ``<component>_energy_j`` [J]
        (`component_energies` with the unit in each name; a mechanism's as
        ``mechanism_energy_j``), and ``closure_energy_j``, their sum."""
        return {f"{k}_energy_j": v for k, v in self.component_energies().items()}

    def component_energies(self) -> dict[str, float]:
        """Energy [J] each component absorbed over the run, keyed by its name (∫ power dt,
        trapezoid over the records; negative: delivered), and ``closure``: their sum, which
        is zero up to the records' trapezoid error and round-off (the power sums to zero at
        every record)."""
        _, power, _, mech = self._quantities
        names = [c.name for c in self.compiled.circuit.components]
        if self.compiled.mechanism is not None:  # its kinetic, potential, damping energy
            names.append("mechanism")
            power = np.column_stack([power, mech[:, -1]])
        e = np.trapezoid(power, self.t, axis=0) if len(self.t) > 1 else np.zeros(len(names))
        out = {n: float(v) for n, v in zip(names, e, strict=True)}
        out["closure"] = float(np.sum(e))
        return out

    def energies(self) -> dict[str, float]:
        """The run's energy account [J]: what each component absorbed, term by term
        (``<component>.<term>``: its declared `Energy`
        terms, or ``<component>.energy``; ``mechanism.energy``), integrated by the run's own
        method as states (a circuit built with ``energy=True``), and ``balance``: their
        sum, zero up to round-off and a node held at the cavitation floor (Σ_c P_c = 0 at
        every evaluation; the projections move no energy state). Negative: delivered."""
        cc = self.compiled
        if not cc.energy_states:
            raise HydroarmError(
                "energy", "the circuit was built without an energy account (energy=True)"
            )
        out = {
            k: float(self.states[-1, j] - self.states[0, j]) for k, j in cc.energy_states.items()
        }
        out["balance"] = math.fsum(out.values())
        return out

    def plot(self, outputs: list[str] | None = None, ax=None):
        """A figure of chosen outputs (default: every node pressure and mechanical position)
        against time (`hydroarm.plotting.circuit.plot_outputs`)."""
        cols = self.columns()
        if outputs is None:
            outputs = [
                k for k in cols if k.endswith(("_pressure_bar", "_position_m", "_angle_deg"))
            ]
        for name in outputs:
            if name not in cols:
                self.output(name)  # the error with suggestions
        return plot_outputs(
            cols["t_s"], {k: cols[k] for k in outputs}, self.compiled.circuit.name, ax=ax
        )
