"""The UCL arm as one mechanism file on the system kernel (issues 28 and 30;
docs/mechanism.md "The UCL arm as a mechanism").

`arm_circuit` writes an arm file's `ArmScenario` as a
`Circuit` with a ``[mechanism]``:

* **the mechanism**: the arm's point masses (upper arm at its centre of mass, forearm at
  its, the hand payload at the hand point; `hydroarm.core.arm_kinematics`) on the
  links of a tree ``base → shoulder → upper_arm → humerus → forearm → hand``, turned by
  ``shoulder_elevation`` (about −y: the arm swings forward from hanging),
  ``shoulder_extension`` (about −y, following ``elbow_reach`` with the ratio −k: the elbow
  block's shoulder over-extension), ``humeral_rotation`` (about the upper arm's axis),
  ``elbow_reach`` (about −y, at the elbow) and ``wrist_rotation`` (about the forearm's axis,
  at the hand point); gravity −z at g₀. A joint the file leaves out is a fixed joint at 0
  (as the arm model holds it). Each joint's limits are its crank's reach (or end stops)
  about its angle datum;
* **each joint's circuit**, the joint's ``own_inertia`` as an ``inertia`` at it: a paper
  joint as `hydroarm.io.joint_circuit`'s ``servo_jack`` and ``crank_linkage`` (the
  joint's piston and gearbox friction), a joint built from components (the elbow's
  single-rod jack) as `hydroarm.io.servo_circuit`'s valve, cylinder, crank (its dry
  friction driven by the cylinder's pressure force) and lever feedback; each crank with the
  joint's ``angle_offset`` (the joint angle is the servo angle plus the offset); each
  joint's lever from ``[inputs]`` as a ``signal_source``; components and nodes named
  ``<joint>_<part>``;
* **a joint on a test bench** (a ``fixed_load``, `hydroarm.Load`: W, X, I; an arm file's
  ``[joints.<name>.load]``): the same circuit driving its own load, an ``inertia`` named
  ``<joint>_load`` on a node ``<joint>`` off the tree (the single joint's load, as
  `hydroarm.io.joint_circuit` writes it: inertia I, gravity torque W·X·cos(θ − θ_h) on the
  servo angle), fed from the shared power pack. The tree holds that articulation as a fixed
  joint at its initial angle (the elbow's with its shoulder over-extension): a joint that
  moved the arm would carry the arm's load. (The decoupled reference,
  `hydroarm.reference.arm_decoupled`, lets the other joints' pose loads follow a bench
  joint's angle with no reaction on it: the arm lifted for nothing, no mechanism's
  physics. The two agree where the bench joint runs alone or holds its angle);
* **the power pack** on the shared nodes ``supply`` and ``T`` (the return, a tank at
  atmospheric pressure): a ``fixed_pump`` at ``pump_flow``, a ``relief_valve`` that passes
  the whole pump flow at ``supply_pressure`` and a ``volume``
  (`SUPPLY_VOLUME`); an ``"unlimited"`` pump flow is a supply held at the pressure.

The start is the arm model's: every joint at rest at its initial angle, each jack's
pressure holding its pose's gravity torque (`hydroarm.arm.model.kernel_inputs`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable

import numpy as np

from ..core.arm_kinematics import JOINT_NAMES
from ..core.params import STANDARD_GRAVITY
from ..core.servo import S_PA, S_PB
from ..errors import HydroarmError
from ..integrators.system import STEPPERS
from ..io.joint_circuit import (
    crank_stop,
    crank_values,
    jack_values,
    load_joint_or_servo_circuit,
)
from ..io.sections import read_toml_file
from ..io.servo_circuit import (
    NAMES,
    actuator_spec,
    crank_spec,
    feedback_specs,
    reference_source,
    valve_spec,
)
from ..model.circuit import (
    Circuit,
    CircuitResult,
    CompiledCircuit,
    ComponentSpec,
    build,
    simulate,
)
from ..model.circuit_stepper import CircuitStepper
from ..model.mechanism import Coupling, Joint, Link, Mechanism, Payload
from .config import load_arm
from .model import ArmJoint, ArmScenario, kernel_inputs
from .result import ArmResult

#: the power pack's oil volume at the supply node [m³]: pump, manifold and lines (an
#: estimate; the paper gives no figure). With the relief's slope it sets the supply's time
#: constant V/(β·k_cs): for examples/ucl-arm.toml (0.6 L/min, β = 3.4e8 Pa) 1.5 ms, far
#: below the joints' (≥ 50 ms), and RK4 at its 1 ms step is stable (β·k_cs/V·h ≈ 0.7,
#: under RK4's 2.78 on the negative real axis)
SUPPLY_VOLUME = 50e-6
#: the pressure [Pa] over which the relief valve goes from closed to passing the whole pump
#: flow (its steady slope k_cs = Q_p/Δp): an estimate for a small direct-acting relief
RELIEF_OVERRIDE = 1.0e5
#: the relief's full opening passes this multiple of the pump flow (its stroke never
#: limits the pump's flow)
RELIEF_OPENING_MARGIN = 2.0
#: the steps of a piece of a run recorded piece by piece (`simulate_arm` with a probe or
#: without the energy account), rounded down to whole records: 20 ms at the validation's
#: 10 µs, some hundred pieces a run (a piece's call costs ~10 µs, its steps ~2 µs each)
PIECE_STEPS = 2000
DOWN = (0.0, 0.0, -1.0)  # along a hanging segment, in its link's frame
FORWARD = (0.0, -1.0, 0.0)  # the flexion axis: a positive angle swings the segment forward
SHARED_NODES = ("supply", "T")


def _held_rpy(axis: tuple[float, float, float], angle: float) -> tuple[float, float, float]:
    """The roll, pitch, yaw [rad] of a fixed joint that holds its child turned by ``angle``
    [rad] about ``axis`` (`FORWARD`: about −y; `DOWN`: about −z)."""
    if axis == FORWARD:
        return (0.0, -angle, 0.0)
    return (0.0, 0.0, -angle)


def _mechanism(sc: ArmScenario, limits: dict[str, tuple[float, float]]) -> Mechanism:
    """The arm's links and joints (module doc); ``limits``: each present joint's range. A
    joint with a fixed load (on a bench: its load is its own ``inertia``, `arm_circuit`)
    is a fixed joint of the tree holding its articulation at its initial angle (the elbow's
    with its shoulder over-extension); a joint the arm leaves out, at 0."""
    g = sc.geometry
    present = {j.name for j in sc.joints if j.fixed_load is None}
    held = {j.name: sc.initial_angles[j.name] for j in sc.joints if j.fixed_load is not None}
    k = g.reach_shoulder_ratio
    if "elbow_reach" in held and k != 0.0:
        held["shoulder_extension"] = -k * held["elbow_reach"]

    def held_joint(name, parent, child, axis, origin=(0.0, 0.0, 0.0)) -> Joint:
        angle = held.get(name, 0.0)
        rpy = _held_rpy(axis, angle) if angle != 0.0 else (0.0, 0.0, 0.0)
        return Joint(name, "fixed", parent, child, axis=axis, origin=origin, rpy=rpy)

    def joint(name, parent, child, axis, origin=(0.0, 0.0, 0.0)) -> Joint:
        if name not in present and name in JOINT_NAMES:
            return held_joint(name, parent, child, axis, origin)
        lo, hi = limits.get(name, (-math.inf, math.inf))
        return Joint(name, "revolute", parent, child, axis=axis, origin=origin, lower=lo, upper=hi)

    reach = "elbow_reach" in present and k != 0.0
    links = (
        Link("base"),
        Link("shoulder"),
        Link("upper_arm", mass=g.upper_arm_mass, com=(0.0, 0.0, -g.upper_arm_com)),
        Link("humerus"),
        Link("forearm", mass=g.forearm_mass, com=(0.0, 0.0, -g.forearm_com)),
        Link("hand"),
    )
    extension = joint("shoulder_extension", "shoulder", "upper_arm", FORWARD)
    if not reach:
        extension = held_joint("shoulder_extension", "shoulder", "upper_arm", FORWARD)
    joints = (
        joint("shoulder_elevation", "base", "shoulder", FORWARD),
        extension,
        joint("humeral_rotation", "upper_arm", "humerus", DOWN),
        joint("elbow_reach", "humerus", "forearm", FORWARD, (0.0, 0.0, -g.upper_arm_length)),
        joint(
            "wrist_rotation",
            "forearm",
            "hand",
            DOWN,
            (0.0, 0.0, -(g.forearm_length + g.hand_length)),
        ),
    )
    payloads: tuple[Payload, ...] = ()
    if g.hand_mass > 0.0:
        payloads = (Payload("hand_payload", "hand", g.hand_mass),)
    elif "wrist_rotation" in present:
        raise HydroarmError(
            "arm.hand_mass",
            "must be positive for the mechanism: the wrist rotation turns the hand alone",
        )
    couplings: tuple[Coupling, ...] = ()
    if reach:
        couplings = (Coupling("shoulder_extension", "elbow_reach", -g.reach_shoulder_ratio),)
    return Mechanism(
        links=links,
        joints=joints,
        gravity=(0.0, 0.0, -STANDARD_GRAVITY),
        payloads=payloads,
        name=sc.name,
        couplings=couplings,
    )


def _renamed(specs: Iterable[ComponentSpec], joint: str) -> list[ComponentSpec]:
    """Components of one joint's circuit, each and each of their nodes and signals named
    ``<joint>_<name>``, but the joint's node (``joint``: the mechanism's joint) and the
    power pack's shared nodes."""

    def node(n: str) -> str:
        if n == "joint":
            return joint
        return n if n in SHARED_NODES else f"{joint}_{n}"

    return [
        dataclasses.replace(
            c, name=f"{joint}_{c.name}", ports={k: node(v) for k, v in c.ports.items()}
        )
        for c in specs
    ]


