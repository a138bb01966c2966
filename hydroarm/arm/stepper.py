"""The whole arm advanced piece by piece, its four levers set between the pieces.

`ArmStepper` is the arm's run for a caller that owns the clock (a co-simulation master, the
arm FMU; a live application, the explorer's arm page). It steps what the system kernel steps
(issue 28: one physics): the arm written as one mechanism (`hydroarm.arm.expand.arm_circuit`:
the coupled tree dynamics, each joint's circuit, the power pack as pump, relief valve and
volume) through a `hydroarm.model.circuit_stepper.CircuitStepper`, whose whole fixed steps are
those of ``simulate(build(arm_circuit(sc)))``. Time as every stepper's (`StepClock`): whole
steps t = k·h, the part of a step left over carried to the next call.

Inputs: each joint's lever [m] (jack coordinates; on the circuit the input ``value`` of the
joint's lever source, ``<joint>_lever`` or, for a joint built from components,
``<joint>_reference``). Until a lever is set, the arm file's lever input runs (its steps or
table against time, as in the whole run); once set, a lever is held over every step until set
again (zero-order hold; set before the first step, it acts from the start). So the file's
levers stepped in any pieces, or levers set once at the start and held, give the whole run's
trajectory bit for bit. A lever changed between two steps is a file's step at that instant
to the last bit with Euler, but for one recorded state: the kernel's projection after a step
reads the signals at the step's end, where a file's step has already changed and a held lever
has not, and the algebraic spool of a joint built from components records its demand there
(recorded, not integrated: the trajectory is the same). RK4 reads the levers at its stages
inside the step too, so a lever held over a step differs there from a file's lever that
moves within it. The hand's payload
(`ArmStepper.hand_mass`) swaps the mechanism's tree the kernel takes (no kernel compiled
again); a contact stops joints (`ArmStepper.stop_joints`).

Outputs are the arm's, read from the circuit's outputs as
`hydroarm.arm.expand.simulate_arm` reads them: each joint's servo angle (its mechanism
angle less its ``angle_offset``), rate, load pressure, and the supply's gauge pressure, with
the jack's rod, torque and flows (`JOINT_OUTPUTS`, `ARM_OUTPUTS`); the levers are
`ArmStepper.levers`.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import HydroarmError
from ..integrators import registry
from ..model.circuit import build
from ..model.circuit_stepper import TREE_SLICE, CircuitStepper
from ..model.stepper import StepClock
from ..model.stepper import finite as _finite
from .expand import arm_circuit
from .model import ArmScenario

# per-joint outputs of ArmStepper.outputs(): name, unit, meaning
JOINT_OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("angle", "rad", "articulation angle (servo angle + offset)"),
    ("theta", "rad", "servo angle θ₂"),
    ("omega", "rad/s", "angular velocity"),
    ("x", "m", "jack (actuator) rod position"),
    ("x_dot", "m/s", "jack (actuator) rod velocity"),
    (
        "p",
        "Pa",
        "load pressure (a component joint: force-equivalent A_A·p_A − A_B·p_B over A_A, of "
        "the chambers' absolute pressures)",
    ),
    ("torque", "N.m", "actuator torque at the joint"),
    ("supply_flow", "m3/s", "flow the joint's valve draws from the supply"),
)
# outputs of the whole arm
ARM_OUTPUTS: tuple[tuple[str, str, str], ...] = (
    ("supply_pressure", "Pa", "supply gauge pressure (the shared power pack's)"),
    ("valve_flow", "m3/s", "flow the valves draw from the supply, all joints"),
    ("pump_flow", "m3/s", "flow the pump delivers (the rest goes over the relief valve)"),
)
#: the first number of `ArmStepper.get_state`: the layout (the arm's own kernel's states,
#: before issue 28, began with the step count, never negative)
STATE_LAYOUT = -28.0
_HEAD = 4  # get_state's leading numbers: layout, steps, requested, failed
_CIRCUIT_HEAD = 4  # CircuitStepper.get_state's: t0, steps, requested, failed
_LPM = 6.0e4  # L/min per m³/s (the circuit's flow columns)
_BAR = 1.0e5  # Pa per bar (its pressure columns)


class ArmStepper(StepClock):
    """The whole arm of an `ArmScenario` advanced in fixed steps of the system kernel from
    its start, its levers set between calls (module doc).

    Parameters
    ----------
    sc : the arm (joints, geometry, power pack, initial angles; its lever inputs run until
        the levers are set)
    method, step : the fixed-step method (``"euler"``, ``"rk4"``) and step h [s] (default:
        the scenario's)
    """

    def __init__(self, sc: ArmScenario, *, method: str | None = None, step: float | None = None):
        method = sc.method if method is None else method
        if method not in registry.fixed_step_methods():
            raise HydroarmError(
                "solver.method",
                f"must be {' or '.join(registry.fixed_step_methods())}, got {method!r}",
            )
        h = sc.step if step is None else _finite("solver.step", step)
        if not h > 0:
            raise HydroarmError("solver.step", f"must be a positive time, got {step!r}")
        sc = sc.replace(method=method, step=h)
        self.scenario = sc
        self.method = method
        self.step = h
        self.names = [j.name for j in sc.joints]
        circuit = arm_circuit(sc)
        #: the arm's circuit stepped on the system kernel
        self.circuit = CircuitStepper(build(circuit), method=method, step=h)
        compiled = self.circuit.compiled
        mech = compiled.mechanism
        assert mech is not None
        # each joint's mechanical node: a tree joint's, or a joint on a test bench (a fixed
        # load, off the tree: `arm_circuit`) its load's node
        tree_nodes = np.asarray(compiled.net[21])
        comp = {c.name: i for i, c in enumerate(circuit.components)}
        self._tree = {
            j: mech.joint_names.index(aj.name)
            for j, aj in enumerate(sc.joints)
            if aj.fixed_load is None
        }
        self._nodes = np.array(
            [
                int(tree_nodes[self._tree[j]])
                if j in self._tree
                else int(compiled.ports[comp[f"{aj.name}_load"], 0])
                for j, aj in enumerate(sc.joints)
            ]
        )
        self._offsets = np.array([float(j.angle_offset) for j in sc.joints])
        self._component = [j.component is not None for j in sc.joints]
        # each lever's input; the component joints' piston areas (their load pressure)
        self._lever_inputs = [
            f"{n}_reference.value" if comp else f"{n}_lever.value"
            for n, comp in zip(self.names, self._component, strict=True)
        ]
        specs = {c.name: c.values for c in circuit.components}
        self._areas = {
            n: (float(specs[f"{n}_actuator"]["area_a"]), float(specs[f"{n}_actuator"]["area_b"]))
            for n, comp in zip(self.names, self._component, strict=True)
            if comp
        }
        self._p_atm = float(circuit.initial_pressure)
        self._unlimited = math.isinf(sc.power_pack.pump_flow)
        self._hand_mass = float(sc.geometry.hand_mass)
        # the circuit's outputs that outputs() reads (`CircuitStepper.outputs`' names)
        wanted = ["supply_pressure_bar"] + ([] if self._unlimited else ["pump_flow_lpm"])
        known = set(self.circuit.output_units())
        # each joint's actuator torque: a tree joint's (the linkage's torque on it, friction
        # aside: the projection's); a bench joint's, off the tree, the same torque read from
        # its jack (a paper joint) or its actuator's force through the crank's moment arm
        self._torque: dict[str, tuple[str, ...]] = {}
        for j, n in enumerate(self.names):
            if j in self._tree:
                self._torque[n] = (f"{n}_torque_n_m",)
            elif f"{n}_jack_torque_n_m" in known:
                self._torque[n] = (f"{n}_jack_torque_n_m",)
            else:
                self._torque[n] = (f"{n}_crank_ratio", f"{n}_actuator_force_n")
        for n in self.names:
            wanted += [f"{n}_rod_position_m", f"{n}_rod_velocity_m_s", *self._torque[n]]
            if n in self._areas:
                wanted += [f"{n}_A_pressure_bar", f"{n}_B_pressure_bar", f"{n}_valve_flow_lpm"]
            else:
                wanted += [f"{n}_jack_load_pressure_bar", f"{n}_jack_flow_lpm"]
        self._wanted = wanted

    def _c(self) -> CircuitStepper:
        """The circuit's stepper, its step count this stepper's (the one clock)."""
        self.circuit._k = self._k
        return self.circuit

    # inputs ----------------------------------------------------------------------------
    @property
    def levers(self) -> dict[str, float]:
        """Lever positions [m] (jack coordinates) by joint name now: the one set, held until
        set again, else the file's lever at the current time. Assigning a dictionary sets the
        joints it names (a copy is returned: set through assignment or `set_lever`)."""
        c = self.circuit
        signals = None if set(self._lever_inputs) <= c._driven else self._c().outputs()
        out = {}
        for n, i in zip(self.names, self._lever_inputs, strict=True):
            if signals is None or i in c._driven:
                out[n] = float(c.P[c.inputs[i].index])
            else:  # the file's lever source at the current time
                out[n] = signals[f"{i.partition('.')[0]}_signal"]
        return out

    @levers.setter
    def levers(self, values: dict) -> None:
        new = {}
        for n, y in dict(values).items():
            if n not in self.names:
                raise HydroarmError(
                    "levers", f"no joint {n!r} in this arm ({', '.join(self.names)})"
                )
            new[n] = _finite(f"levers.{n}", y)
        c = self._c()
        for n, y in new.items():
            c.set_input(self._lever_inputs[self.names.index(n)], y)

    def set_lever(self, name: str, y: float) -> None:
        """Set joint ``name``'s lever position y [m]."""
        self.levers = {name: y}

    def lever_for_angle(self, name: str, angle: float) -> float:
        """The lever position [m] that holds joint ``name`` at articulation angle ``angle``
        [rad] (as an arm file's inputs in degrees are read)."""
        return float(self.scenario.joint(name).lever_for_angle(angle))

    @property
    def hand_mass(self) -> float:
        """The payload at the hand point [kg] (`ArmGeometry.hand_mass`, the scenario's at the
        start). Assigning it swaps the mechanism's tree the kernel takes (the arm's mechanism
        with that hand mass: its masses, centres of mass and inertias) from the next step on,
        the kernel not compiled again. It is a parameter, not part of `get_state`."""
        return self._hand_mass

    @hand_mass.setter
    def hand_mass(self, mass: float) -> None:
        m = _finite("arm.hand_mass", mass)
        if m < 0:
            raise HydroarmError("arm.hand_mass", f"must not be negative, got {mass!r}")
        if m == self._hand_mass:
            return
        sc = self.scenario
        mech = arm_circuit(sc.replace(geometry=sc.geometry.replace(hand_mass=m))).mechanism
        assert mech is not None
        c = self.circuit
        net = list(c.net)
        net[TREE_SLICE] = list(mech.compile().tree)
        c.net = tuple(net)
        self._hand_mass = m

    def servo_angles(self) -> np.ndarray:
        """The joints' servo angles θ [rad] now (articulation angle = θ + offset)."""
        q, _ = self._positions()
        return q - self._offsets

    def _positions(self) -> tuple[np.ndarray, np.ndarray]:
        """The joints' articulation angles [rad] and rates [rad/s] now, in the arm's order
        (a bench joint's: its load's node)."""
        c = self.circuit
        nh, nm = int(c.net[9][0]), int(c.net[9][1])
        return c._s[nh + self._nodes].copy(), c._s[nh + nm + self._nodes].copy()

    def stop_joints(self, theta, joints) -> None:
        """Stop the joints ``joints`` (indices) at servo angles ``theta[j]`` [rad] at rest:
        their angle set, their angular velocity zero, their pressures and every other state
        kept (`CircuitStepper.stop_joints`); an inelastic stop at a contact, applied between
        calls."""
        at = {}
        c = self.circuit
        nh, nm = int(c.net[9][0]), int(c.net[9][1])
        for j in joints:
            a = _finite(f"theta.{self.names[j]}", theta[j]) + float(self._offsets[j])
            if j in self._tree:
                at[self._tree[j]] = a
            else:  # on a bench: its load's node
                node = int(self._nodes[j])
                c._s[nh + node], c._s[nh + nm + node] = a, 0.0
        c.stop_joints(at)

    # time ------------------------------------------------------------------------------
    def _steps(self, n: int) -> tuple[int, bool]:
        return self._c()._steps(n)

    def _failure(self) -> str:
        return (
            f"the run left the physical bounds at t = {self.t:.6g} s (a state not finite): "
            f"reduce the step ({self.step:g} s)"
        )

    # outputs ---------------------------------------------------------------------------
    def outputs(self) -> dict:
        """``{joint name: {output: value}}`` (`JOINT_OUTPUTS`) and the arm's
        `ARM_OUTPUTS` at the top level; SI floats, read from the circuit's outputs
        (`CircuitStepper.outputs`) as `hydroarm.arm.expand.simulate_arm` reads them."""
        c = self._c()
        o = c.outputs(self._wanted)
        q, qd = self._positions()
        out: dict = {}
        for j, n in enumerate(self.names):
            angle = float(q[j])
            if n in self._areas:
                a_a, a_b = self._areas[n]
                p_a, p_b = o[f"{n}_A_pressure_bar"] * _BAR, o[f"{n}_B_pressure_bar"] * _BAR
                p = (a_a * p_a - a_b * p_b) / a_a
                flow = o[f"{n}_valve_flow_lpm"]
            else:
                p = o[f"{n}_jack_load_pressure_bar"] * _BAR
                flow = o[f"{n}_jack_flow_lpm"]
            out[n] = {
                "angle": angle,
                "theta": angle - float(self._offsets[j]),
                "omega": float(qd[j]),
                "x": o[f"{n}_rod_position_m"],
                "x_dot": o[f"{n}_rod_velocity_m_s"],
                "p": float(p),
                "torque": float(np.prod([o[k] for k in self._torque[n]])),
                "supply_flow": flow / _LPM,
            }
        qv = sum(out[n]["supply_flow"] for n in self.names)
        out["supply_pressure"] = o["supply_pressure_bar"] * _BAR - self._p_atm
        out["valve_flow"] = qv
        out["pump_flow"] = max(qv, 0.0) if self._unlimited else o["pump_flow_lpm"] / _LPM
        return out

    # state -----------------------------------------------------------------------------
    def get_state(self) -> np.ndarray:
        """The complete state as one float array: the layout (`STATE_LAYOUT`), step count,
        requested time, failed flag, then the circuit's state vector, its parameter vector
        (the levers held in it) and which of its inputs are set
        (`CircuitStepper.get_state` after its head). `set_state` restores it exactly."""
        head = [STATE_LAYOUT, float(self._k), self._requested, float(self._failed)]
        return np.concatenate([head, self.circuit.get_state()[_CIRCUIT_HEAD:]])

    @property
    def state_size(self) -> int:
        """The length of `get_state`'s array."""
        c = self.circuit
        return _HEAD + c._s.size + c.P.size + len(c.inputs)

    def set_state(self, s) -> None:
        """Restore a state from `get_state` (of a stepper of the same arm); a state of
        another layout (the arm's own kernel's, before issue 28) or length is refused."""
        s = np.asarray(s, dtype=float)
        if s.shape != (self.state_size,) or s[0] != STATE_LAYOUT:
            raise HydroarmError(
                "state",
                f"must be {self.state_size} numbers beginning {STATE_LAYOUT:g} (a state of "
                f"this arm's stepper on the system kernel), got shape {s.shape}"
                + ("" if s.ndim != 1 or s.size == 0 else f" beginning {s[0]:g}"),
            )
        self.circuit.set_state(np.concatenate([[0.0, s[1], s[2], s[3]], s[_HEAD:]]))
        self._k = int(s[1])
        self._requested = float(s[2])
        self._failed = bool(s[3])
