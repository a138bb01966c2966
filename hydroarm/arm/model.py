"""The whole arm: four hydraulic servo joints on one power pack, with 3-D kinematics.

The arm's description (`ArmScenario`, `ArmJoint`, `ArmGeometry`, `PowerPack`, the
stable-step check, the start state `kernel_inputs`). The arm runs on the system kernel:
`hydroarm.arm.expand.simulate_arm` writes the scenario as one mechanism and runs it. The
decoupled arm model's own loop (`arm_integrate`, `simulate_decoupled`), which what follows
describes, is held apart as a reference: `hydroarm.reference.arm_decoupled`.

Every articulation is a [`ServoJoint`][hydroarm.ServoJoint] (valve, jack, crank,
gearbox, physics options) advanced by the single-joint step kernel
(`hydroarm.integrators.fixed.step_once`), so that one joint alone is the single-joint
model. What the arm adds (docs/arm.md):

* **Kinematics** — articulation angles q = (α shoulder elevation from hanging, ψ humeral
  rotation, ε elbow flexion, ρ wrist rotation); the reach actuator drives ε and, through the
  elbow block, over-extends the shoulder by −k·ε (k = 55°/110°). Upper-arm direction
  u = (sin β, 0, −cos β) with β = α − k·ε (x forward, y left, z up, shoulder at the origin);
  forearm direction f = rotation about u by ψ of (sin(β+ε), 0, −cos(β+ε)).
* **Pose-dependent loads** — the gravity torque on each joint is ∂U/∂q_j of the potential
  U = g·Σ m_i·z_i (virtual work, so the linked reach gets both of its angles), and its
  inertia the diagonal mass-matrix term Σ m_i·|∂r_i/∂q_j|² plus the joint's own inertia
  (off-diagonal inertial coupling is neglected: the arm's joints are slow and geared).
  Both are evaluated at the start of each Euler step and at every stage of the coupled
  RK4 (docs/arm.md, Speed).
* **Shared power pack** — a pump of flow Q_p with a relief valve at p_r: the supply
  pressure is p_r while the valves draw less than Q_p, and otherwise the pressure at which
  the valves together draw exactly Q_p (flow balance Σ Q_i(p_s) = Q_p, solved each step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from ..core.arm_kinematics import (
    JOINT_NAMES,
    pose_load,
)
from ..core.circuit.system import SYSTEM
from ..core.equations import (
    holding_pressure,
)
from ..core.params import (
    N_ROW,
    ArmGeometryParams,
    arm_geometry_params,
)
from ..core.params import STANDARD_GRAVITY as G0
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    LOAD_MASS,
    P_AREA_A,
    P_AREA_B,
    P_FORCE,
    P_LOAD,
    P_P_CAV,
    P_P_SUPPLY,
    P_P_TANK,
    P_Q_MAX,
    P_Q_MIN,
    PARAMETER_INDEX,
    PARAMETERS,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    SUPPLY_FIXED,
    VALVE_SPOOL,
    default_parameters,
)
from ..core.servo import (
    N_PARAMETERS as N_SERVO_PARAMETERS,
)
from ..core.servo import N_STATES as N_SERVO_STATES
from ..errors import HydroarmError, check_number
from ..integrators import registry
from ..io.joint_circuit import crank_stop
from ..metrics import power
from ..model.circuit import CompiledCircuit
from ..model.circuit_steady import rhs
from ..model.joint import (
    Load,
    ServoJoint,
    pack,
)
from ..model.lever import LeverInput
from ..model.lever import step as lever_step
from ..model.scenario import Scenario
from ..model.servo import ServoScenario
from ..model.servo_circuit import circuit_step_limit
from .blocks import BlockTask

# the load of a joint whose load comes from the pose: gravity torque T and inertia set each
# step by the kernel (W = X = 0)
_POSE_LOAD = Load(weight=0.0, arm=0.0, inertia=1.0)


@dataclass(frozen=True)
class ArmGeometry:
    """Segment lengths [m] and masses [kg] of the arm (estimates in docs/arm.md)."""

    upper_arm_length: float = 0.25
    forearm_length: float = 0.21
    hand_length: float = 0.05
    upper_arm_mass: float = 1.03
    upper_arm_com: float = 0.11  # from the shoulder [m]
    forearm_mass: float = 0.52
    forearm_com: float = 0.07  # from the elbow [m]
    hand_mass: float = 0.0  # payload at the hand point [kg]
    reach_shoulder_ratio: float = 0.5  # shoulder over-extension per elbow flexion (55/110)

    def __post_init__(self):
        for f in ("upper_arm_length", "forearm_length"):
            check_number(f"arm.{f}", getattr(self, f), positive=True)
        for f in (
            "hand_length",
            "upper_arm_mass",
            "upper_arm_com",
            "forearm_mass",
            "forearm_com",
            "hand_mass",
            "reach_shoulder_ratio",
        ):
            check_number(f"arm.{f}", getattr(self, f), nonnegative=True)

    def params(self) -> ArmGeometryParams:
        """The geometry as the compiled kinematics take it (gravity g₀)."""
        return arm_geometry_params(
            self.upper_arm_length,
            self.forearm_length,
            self.hand_length,
            self.upper_arm_mass,
            self.upper_arm_com,
            self.forearm_mass,
            self.forearm_com,
            self.hand_mass,
            self.reach_shoulder_ratio,
            G0,
        )

    def replace(self, **kw) -> ArmGeometry:
        return replace(self, **kw)

    def inertia_bounds(self, name: str) -> tuple[float, float]:
        """Bounds [kg m²] on the pose inertia M_jj of joint ``name`` over every pose (docs/arm.md:
        the Jacobian columns of the point masses r = λ·u + μ·f, with g = λ + μ·cos ε in
        [λ − μ, λ + μ] and |∂β/∂ε| = k): elevation Σ m·max(λ − μ, 0)² ≤ M ≤ Σ m·(λ + μ)²;
        humeral rotation 0 ≤ M ≤ Σ m·μ²; reach m_u·(k·c_u)² ≤ M ≤ Σ m·(k·(λ + μ) + μ)²;
        the wrist 0."""
        k = self.reach_shoulder_ratio
        pts = (
            (self.upper_arm_mass, self.upper_arm_com, 0.0),
            (self.forearm_mass, self.upper_arm_length, self.forearm_com),
            (self.hand_mass, self.upper_arm_length, self.forearm_length + self.hand_length),
        )
        if name == "shoulder_elevation":
            lo = sum(m * max(lam - mu, 0.0) ** 2 for m, lam, mu in pts)
            return lo, sum(m * (lam + mu) ** 2 for m, lam, mu in pts)
        if name == "humeral_rotation":
            return 0.0, sum(m * mu**2 for m, lam, mu in pts)
        if name == "elbow_reach":
            lo = self.upper_arm_mass * (k * self.upper_arm_com) ** 2
            return lo, sum(m * (k * (lam + mu) + mu) ** 2 for m, lam, mu in pts)
        return 0.0, 0.0


@dataclass(frozen=True)
class ArmJoint:
    """One articulation: its servo, how its servo angle maps to the articulation angle, and
    its load (from the pose, or a fixed [`Load`][hydroarm.Load] as in the single-joint model).

    articulation angle q = θ_servo + ``angle_offset``; ``own_inertia`` [kg m²] is added to
    the pose inertia (rotating parts on the joint axis, the piston referred through the crank).
    A ``fixed_load`` puts the joint on a test bench: it drives that load (its whole load,
    no ``own_inertia``) from the arm's power pack, off the arm's tree, whose pose holds the
    articulation at its initial angle (`hydroarm.arm.expand.arm_circuit`).
    """

    name: str
    servo: ServoJoint
    angle_offset: float = 0.0
    own_inertia: float = 0.0
    fixed_load: Load | None = None
    # a joint built from components (docs/arm.md, "Joints built from components"): the
    # actuator's and valve's servo parameters {name of hydroarm.core.servo.PARAMETERS: SI
    # value}; the crank, gearbox, lever feedback and supply stay the joint's (``servo``)
    component: dict | None = None

    def __post_init__(self):
        if self.name not in JOINT_NAMES:
            raise HydroarmError(
                "joints", f"unknown joint {self.name!r} (known: {', '.join(JOINT_NAMES)})"
            )
        check_number(f"joints.{self.name}.own_inertia", self.own_inertia, nonnegative=True)
        check_number(f"joints.{self.name}.angle_offset", self.angle_offset)
        if self.fixed_load is not None and self.own_inertia != 0.0:
            raise HydroarmError(
                f"joints.{self.name}.own_inertia",
                "is added to a pose's inertia: a fixed load's inertia is the joint's whole",
            )
        if self.component is not None:
            for k in self.component:
                if k not in PARAMETER_INDEX:
                    raise HydroarmError(
                        f"joints.{self.name}.{k}", "is not a component servo parameter"
                    )
            if self.servo.backlash != 0.0:
                raise HydroarmError(
                    f"joints.{self.name}.backlash", "is not modelled for a component joint"
                )

    def component_vector(self, supply_pressure: float, load: Load | None) -> np.ndarray:
        """The component servo's parameter vector of this joint (`hydroarm.core.servo`):
        the crank and gearbox, piston friction, end stops and mechanical lever feedback (gain
        1: the spool opening is lever − jack, eq. (2)) of ``servo``; a fixed supply at the
        gauge ``supply_pressure`` above a tank at atmospheric pressure (absolute pressures;
        the arm kernel sets the supply each step); the ``load`` (W·X at θ_h, inertia) or for
        a pose load none (the kernel sets the torque and inertia); then the ``component``
        values over these."""
        s = self.servo
        P = default_parameters()
        p_t = s.atmospheric_pressure
        idx = PARAMETER_INDEX
        values = {
            # valve: the joint's orifice valve as a zero-lap 4/3 spool valve (the same law,
            # docs/components.md), unless the component gives its own
            "valve_kind": VALVE_SPOOL,
            "edge_pa": s.flow_coefficient,
            "edge_at": s.flow_coefficient,
            "edge_pb": s.flow_coefficient,
            "edge_bt": s.flow_coefficient,
            "spool_max": s.valve_saturation,
            "transition_pressure": s.transition_pressure,
            "feedback_kind": FEEDBACK_MECHANICAL,
            "feedback_gain": 1.0,
            "coulomb_friction": s.coulomb_friction,
            "breakaway_friction": s.breakaway_friction,
            "viscous_friction": s.viscous_friction,
            "atmospheric_pressure": p_t,
            "load_kind": LOAD_CRANK,
            "crank_radius": s.crank_radius,
            "gear_ratio": s.gear_ratio,
            "kinematic_torque_arm": 1.0 if s.torque_arm == "kinematic" else 0.0,
            "gearbox_friction_torque": s.gearbox_friction_torque,
            "gearbox_loss_at_stall": s.gearbox_loss_at_stall,
            "gearbox_loss_exponent": s.gearbox_loss_exponent,
            "rated_load_pressure": s.supply_pressure,
            "supply_kind": SUPPLY_FIXED,
            "tank_pressure": p_t,
            "supply_pressure": supply_pressure + p_t,
            "mass": 1.0 if load is None else load.inertia,
            "gravity_moment": 0.0 if load is None else load.weight * load.arm,
            "gravity_angle": s.horizontal_angle,
        }
        if s.null_leakage_coefficient > 0.0:
            # the valve's leakage at null L₀ (O6) as an underlap u on each edge: the same
            # null flow-pressure coefficient, k·u/(2·√(p_s/2)) = 2·L₀ at the rated supply,
            # fading as the spool opens (the closing edges shut at |x_v| = u)
            u = 4.0 * s.null_leakage_coefficient * math.sqrt(0.5 * s.supply_pressure)
            u /= s.flow_coefficient
            for e in ("pa", "at", "pb", "bt"):
                values[f"lap_{e}"] = -u
        if s.end_stop_angle is not None:
            values["position_min"] = -s.end_stop_angle
            values["position_max"] = s.end_stop_angle
        values.update(self.component or {})
        for k, v in values.items():
            P[idx[k]] = v
        return P

    def servo_angle(self, angle: float) -> float:
        th = angle - self.angle_offset
        if abs(th) >= self.servo.max_angle:
            raise HydroarmError(
                f"inputs.{self.name}", f"{math.degrees(angle):.4g} deg is beyond the joint's reach"
            )
        return th

    def lever_for_angle(self, angle: float) -> float:
        """Lever (valve spool) position [m] that commands the articulation angle [rad]."""
        return self.servo.jack_position(self.servo_angle(angle))


@dataclass(frozen=True)
class PowerPack:
    """Body-worn power pack: pump flow Q_p [m³/s] (inf: unlimited) and relief pressure [Pa];
    its electric side (docs/arm.md, "Power pack: the electric side"): the pump's overall and
    the motor's efficiency (0 < η ≤ 1, constants; None: no electric energy reported) and the
    battery, its capacity as an energy [J] or a charge [C] at a nominal voltage [V], of which
    ``usable_fraction`` is used per charge (None: no cycles per charge reported)."""

    supply_pressure: float = 31e5
    pump_flow: float = math.inf
    motor_efficiency: float | None = None
    pump_efficiency: float | None = None
    battery_energy: float | None = None  # nominal [J]
    battery_charge: float | None = None  # nominal [C]
    battery_voltage: float | None = None  # nominal [V]
    usable_fraction: float = 1.0

    def __post_init__(self):
        check_number("power_pack.supply_pressure", self.supply_pressure, positive=True)
        if not (isinstance(self.pump_flow, (int, float)) and self.pump_flow > 0):
            raise HydroarmError("power_pack.pump_flow", f"must be positive, got {self.pump_flow!r}")
        effs = ("motor_efficiency", "pump_efficiency")
        for f in effs:
            if getattr(self, f) is not None:
                power.check_efficiency(f"power_pack.{f}", getattr(self, f))
        given = [f for f in effs if getattr(self, f) is not None]
        if len(given) == 1:
            other = effs[1 - effs.index(given[0])]
            raise HydroarmError(
                f"power_pack.{other}", f"is missing (the electric energy needs it with {given[0]})"
            )
        u = self.usable_fraction
        check_number("power_pack.usable_fraction", u, positive=True)
        if u > 1.0:
            raise HydroarmError("power_pack.usable_fraction", f"must be at most 1, got {u!r}")
        if self.battery_energy is not None and self.battery_charge is not None:
            raise HydroarmError(
                "power_pack.battery_capacity", "give it as an energy or as a charge, not both"
            )
        for f in ("battery_energy", "battery_charge", "battery_voltage"):
            if getattr(self, f) is not None:
                check_number(f"power_pack.{f}", getattr(self, f), positive=True)
        if self.battery_charge is not None and self.battery_voltage is None:
            raise HydroarmError(
                "power_pack.battery_voltage",
                "is missing (needed with a battery_capacity given as a charge, e.g. A*h)",
            )
        if self.battery_charge is None and self.battery_voltage is not None:
            raise HydroarmError(
                "power_pack.battery_voltage",
                "is only for a battery_capacity given as a charge (e.g. A*h)",
            )
        has_battery = self.battery_energy is not None or self.battery_charge is not None
        if has_battery and not given:
            raise HydroarmError(
                "power_pack.motor_efficiency",
                "is missing (cycles per charge need the motor and pump efficiencies)",
            )

    @property
    def electric(self) -> bool:
        """Whether the efficiencies are given (the electric energy can be reported)."""
        return self.motor_efficiency is not None and self.pump_efficiency is not None

    @property
    def usable_battery_energy(self) -> float | None:
        """Usable energy of one charge [J] (None: no battery given)."""
        if self.battery_energy is None and self.battery_charge is None:
            return None
        return power.battery_energy(
            energy=self.battery_energy,
            charge=self.battery_charge,
            voltage=self.battery_voltage,
            usable_fraction=self.usable_fraction,
        )


@dataclass(frozen=True)
class ArmScenario:
    """Joints (any subset of the four), their lever inputs and start angles, the power pack."""

    joints: tuple
    inputs: dict
    initial_angles: dict
    geometry: ArmGeometry = field(default_factory=ArmGeometry)
    power_pack: PowerPack = field(default_factory=PowerPack)
    duration: float = 2.0
    step: float = 10e-6
    method: str = "euler"
    record_every: int = 10
    name: str = "arm"
    # the block transfer of the arm's card (hydroarm.arm.blocks; None: DEFAULT_TASK)
    block_task: BlockTask | None = None

    def __post_init__(self):
        names = [j.name for j in self.joints]
        if len(set(names)) != len(names):
            raise HydroarmError("joints", "a joint is given twice")
        for n in names:
            if n not in self.inputs:
                raise HydroarmError(f"inputs.{n}", "is missing")
            if n not in self.initial_angles:
                raise HydroarmError(f"initial.{n}", "is missing")
        if self.method not in registry.fixed_step_methods():
            raise HydroarmError(
                "solver.method",
                f"must be {' or '.join(registry.fixed_step_methods())}, got {self.method!r}",
            )
        check_number("solver.duration", self.duration, positive=True)
        check_number("solver.step", self.step, positive=True)
        if self.step > self.duration:
            raise HydroarmError("solver.step", "is longer than the duration")

    def joint(self, name: str) -> ArmJoint:
        for j in self.joints:
            if j.name == name:
                return j
        raise HydroarmError("joints", f"no joint {name!r} in this arm")

    def replace(self, **kw) -> ArmScenario:
        return replace(self, **kw)

    def check_step(self) -> None:
        """Refuse a step above any joint's stability limit (with its own load).

        A pose-loaded joint is checked with no gravity torque at the smallest and the largest
        inertia its pose can give it (`ArmGeometry.inertia_bounds` plus its own inertia)
        and at their geometric mean: the stable step is not monotonic in the inertia."""
        for j in self.joints:
            if j.fixed_load is not None:
                loads = [j.fixed_load]
            else:
                lo, hi = self.geometry.inertia_bounds(j.name)
                lo, hi = max(lo + j.own_inertia, 1e-6), max(hi + j.own_inertia, 1e-6)
                loads = [
                    Load(weight=0.0, arm=0.0, inertia=i)
                    for i in sorted({lo, math.sqrt(lo * hi), hi})
                ]
            th0 = j.servo_angle(self.initial_angles[j.name])
            lever = self.inputs[j.name]
            if j.component is not None:
                for load in loads:
                    P = _as_in_arm(j, j.component_vector(self.power_pack.supply_pressure, load))
                    limit = _component_step_limit(
                        self.method,
                        self.step,
                        self.duration,
                        tuple(float(v) for v in P),
                        th0,
                        float(lever(0.0)[0]),
                    )
                    if limit is not None:
                        raise HydroarmError(
                            "solver.step",
                            f"{self.step:.3g} s is above the stable limit {limit:.3g} s of "
                            f"'{self.method}' for this servo; use a smaller step "
                            f"(joint {j.name})",
                        )
                continue
            for load in loads:
                problem = _step_problem(
                    j.servo, load, th0, lever.final, self.duration, self.step, self.method
                )
                if problem:
                    raise HydroarmError("solver.step", f"{problem} (joint {j.name})")


def _as_in_arm(j: ArmJoint, P: np.ndarray) -> np.ndarray:
    """A component joint's servo parameters ``P`` as the arm's circuit runs it
    (`hydroarm.arm.expand.arm_circuit`), in place: its load's stops at the joint's reach
    (`hydroarm.io.joint_circuit.crank_stop`: its circuit's crank passes no dead centre) and
    the cavitation floor the arm's circuit's (the system's default)."""
    stop = crank_stop(j.servo)
    P[P_Q_MIN] = max(P[P_Q_MIN], -stop)
    P[P_Q_MAX] = min(P[P_Q_MAX], stop)
    P[P_P_CAV] = SYSTEM.parameter("cavitation_pressure").default
    return P


@lru_cache(maxsize=256)
def _step_problem(servo, load, theta0, target, duration, step, method) -> str:
    """Why the single-joint check refuses this joint's step ('' if it does not): what
    [`Scenario.check_step`][hydroarm.Scenario.check_step] depends on, remembered (the validation's
    bisection checks the same joints again and again)."""
    sc = Scenario(
        joint=servo,
        load=load,
        lever=lever_step(target, target, 0.0),
        initial_angle=theta0,
        duration=duration,
        step=step,
        method=method,
    )
    try:
        sc.check_step()
    except HydroarmError as exc:
        return exc.problem
    return ""


def component_holding_pressures(P: np.ndarray, theta: float) -> tuple[float, float]:
    """(p_A, p_B) [Pa]: the chamber pressures of a component servo (parameter vector ``P``,
    `hydroarm.core.servo.PARAMETERS`, as the arm's circuit runs it: `_as_in_arm`)
    holding its load at rest at servo angle ``theta`` [rad]: those of a zero-lap valve
    feeding the actuator's leakage, p_A + p_B = p_s + p_T, at which the load's acceleration
    on the servo's circuit (`hydroarm.model.servo_circuit.scenario_circuit`; the system
    kernel's right-hand side, `hydroarm.model.circuit_steady.rhs`: the actuator's pressure
    force through the crank linkage against the load's laws) vanishes. It is affine in p_A
    along that line, so two evaluations (p_A at the tank's and at the supply's pressure)
    give the root. Neither pressure below the cavitation floor."""
    compiled = _servo_circuit(tuple(float(v) for v in P))
    nh, nm = len(compiled.hydraulic), len(compiled.mechanical)
    m = compiled.mechanical["rod" if P[P_LOAD] == LOAD_MASS else "joint"]
    i_a, i_b = compiled.hydraulic["A"], compiled.hydraulic["B"]
    total = P[P_P_SUPPLY] + P[P_P_TANK]
    s = compiled.s0.astype(float).copy()
    s[nh + m] = theta
    s[nh + nm + m] = 0.0

    def acceleration(p_a: float) -> float:
        s[i_a], s[i_b] = p_a, total - p_a
        return float(rhs(compiled, 0.0, s, compiled.P)[nh + nm + m])

    lo, hi = P[P_P_TANK], P[P_P_SUPPLY]
    a_lo, a_hi = acceleration(lo), acceleration(hi)
    p_a = lo + (hi - lo) * a_lo / (a_lo - a_hi)
    p_b = total - p_a
    return max(p_a, P[P_P_CAV]), max(p_b, P[P_P_CAV])


def _servo(P, **scenario) -> ServoScenario:
    """The component servo of parameter vector ``P`` (`hydroarm.core.servo.PARAMETERS`)
    with the other ``scenario`` fields."""
    names = [name for name, _, _ in PARAMETERS]
    return ServoScenario(parameters=dict(zip(names, P, strict=True)), **scenario)


@lru_cache(maxsize=64)
def _servo_circuit(P: tuple) -> CompiledCircuit:
    """The compiled circuit of a component servo's parameter vector ``P`` (as a tuple)."""
    return _servo(P, reference=lever_step(0.0, 0.0, 0.0)).compiled_circuit


def component_initial_state(P: np.ndarray, theta: float) -> np.ndarray:
    """The component servo's state (`hydroarm.core.servo.STATES`) at rest at servo angle
    ``theta`` [rad] holding its load (`component_holding_pressures`), its supply at
    ``supply_pressure``; the spool and the rest at 0."""
    s0 = np.zeros(N_SERVO_STATES)
    s0[S_Q] = theta
    s0[S_PA], s0[S_PB] = component_holding_pressures(P, theta)
    s0[S_PS] = P[P_P_SUPPLY]
    return s0


@lru_cache(maxsize=256)
def _component_step_limit(method, step, duration, P, theta0, lever):
    """None, or the largest stable step of a component joint started at rest at θ₀ holding
    its load: its servo's circuit on the system kernel
    (`hydroarm.model.servo_circuit.circuit_step_limit`), the lever held at ``lever``."""
    Pv = np.array(P)
    s0 = component_initial_state(Pv, theta0)
    servo = _servo(
        P,
        reference=lever_step(lever, lever, 0.0),
        initial={
            "position": theta0,
            "pressure_a": float(s0[S_PA]),
            "pressure_b": float(s0[S_PB]),
            "supply_pressure": float(s0[S_PS]),
        },
        method=method,
        step=step,
        duration=max(duration, step),
    )
    return circuit_step_limit(servo)


def _initial_pressure(j: ArmJoint, theta: float, q: np.ndarray, G: ArmGeometryParams) -> float:
    """Pressure that holds the joint's load at rest (as the single-joint model starts)."""
    load = (j.fixed_load or _POSE_LOAD).params()
    if j.fixed_load is None:
        tg, _ = pose_load(q, JOINT_NAMES.index(j.name), G)
        load = load._replace(torque=float(tg))
    return float(holding_pressure(theta, j.servo.params(), load))


def kernel_inputs(sc: ArmScenario) -> dict:
    """The arrays `arm_integrate` (and `ArmStepper`) take
    for a scenario, by argument name: the geometry G, the joints' kinds, offsets, own
    inertias and pose flags, the lever tables (TT, TY, NT, SINE), the parameter table PM,
    the start state (TH0, PP0, CS0), the component flags and parameters (comp, CP)."""
    nj = len(sc.joints)
    G = sc.geometry.params()
    kinds = np.array([JOINT_NAMES.index(j.name) for j in sc.joints], dtype=np.int64)
    offsets = np.array([j.angle_offset for j in sc.joints])
    own = np.array([j.own_inertia for j in sc.joints])
    pose = np.array([j.fixed_load is None for j in sc.joints])
    levers: list[LeverInput] = [sc.inputs[j.name] for j in sc.joints]
    n = max(len(lv.times) for lv in levers)
    TT = np.zeros((nj, n))
    TY = np.zeros((nj, n))
    NT = np.array([len(lv.times) for lv in levers], dtype=np.int64)
    SINE = np.array([lv.sine for lv in levers])
    for j, lv in enumerate(levers):
        TT[j, : NT[j]] = lv.times
        TY[j, : NT[j]] = lv.positions
    PM = np.empty((nj, N_ROW))  # one batch-table row per joint; the kernel updates the
    # supply pressure and, for pose loads, the load torque and inertia of each step
    for j, aj in enumerate(sc.joints):
        load = aj.fixed_load or _POSE_LOAD
        PM[j] = pack(aj.servo.replace(supply_pressure=sc.power_pack.supply_pressure), load)
    th0 = np.array([aj.servo_angle(sc.initial_angles[aj.name]) for aj in sc.joints])
    q = np.zeros(4)
    for j in range(nj):
        q[kinds[j]] = th0[j] + offsets[j]
    p0 = np.array([_initial_pressure(aj, th0[j], q, G) for j, aj in enumerate(sc.joints)])
    comp = np.array([aj.component is not None for aj in sc.joints])
    CP = np.zeros((nj, N_SERVO_PARAMETERS))
    CS0 = np.zeros((nj, N_SERVO_STATES))
    for j, aj in enumerate(sc.joints):
        if aj.component is None:
            continue
        CP[j] = aj.component_vector(sc.power_pack.supply_pressure, aj.fixed_load)
        if aj.fixed_load is None:
            # the pose's gravity torque at the start (the kernel sets it each step)
            CP[j, P_FORCE] = float(pose_load(q, JOINT_NAMES.index(aj.name), G)[0])
        CS0[j] = component_initial_state(_as_in_arm(aj, CP[j].copy()), th0[j])
        p0[j] = (CP[j, P_AREA_A] * CS0[j, S_PA] - CP[j, P_AREA_B] * CS0[j, S_PB]) / CP[j, P_AREA_A]
    return {
        "G": G,
        "kinds": kinds,
        "offsets": offsets,
        "own_inertia": own,
        "pose": pose,
        "TT": TT,
        "TY": TY,
        "NT": NT,
        "SINE": SINE,
        "PM": PM,
        "TH0": th0,
        "PP0": p0,
        "comp": comp,
        "CS0": CS0,
        "CP": CP,
    }