def _paper_joint(aj: ArmJoint, sc: ArmScenario, start_pressure: float) -> list[ComponentSpec]:
    """A paper joint's jack and crank (`hydroarm.io.joint_circuit`) and its lever."""
    servo = aj.servo.replace(supply_pressure=sc.power_pack.supply_pressure)
    crank = crank_values(servo)
    if aj.angle_offset != 0.0:
        crank["angle_offset"] = aj.angle_offset
    jack_ports = {"P": "supply", "T": "T", "rod": "rod", "lever": "lever", "force": "jack_force"}
    crank_ports = {"joint": "joint", "rod": "rod", "drive_force": "jack_force"}
    return [
        ComponentSpec("servo_jack", "jack", jack_ports, jack_values(servo, start_pressure)),
        ComponentSpec("crank_linkage", "crank", crank_ports, crank),
        reference_source(sc.inputs[aj.name], "lever"),
    ]


def _component_joint(aj: ArmJoint, sc: ArmScenario) -> list[ComponentSpec]:
    """A joint built from components (`hydroarm.io.servo_circuit`): valve, cylinder,
    crank with its dry friction, the lever feedback (the arm's component parameter vector,
    `component_vector`)."""
    P = dict(zip(NAMES, aj.component_vector(sc.power_pack.supply_pressure, None), strict=True))
    return [
        valve_spec(P, {}),
        actuator_spec(P),
        crank_spec(P, aj.angle_offset),
        *feedback_specs(P),
        reference_source(sc.inputs[aj.name]),
    ]


def _bench_load(aj: ArmJoint, angle: float, limits: tuple[float, float]) -> ComponentSpec:
    """The ``inertia`` named ``load`` on the node ``joint`` of a joint with a fixed load
    (`hydroarm.Load`: W, X, I), the single joint's load (`hydroarm.io.joint_circuit`'s,
    the component servo's crank load): inertia I, gravity torque W·X·cos(θ − θ_h) on the
    servo angle θ (the node's angle less the offset), the joint's range ``limits`` [rad]
    and its initial articulation ``angle`` [rad]. The load is the joint's whole load, as in
    the single-joint model: its ``own_inertia`` (an addition to a pose's) is not added."""
    load = aj.fixed_load
    assert load is not None
    values = {
        "inertia": load.inertia,
        "gravity_moment": load.weight * load.arm,
        "gravity_angle": aj.servo.horizontal_angle + aj.angle_offset,
        "angle_min": limits[0],
        "angle_max": limits[1],
        "initial_angle": angle,
    }
    return ComponentSpec("inertia", "load", {"body": "joint"}, values)


def _power_pack(sc: ArmScenario, p_atm: float, bulk_modulus: float) -> list[ComponentSpec]:
    """The power pack on the nodes ``supply`` and ``T`` (module doc)."""
    pack = sc.power_pack
    tank = ComponentSpec("tank", "tank", {"port": "T"}, {"pressure": p_atm})
    p_supply = p_atm + pack.supply_pressure
    if math.isinf(pack.pump_flow):
        return [tank, ComponentSpec("tank", "source", {"port": "supply"}, {"pressure": p_supply})]
    q = pack.pump_flow
    pump = {"displacement": q, "speed": 1.0}  # [m³/rad] at 1 rad/s: the pump flow
    relief = {
        # the whole pump flow passes at the supply pressure: open from RELIEF_OVERRIDE below
        # it, at the steady slope k_cs = Q_p/RELIEF_OVERRIDE (rated at the supply pressure)
        "cracking_pressure": p_supply - RELIEF_OVERRIDE,
        "spring_slope": q / RELIEF_OVERRIDE,
        "nominal_pressure_drop": pack.supply_pressure,
        "nominal_flow": RELIEF_OPENING_MARGIN * q,
    }
    volume = {"volume": SUPPLY_VOLUME, "bulk_modulus": bulk_modulus}
    return [
        tank,
        ComponentSpec("fixed_pump", "pump", {"inlet": "T", "outlet": "supply"}, pump),
        ComponentSpec("relief_valve", "relief", {"inlet": "supply", "outlet": "T"}, relief),
        ComponentSpec("volume", "supply_line", {"port": "supply"}, volume),
    ]


def arm_circuit(sc: ArmScenario) -> Circuit:
    """The arm of ``sc`` as one mechanism on the system kernel (module doc)."""
    k = kernel_inputs(sc)
    limits: dict[str, tuple[float, float]] = {}
    components: list[ComponentSpec] = []
    initial: dict[str, float] = {}
    atmospheres = {aj.servo.atmospheric_pressure for aj in sc.joints}
    if len(atmospheres) != 1:
        raise HydroarmError("joints", "the joints' atmospheric pressures differ: one tank")
    p_atm = atmospheres.pop()
    for i, aj in enumerate(sc.joints):
        sec = f"joints.{aj.name}"
        if aj.servo.backlash != 0.0:
            raise HydroarmError(f"{sec}.backlash", "has no circuit form")
        stop = crank_stop(aj.servo)
        limits[aj.name] = (aj.angle_offset - stop, aj.angle_offset + stop)
        if aj.component is None:
            parts = _paper_joint(aj, sc, float(k["PP0"][i]))
        else:
            parts = _component_joint(aj, sc)
            initial[f"{aj.name}_A"] = float(k["CS0"][i, S_PA])
            initial[f"{aj.name}_B"] = float(k["CS0"][i, S_PB])
        if aj.fixed_load is not None:
            parts.append(_bench_load(aj, sc.initial_angles[aj.name], limits[aj.name]))
        elif aj.own_inertia > 0.0:
            own = {"inertia": aj.own_inertia, "initial_angle": sc.initial_angles[aj.name]}
            parts.append(ComponentSpec("inertia", "own_inertia", {"body": "joint"}, own))
        components += _renamed(parts, aj.name)
    bulk = sc.joints[0].servo.bulk_modulus
    components = _power_pack(sc, p_atm, bulk) + components
    initial = {"supply": p_atm + sc.power_pack.supply_pressure, **initial}
    return Circuit(
        name=sc.name,
        components=tuple(components),
        initial_pressure=p_atm,
        initial=initial,
        mechanism=_mechanism(sc, limits),
        initial_joints={
            aj.name: sc.initial_angles[aj.name] for aj in sc.joints if aj.fixed_load is None
        },
        method=sc.method,
        step=sc.step,
        duration=sc.duration,
        record_every=sc.record_every,
    )


def is_arm_file(doc: dict) -> bool:
    """Whether a parsed file is an arm file (``[joints.<name>]``, no circuit)."""
    return "joints" in doc and "component" not in doc and "mechanism" not in doc


def expand_file(path) -> tuple[Circuit, str]:
    """The circuit a file stands for (``hydroarm expand``) and which kind of file it was: an
    arm file as one mechanism (`arm_circuit`), a component servo or a paper joint
    file as its circuit (`hydroarm.io.joint_circuit.load_joint_or_servo_circuit`)."""
    doc, p = read_toml_file(path)
    if is_arm_file(doc):
        return arm_circuit(load_arm(p)), "arm"
    return load_joint_or_servo_circuit(p)


def simulate_arm(
    sc: ArmScenario, *, check_stability: bool = True, energy: bool = True
) -> ArmResult:
    """Run an `ArmScenario` on the system kernel: its mechanism (`arm_circuit`) with the
    circuit's energy account (pressures from the tank's), returned as an `ArmResult`
    that holds the circuit's result (``circuit``) and, read from it, each joint's servo
    angle (its angle less the offset), rate, load pressure (a paper joint's jack's; a
    component joint's (A_a·p_a − A_b·p_b)/A_a), lever (a component joint's reference), and
    the supply's gauge pressure.

    ``check_stability``: refuse, before the run, a step above any joint's stable limit
    (`ArmScenario.check_step`). ``energy``: keep the circuit's energy account (what
    `ArmResult.energy` reads; about a fifth of the run's time). A run that leaves finite
    numbers is refused after it (``solver.step``). The whole run, always
    (`simulate_motion` is the validation's run that stops once decided)."""
    return _run_arm(sc, check_stability=check_stability, energy=energy)


def _run_arm(
    sc: ArmScenario,
    *,
    check_stability: bool = True,
    energy: bool = True,
    stop_early: bool = False,
    probe: tuple[str, float] | None = None,
) -> ArmResult:
    """`simulate_arm`, or with ``stop_early`` (`simulate_motion`: no energy account) the
    run recorded piece by piece (`record_in_pieces`: the same steps and records, bit for
    bit) and stopped once the rest is decided: at a fixed point after the levers settled
    (the state, but a controller's integral that nothing reads, repeats over a piece), the
    later records then those of the last piece over again (the unread integrals' NaN); the
    result's angles, rates, pressures and levers are the whole run's. ``probe`` (joint
    name, articulation angle [rad]): also once a record's articulation angle of that joint
    is above the angle; the result then holds the records up to the end of that piece, with
    the whole run's answer to whether a recorded angle is above it (as
    `hydroarm.reference.arm_decoupled.simulate_decoupled`'s ``probe``). A stopped run's
    result holds no circuit result (``circuit`` None: its derived outputs past the stop
    would read the unread integrals' NaN), so its energies and power traces are refused in
    one line."""
    if check_stability:
        sc.check_step()
    circuit = arm_circuit(sc)
    p_atm = circuit.initial_pressure
    compiled = build(circuit, energy=energy, energy_reference_pressure=p_atm)
    if not stop_early or sc.method not in STEPPERS:  # adaptive: one call
        res = simulate(compiled)
    else:
        res = record_in_pieces(
            compiled,
            settle=math.inf if energy else settle_time(sc),
            above=None if probe is None else (probe[0], sc.joint(probe[0]).angle_offset, probe[1]),
        )
    if res.bad_step >= 0:
        raise HydroarmError(
            "solver.step",
            f"the state stopped being finite at t = {res.bad_step * sc.step:.6g} s: "
            "reduce the step",
        )
    out = _arm_result(sc, circuit, res)
    return dataclasses.replace(out, circuit=None) if stop_early else out


def settle_time(sc: ArmScenario) -> float:
    """The time [s] from which every lever of ``sc`` holds still (∞ with a sine)."""
    levers = [sc.inputs[j.name] for j in sc.joints]
    if any(lv.sine_amplitude != 0.0 for lv in levers):
        return math.inf
    return max(float(lv.times[-1]) for lv in levers)


def unread_states(compiled: CompiledCircuit) -> list[int]:
    """The states no law reads: the integral of a ``pid`` without integral gain (its output
    adds 0·∫e; the component servo's mechanical feedback is such a controller), and the
    energy account's integrals."""
    index = {stem: i for i, (stem, _) in enumerate(compiled.state_names)}
    out = sorted(compiled.energy_states.values())
    for c in compiled.circuit.components:
        if c.type == "pid" and compiled.P[compiled.parameter_index[f"{c.name}.integral_gain"]] == 0:
            out.append(index[f"{c.name}.integral"])
    return out


def record_in_pieces(
    compiled: CompiledCircuit,
    *,
    settle: float = math.inf,
    above: tuple[str, float, float] | None = None,
) -> CircuitResult:
    """`simulate` of a circuit (fixed steps) recorded piece by piece
    (`CircuitStepper.record`, pieces of `PIECE_STEPS` whole records: the whole run's
    records bit for bit), stopped once the rest is decided (`simulate_arm`): at the end
    of a piece that starts after ``settle`` [s] over which every state but the
    `unread_states` repeats (then, from there, every ``record_every``-th state repeats
    the piece's records in turn: they are filled in, the unread states' with NaN); with
    ``above`` (mechanism joint, offset, angle [rad]), at the end of a piece with a record
    whose angle less the offset plus the offset (`ArmResult.angle`'s float) is above the
    angle. A run that leaves finite numbers stops there (its ``bad_step``)."""
    c = compiled.circuit
    n = int(round(c.duration / c.step))
    every = c.record_every
    piece = every * max(1, PIECE_STEPS // every)
    stepper = CircuitStepper(compiled)
    live = np.ones(compiled.s0.size, dtype=bool)
    live[unread_states(compiled)] = False
    T, S = [np.array([stepper.t])], [stepper.state[None, :]]
    bad = -1
    while stepper.steps < n:
        before, t_before = stepper.state, stepper.t
        try:
            t, states = stepper.record(min(piece, n - stepper.steps), every)
        except HydroarmError:  # the failing state is the last record, as simulate's
            t, states = np.array([stepper.t]), stepper.state[None, :]
            bad = stepper.steps
        T.append(t)
        S.append(states)
        if bad >= 0 or (above is not None and _above(compiled, states, above)):
            break
        if t_before > settle and np.array_equal(before[live], stepper.state[live]):
            rest = n // every - stepper.steps // every
            k = stepper.steps + every * np.arange(1, rest + 1)
            T.append(k * c.step)  # integrate's t0 + k·h, t0 = 0
            filled = np.resize(states, (rest, states.shape[1]))
            filled[:, ~live] = np.nan
            S.append(filled)
            break
    return CircuitResult(compiled, np.concatenate(T), np.concatenate(S), bad, compiled.P)


def _above(compiled: CompiledCircuit, states: np.ndarray, above: tuple[str, float, float]) -> bool:
    """Whether a record's angle of a joint (``above``: name, offset, angle) is above the
    angle, computed as `simulate_arm` and `ArmResult.angle` compute it."""
    name, offset, angle = above
    column = f"{name}_angle_deg"
    res = CircuitResult(compiled, np.zeros(states.shape[0]), states, -1, compiled.P)
    theta = np.radians(res.columns([column])[column]) - offset
    return bool(np.any(theta + offset > angle))


def _arm_result(sc: ArmScenario, circuit: Circuit, res: CircuitResult) -> ArmResult:
    """The `ArmResult` read from the circuit's result of ``sc`` (`simulate_arm`)."""
    p_atm = circuit.initial_pressure
    columns = res.columns()
    specs = {c.name: c for c in circuit.components}
    n, nj = columns["t_s"].size, len(sc.joints)
    theta, omega, p, y = (np.zeros((n, nj)) for _ in range(4))
    for i, aj in enumerate(sc.joints):
        name = aj.name
        theta[:, i] = np.radians(columns[f"{name}_angle_deg"]) - aj.angle_offset
        omega[:, i] = columns[f"{name}_angular_velocity_rad_s"]
        if aj.component is None:
            p[:, i] = columns[f"{name}_jack_load_pressure_bar"] * 1e5
            y[:, i] = columns[f"{name}_lever_signal"]
            continue
        areas = specs[f"{name}_actuator"].values
        a_a, a_b = float(areas["area_a"]), float(areas["area_b"])
        p_a = columns[f"{name}_A_pressure_bar"] * 1e5
        p_b = columns[f"{name}_B_pressure_bar"] * 1e5
        p[:, i] = (a_a * p_a - a_b * p_b) / a_a
        y[:, i] = columns[f"{name}_reference_signal"]
    return ArmResult(
        t=columns["t_s"],
        theta=theta,
        omega=omega,
        p=p,
        y=y,
        supply_pressure=columns["supply_pressure_bar"] * 1e5 - p_atm,
        scenario=sc,
        circuit=res,
    )


def simulate_motion(sc: ArmScenario, *, probe: tuple[str, float] | None = None) -> ArmResult:
    """`simulate_arm` without the energy account (stopped at a fixed point, or once the
    ``probe`` is decided): the runs of the arm's validation and card
    (`hydroarm.paper.arm_validation`, `hydroarm.paper.arm_card`), which read motions only."""
    return _run_arm(sc, energy=False, stop_early=True, probe=probe)
