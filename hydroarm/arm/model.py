"""The whole arm: four hydraulic servo joints on one power pack, with 3-D kinematics.

The arm's description (`ArmScenario`, `ArmJoint`, `ArmGeometry`, `PowerPack`, the
stable-step check) and the decoupled arm model's loop. The arm runs on the system kernel:
`hydroarm.arm.expand.simulate_arm` writes the scenario as one mechanism and runs it. The
loop below (`arm_integrate`, `simulate_decoupled`) is no product path's physics but that of
`hydroarm.arm.stepper.ArmStepper` (the explorer's live arm, the arm FMU), until that runs
on the system kernel too; what follows describes it.

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
from numba import njit

from ..core.arm_kinematics import (
    ELEVATION,
    JOINT_NAMES,
    REACH,
    ROTATION,
    WRIST,
    pose_load,
    pose_terms,
)
from ..core.components import spool_valve_flows
from ..core.equations import (
    crank_reach,
    derivatives,
    holding_pressure,
    jack_position,
    pressure_bound,
    supply_flow,
    valve_opening,
)
from ..core.params import (
    J_SUPPLY,
    L_INERTIA,
    L_TORQUE,
    N_ROW,
    ArmGeometryParams,
    arm_geometry_params,
    joint_at,
    load_at,
)
from ..core.params import STANDARD_GRAVITY as G0
from ..core.servo import (
    FEEDBACK_MECHANICAL,
    LOAD_CRANK,
    P_AREA_A,
    P_AREA_B,
    P_FLOW_GAIN,
    P_FORCE,
    P_GRAV_ANGLE,
    P_GRAV_MOMENT,
    P_K_AT,
    P_K_BT,
    P_K_PA,
    P_K_PB,
    P_LAP_AT,
    P_LAP_BT,
    P_LAP_PA,
    P_LAP_PB,
    P_MASS,
    P_P_SUPPLY,
    P_P_TANK,
    P_P_TRANS,
    P_SPOOL_ORDER,
    P_VALVE,
    PARAMETER_INDEX,
    S_E_SUPPLY,
    S_PA,
    S_PB,
    S_PS,
    S_Q,
    S_V,
    S_XV,
    SUPPLY_FIXED,
    VALVE_LINEARISED,
    VALVE_SPOOL,
    actuator_motion,
    default_parameters,
    servo_rhs,
    spool_demand,
)
from ..core.servo import (
    N_PARAMETERS as N_SERVO_PARAMETERS,
)
from ..core.servo import N_STATES as N_SERVO_STATES
from ..errors import HydroarmError, check_number
from ..integrators import registry, stability
from ..integrators.fixed import EULER, in_bounds, rk4_projections, step_once
from ..integrators.servo import project as servo_project
from ..integrators.servo import step as servo_step
from ..metrics import power
from ..model.joint import (
    Load,
    ServoJoint,
    pack,
)
from ..model.lever import LeverInput
from ..model.lever import step as lever_step
from ..model.scenario import Scenario
from .blocks import BlockTask
from .result import ArmResult

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
                    P = j.component_vector(self.power_pack.supply_pressure, load)
                    limit = _component_step_limit(
                        self.method, self.step, tuple(P), th0, float(lever(0.0)[0])
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


def component_initial_state(P: np.ndarray, theta: float, lever: float) -> np.ndarray:
    """The component servo's state holding its load at rest at servo angle ``theta``: the
    chamber pressures of a zero-lap valve feeding the actuator's leakage, p_A + p_B = p_s +
    p_T, with A_A·p_A − A_B·p_B the force that holds the load; the spool at its demand for
    the ``lever`` (the projection of `hydroarm.integrators.servo.integrate`'s start)."""
    s0 = np.zeros(N_SERVO_STATES)
    s0[S_Q] = theta
    x, _, arm = actuator_motion(theta, 0.0, P)
    torque = P[P_FORCE] + P[P_GRAV_MOMENT] * math.cos(theta - P[P_GRAV_ANGLE])
    force = torque / arm
    total = P[P_P_SUPPLY] + P[P_P_TANK]
    s0[S_PA] = (force + P[P_AREA_B] * total) / (P[P_AREA_A] + P[P_AREA_B])
    s0[S_PB] = total - s0[S_PA]
    s0[S_PS] = P[P_P_SUPPLY]
    s = s0.copy()
    servo_project(EULER, s0, s, 0.0, lever, P)
    return s


@lru_cache(maxsize=256)
def _component_step_limit(method, step, P, theta0, lever):
    """None, or the largest stable step of a component joint (the component servo's check,
    `hydroarm.integrators.stability.servo_step_limit`) started at rest at θ₀."""
    Pv = np.array(P)
    s0 = component_initial_state(Pv, theta0, lever)
    return stability.servo_step_limit(method, step, s0, lever, Pv)


# ---------------------------------------------------------------------- kernel ---
@njit(cache=True, nogil=True)
def _demand(ps, es, PP, PM, comp, CS, CP):
    """Σ_i |Q_i| [m³/s]: the flow the valves draw from the supply at pressure ``ps`` (the
    supply-edge flows of `supply_flow`), PM's supply set to ps.
    A component joint (``comp``) draws its valve's supply flow Q_P
    (`valve_flows`) at spool position ``es`` and state ``CS``,
    whose supply (absolute) is set to ps above its tank."""
    s = 0.0
    for j in range(es.shape[0]):
        PM[j, J_SUPPLY] = ps
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
            s += _component_supply_flow(es[j], CS, CP, j)
            continue
        s += supply_flow(es[j], PP[j], joint_at(PM, j))
    return s


@njit(cache=True, nogil=True)
def _component_supply_flow(x_v, CS, CP, j):
    """The supply flow Q_P [m³/s] of `valve_flows` of component
    joint ``j`` at spool position x_v, read from the rows of ``CS`` and ``CP`` in place (the
    same operations; a row view would cost an atomic reference-count pair per call)."""
    if CP[j, P_VALVE] == VALVE_LINEARISED:
        q = CP[j, P_FLOW_GAIN] * x_v
        if q >= 0.0:
            return q
        return -(q * (CP[j, P_AREA_B] / CP[j, P_AREA_A]))
    return spool_valve_flows(
        x_v,
        CS[j, S_PS],
        CP[j, P_P_TANK],
        CS[j, S_PA],
        CS[j, S_PB],
        CP[j, P_K_PA],
        CP[j, P_K_AT],
        CP[j, P_K_PB],
        CP[j, P_K_BT],
        CP[j, P_LAP_PA],
        CP[j, P_LAP_AT],
        CP[j, P_LAP_PB],
        CP[j, P_LAP_BT],
        CP[j, P_P_TRANS],
    )[2]


@njit(cache=True, nogil=True)
def _lever(t, TT, TY, NT, SINE, j):
    """`evaluate` of joint ``j``'s lever (row j of the tables,
    its first NT[j] points), read in place: the same operations (the interval found by the
    same bisection as ``np.searchsorted(side="right")``), no row views."""
    n = NT[j]
    if t >= TT[j, n - 1]:
        y = TY[j, n - 1]
    elif t < TT[j, 0]:
        y = TY[j, 0]
    else:
        lo, hi = 0, n  # the first index whose time is > t, minus one
        while lo < hi:
            mid = (lo + hi) >> 1
            if TT[j, mid] <= t:
                lo = mid + 1
            else:
                hi = mid
        i = lo - 1
        dt = TT[j, i + 1] - TT[j, i]
        if dt > 0.0:
            y = TY[j, i] + (TY[j, i + 1] - TY[j, i]) * (t - TT[j, i]) / dt
        else:
            y = TY[j, i + 1]
    if SINE[j, 0] != 0.0 and t >= SINE[j, 2]:
        y += SINE[j, 0] * np.sin(2.0 * np.pi * SINE[j, 1] * (t - SINE[j, 2]))
    return y


@njit(cache=True, nogil=True)
def _component_spool(y, s, P):
    """Spool position [m] of a component joint at lever ``y`` and state ``s``: the feedback's
    demand for a spool without dynamics (as `servo_rhs` takes it),
    else the spool state."""
    if P[P_SPOOL_ORDER] == 0:
        x, v_x, _ = actuator_motion(s[S_Q], s[S_V], P)
        return spool_demand(y, s, x, v_x, P)[0]
    return s[S_XV]


@njit(cache=True, nogil=True)
def _supply(t, TH, PP, TT, TY, NT, SINE, PM, es, pump_flow, p_relief, comp, CS, CP):
    """Supply pressure from the flow balance of the pump and the valves (module doc), the
    valves' openings taken from the lever at time ``t`` and the angles ``TH`` (component
    joints: their spool at state ``CS``); PM's supply column set to it. ``es`` is scratch
    for the valve openings."""
    for j in range(TH.shape[0]):
        y = _lever(t, TT, TY, NT, SINE, j)
        if comp[j]:
            es[j] = _component_spool(y, CS[j], CP[j])
            continue
        J = joint_at(PM, j)
        es[j] = valve_opening(y, jack_position(TH[j], J), J)
    return _supply_pressure(PP, PM, es, pump_flow, p_relief, p_relief, comp, CS, CP)


@njit(cache=True, nogil=True)
def _supply_pressure(PP, PM, es, pump_flow, p_relief, guess, comp, CS, CP):
    """Supply pressure at the valve openings ``es`` and load pressures ``PP``; PM's supply
    column set to it.

    The demand D rises monotonically with the supply pressure; the root of D·|D| = Q_p² (nearly
    linear in p_s: each valve draws ∝ √(p_s ∓ p)) in [0, p_r] is found by the Illinois
    variant of false position (superlinear; a bisection step whenever the bracket does not
    halve), to a bracket of 1e-12·p_r. A ``guess`` strictly inside (0, p_r) (the last
    solution, in the coupled RK4) narrows the starting bracket to about it: a bracket of
    ±10⁻³·p_r widened fourfold until it holds the root; otherwise it is [0, p_r].
    """
    nj = PP.shape[0]
    q2 = pump_flow * pump_flow
    d = _demand(p_relief, es, PP, PM, comp, CS, CP)
    if d <= pump_flow:
        return p_relief
    f_hi = d * abs(d) - q2
    lo, hi = 0.0, p_relief
    if 0.0 < guess < p_relief:
        d = _demand(guess, es, PP, PM, comp, CS, CP)
        fg = d * abs(d) - q2
        step = 1e-3 * p_relief
        if fg > 0.0:  # the root is below the guess
            hi, f_hi = guess, fg
            while True:
                x = hi - step
                if x <= 0.0:
                    break
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx <= 0.0:
                    lo = x
                    break
                hi, f_hi = x, fx
                step *= 4.0
        else:
            lo = guess
            while True:
                x = lo + step
                if x >= p_relief:
                    break
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx > 0.0:
                    hi, f_hi = x, fx
                    break
                lo = x
                step *= 4.0
    d = _demand(lo, es, PP, PM, comp, CS, CP)
    f_lo = d * abs(d) - q2
    ps = p_relief
    if f_lo >= 0.0:
        ps = lo
    else:
        side = 0
        tol = 1e-12 * p_relief
        for _ in range(100):
            width = hi - lo
            if width <= tol:
                break
            x = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if not (lo < x < hi):
                x = 0.5 * (lo + hi)
            d = _demand(x, es, PP, PM, comp, CS, CP)
            fx = d * abs(d) - q2
            if fx == 0.0:
                lo = hi = x
                break
            if fx > 0.0:
                hi, f_hi = x, fx
                if side == 1:  # the same end moved twice: halve the other end's value
                    f_lo *= 0.5
                side = 1
            else:
                lo, f_lo = x, fx
                if side == -1:
                    f_hi *= 0.5
                side = -1
            if hi - lo > 0.5 * width:  # no halving: bisect once
                x = 0.5 * (lo + hi)
                d = _demand(x, es, PP, PM, comp, CS, CP)
                fx = d * abs(d) - q2
                if fx > 0.0:
                    hi, f_hi = x, fx
                else:
                    lo, f_lo = x, fx
                side = 0
        ps = 0.5 * (lo + hi)
    for j in range(nj):
        PM[j, J_SUPPLY] = ps
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
    return ps


@njit(cache=True, nogil=True)
def _pose_loads(TH, PM, kinds, pose, offsets, own_inertia, G):
    """Set the gravity torque (as the load torque T, W = X = 0) and the inertia of every
    pose-loaded joint from the articulation angles of the servo angles ``TH`` (closed form)."""
    nj = TH.shape[0]
    qa = qp = qe = 0.0  # articulation angles α, ψ, ε (0 for a joint not in the arm)
    for j in range(nj):
        if kinds[j] == ELEVATION:
            qa = TH[j] + offsets[j]
        elif kinds[j] == ROTATION:
            qp = TH[j] + offsets[j]
        elif kinds[j] == REACH:
            qe = TH[j] + offsets[j]
    ta, tp, te, maa, mpp, mee, _, _, _ = pose_terms(qa, qp, qe, G)
    for j in range(nj):
        if pose[j] and kinds[j] != WRIST:
            kj = kinds[j]
            tg = ta if kj == ELEVATION else (tp if kj == ROTATION else te)
            inert = maa if kj == ELEVATION else (mpp if kj == ROTATION else mee)
            PM[j, L_TORQUE] = tg
            PM[j, L_INERTIA] = inert + own_inertia[j]


@njit(cache=True, nogil=True)
def _component_loads(PM, CP, comp, pose):
    """Copy the pose load (torque, inertia) of every pose-loaded component joint from its PM
    row into its servo parameters (the servo's external torque and mass entries)."""
    for j in range(PM.shape[0]):
        if comp[j] and pose[j]:
            CP[j, P_FORCE] = PM[j, L_TORQUE]
            CP[j, P_MASS] = PM[j, L_INERTIA]


@njit(cache=True, nogil=True)
def _rates(
    t, TH, OM, PP, TT, TY, NT, SINE, PM, kinds, pose, offsets, own, G, any_pose, pump_flow,
    p_relief, es, KA, KB, KC, comp, CS, CP, CK,
):  # fmt: skip
    """The coupled right-hand side of the whole arm at (t, θ, ω, p): pose loads and the
    supply pressure at that state, then every joint's smooth (θ̇, θ̈, ṗ) into KA, KB, KC (dry
    friction excluded: it is the step's projection, as in the single joint). A component
    joint's state is its row of ``CS`` (θ, ω its position and velocity), its rates
    `servo_rhs` into its row of ``CK``. Returns the supply
    pressure."""
    nj = TH.shape[0]
    if any_pose:
        _pose_loads(TH, PM, kinds, pose, offsets, own, G)
        _component_loads(PM, CP, comp, pose)
    for j in range(nj):
        KC[j] = _lever(t, TT, TY, NT, SINE, j)  # the lever, for now
        if comp[j]:
            es[j] = _component_spool(KC[j], CS[j], CP[j])
            continue
        J = joint_at(PM, j)
        es[j] = valve_opening(KC[j], jack_position(TH[j], J), J)
    ps = p_relief
    if np.isfinite(pump_flow):
        ps = _supply_pressure(PP, PM, es, pump_flow, p_relief, PM[0, J_SUPPLY], comp, CS, CP)
    for j in range(nj):
        if comp[j]:
            CS[j, S_PS] = ps + CP[j, P_P_TANK]
            servo_rhs(KC[j], CS[j], CP[j], CK[j])
            KA[j], KB[j], KC[j] = CK[j, S_Q], CK[j, S_V], 0.0
            continue
        J = joint_at(PM, j)
        L = load_at(PM, j)
        KA[j], KB[j], KC[j] = derivatives(TH[j], OM[j], PP[j], KC[j], J, L)
    return ps


@njit(cache=True, nogil=True)
def _component_pressure(s, P):
    """The force-equivalent load pressure (A_A·p_A − A_B·p_B)/A_A [Pa] of a component joint
    (the jack force over the piston area: the arm's recorded load pressure)."""
    return (P[P_AREA_A] * s[S_PA] - P[P_AREA_B] * s[S_PB]) / P[P_AREA_A]


@njit(cache=True, nogil=True)
def _component_in_bounds(s, reach):
    """A component joint's state is finite and short of the crank's dead centre."""
    for i in range(s.shape[0]):
        if not np.isfinite(s[i]):
            return False
    return abs(s[S_Q]) < reach


@njit(cache=True, nogil=True)
def arm_integrate(
    method,
    TH0,
    OM0,
    PP0,
    t0,
    h,
    nsteps,
    record_every,
    TT,
    TY,
    NT,
    SINE,
    PM,
    kinds,
    pose,
    offsets,
    own_inertia,
    G,
    pump_flow,
    p_relief,
    comp,
    CS0,
    CP,
    stop_joint=-1,
    stop_offset=0.0,
    stop_angle=0.0,
    settle_t=np.inf,
    resume=False,
    PB=None,
):
    """Advance all joints together; returns (t, θ, ω, p, y, supply pressure, bad step,
    component states): the bad step is the first step at which a joint's state left the
    physical bounds (non-finite, past the crank's dead centre or above
    `pressure_bound`), or −1.

    ``euler``: each joint takes the single-joint step (`step_once`) with the pose loads
    and the supply pressure of the start of the step. ``rk4``: the classical RK4 of the
    coupled system (pose loads and supply pressure evaluated at every stage, so fourth order
    where the motion is smooth; dry friction is not in the stages), then each joint's
    non-smooth physics (`rk4_projections`: dry friction's
    stick or slide, the single joint's projection) with its start-of-step load.

    A joint built from components (``comp[j]``; docs/arm.md) has the state ``CS0[j]`` and
    the parameters ``CP[j]`` of the component servo (`hydroarm.core.servo`, its
    external torque, mass and supply set here each step or stage): ``euler`` takes the
    servo's own step (`hydroarm.integrators.servo.step`), ``rk4`` its right-hand side
    in the coupled stages and its projections (`hydroarm.integrators.servo.project`)
    with the start-of-step load. Its recorded p is the force-equivalent load pressure, its
    full state is recorded too (the last output; one row when no joint is a component).

    A probe (``stop_joint`` ≥ 0; `probe_reaches`) stops once its answer is decided:
    at the first recorded state whose articulation angle θ + ``stop_offset`` of joint
    ``stop_joint`` is above ``stop_angle``, or (``euler``) at an exact fixed point of the
    step after ``settle_t`` (every lever settled: from there every state repeats, the
    energies aside), with that state recorded once more when a later record would have kept
    it. The recorded angles then have the same maximum above ``stop_angle`` or not as the
    full run's.

    A run advanced piece by piece (`ArmStepper`) calls the
    kernel for each piece with ``resume`` True: the state (TH0, OM0, PP0, CS0) is where the
    last piece ended, PM's supply and pose columns and CP's load entries are as the last
    piece left them (the coupled RK4 starts its supply solve from the last root), not set
    to the start's; ``PB`` are the start pressures of the whole run (its pressure bounds;
    None: PP0). From the same state and inputs the pieces' steps are the whole run's, bit
    for bit.
    """
    nj = TH0.shape[0]
    ns = N_SERVO_STATES
    P_B = PP0 if PB is None else PB
    nrec = nsteps // record_every + 1
    T = np.empty(nrec)
    TH = np.empty((nrec, nj))
    OM = np.empty((nrec, nj))
    PPr = np.empty((nrec, nj))
    Y = np.empty((nrec, nj))
    PS = np.empty(nrec)
    th = TH0.copy()
    om = OM0.copy()
    pp = PP0.copy()
    any_comp = False
    for j in range(nj):
        if comp[j]:
            any_comp = True
    CSR = np.zeros((nrec if any_comp else 1, nj, ns))
    cs = CS0.copy()  # component states (rows of non-component joints unused)
    cst = np.empty((nj, ns))  # component stage states
    CK = np.empty((4, nj, ns))  # component stage rates
    cout = np.empty(ns)
    w1 = np.empty(ns)
    w2 = np.empty(ns)
    w3 = np.empty(ns)
    w4 = np.empty(ns)
    w5 = np.empty(ns)
    cheld = np.empty((nj, 2))
    es = np.empty(nj)  # scratch of the supply solve
    # RK4 scratch: stage rates and states, the start-of-step load and supply of each joint
    K = np.empty((4, 3, nj))
    ths = np.empty(nj)
    oms = np.empty(nj)
    pps = np.empty(nj)
    held = np.empty((nj, 3))
    finite_pump = np.isfinite(pump_flow)
    any_pose = False
    for j in range(nj):
        if pose[j]:
            any_pose = True
        if resume:
            continue
        PM[j, J_SUPPLY] = p_relief
        if comp[j]:
            cs[j, S_PS] = p_relief + CP[j, P_P_TANK]
        if pose[j]:
            # the wrist's pose load is zero and stays so (ρ moves no point)
            PM[j, L_TORQUE] = 0.0
            PM[j, L_INERTIA] = own_inertia[j]
            if comp[j]:
                CP[j, P_FORCE] = 0.0
                CP[j, P_MASS] = own_inertia[j]
    T[0] = t0
    for j in range(nj):
        TH[0, j] = th[j]
        OM[0, j] = om[j]
        PPr[0, j] = pp[j]
        Y[0, j] = _lever(t0, TT, TY, NT, SINE, j)
        if comp[j]:
            CSR[0, j] = cs[j]
    PS[0] = p_relief
    rec = 1
    bad = -1
    probe = stop_joint >= 0
    last_record = (nsteps // record_every) * record_every
    ps_prev = np.nan
    for k in range(1, nsteps + 1):
        t = t0 + (k - 1) * h
        fixed = probe and t > settle_t  # an exact fixed point of this step, so far
        if method == EULER:
            if any_pose:
                _pose_loads(th, PM, kinds, pose, offsets, own_inertia, G)
                if any_comp:
                    _component_loads(PM, CP, comp, pose)
            ps = p_relief
            if finite_pump:
                ps = _supply(t, th, pp, TT, TY, NT, SINE, PM, es, pump_flow, p_relief, comp, cs, CP)
            for j in range(nj):
                if comp[j]:
                    cs[j, S_PS] = ps + CP[j, P_P_TANK]
                    servo_step(
                        method, t, h, cs[j], cout, TT[j, : NT[j]], TY[j, : NT[j]], SINE[j],
                        CP[j], w1, w2, w3, w4, w5,
                    )  # fmt: skip
                    if fixed:
                        for i in range(S_E_SUPPLY):  # the energies are integrals only
                            if cout[i] != cs[j, i]:
                                fixed = False
                                break
                    cs[j] = cout
                    th[j], om[j], pp[j] = cout[S_Q], cout[S_V], _component_pressure(cout, CP[j])
                    if not _component_in_bounds(cout, crank_reach(joint_at(PM, j))):
                        bad = k
                    continue
                Jj = joint_at(PM, j)
                Lj = load_at(PM, j)
                a, b, c = step_once(
                    method,
                    t,
                    h,
                    th[j],
                    om[j],
                    pp[j],
                    TT[j, : NT[j]],
                    TY[j, : NT[j]],
                    SINE[j],
                    Jj,
                    Lj,
                )
                if fixed and (a != th[j] or b != om[j] or c != pp[j]):
                    fixed = False
                th[j], om[j], pp[j] = a, b, c
                # finite, short of the crank's dead centre, below the pressure bound
                if not in_bounds(a, b, c, crank_reach(Jj), pressure_bound(P_B[j], Jj, Lj)):
                    bad = k
            if fixed and ps != ps_prev:
                fixed = False
            ps_prev = ps
        else:
            fixed = False
            ps = _rates(
                t, th, om, pp, TT, TY, NT, SINE, PM, kinds, pose, offsets, own_inertia, G,
                any_pose, pump_flow, p_relief, es, K[0, 0], K[0, 1], K[0, 2], comp, cs, CP,
                CK[0],
            )  # fmt: skip
            for j in range(nj):
                held[j, 0] = PM[j, J_SUPPLY]
                held[j, 1] = PM[j, L_TORQUE]
                held[j, 2] = PM[j, L_INERTIA]
                if comp[j]:
                    cheld[j, 0] = CP[j, P_FORCE]
                    cheld[j, 1] = CP[j, P_MASS]
            for s in range(1, 4):
                c = 0.5 * h if s < 3 else h
                for j in range(nj):
                    if comp[j]:
                        for i in range(ns):
                            cst[j, i] = cs[j, i] + c * CK[s - 1, j, i]
                        ths[j] = cst[j, S_Q]
                        oms[j] = cst[j, S_V]
                        pps[j] = pp[j]
                        continue
                    ths[j] = th[j] + c * K[s - 1, 0, j]
                    oms[j] = om[j] + c * K[s - 1, 1, j]
                    pps[j] = pp[j] + c * K[s - 1, 2, j]
                _rates(
                    t + c, ths, oms, pps, TT, TY, NT, SINE, PM, kinds, pose, offsets,
                    own_inertia, G, any_pose, pump_flow, p_relief, es, K[s, 0], K[s, 1], K[s, 2],
                    comp, cst, CP, CK[s],
                )  # fmt: skip
            w = h / 6.0
            for j in range(nj):
                PM[j, J_SUPPLY] = held[j, 0]
                PM[j, L_TORQUE] = held[j, 1]
                PM[j, L_INERTIA] = held[j, 2]
                Jj = joint_at(PM, j)
                if comp[j]:
                    CP[j, P_FORCE] = cheld[j, 0]
                    CP[j, P_MASS] = cheld[j, 1]
                    for i in range(ns):
                        cout[i] = cs[j, i] + w * (
                            CK[0, j, i] + 2.0 * CK[1, j, i] + 2.0 * CK[2, j, i] + CK[3, j, i]
                        )
                    cout[S_PS] = held[j, 0] + CP[j, P_P_TANK]
                    cs[j, S_PS] = cout[S_PS]
                    tr = _lever(t + h, TT, TY, NT, SINE, j)
                    servo_project(method, cs[j], cout, h, tr, CP[j])
                    cs[j] = cout
                    th[j], om[j], pp[j] = cout[S_Q], cout[S_V], _component_pressure(cout, CP[j])
                    if not _component_in_bounds(cout, crank_reach(Jj)):
                        bad = k
                    continue
                Lj = load_at(PM, j)
                a = th[j] + w * (K[0, 0, j] + 2.0 * K[1, 0, j] + 2.0 * K[2, 0, j] + K[3, 0, j])
                b = om[j] + w * (K[0, 1, j] + 2.0 * K[1, 1, j] + 2.0 * K[2, 1, j] + K[3, 1, j])
                c = pp[j] + w * (K[0, 2, j] + 2.0 * K[1, 2, j] + 2.0 * K[2, 2, j] + K[3, 2, j])
                # the single joint's projections after its smooth RK4 update (dry friction's
                # stick or slide, cavitation floor, end stops): one rule for both
                a, b, c = rk4_projections(h, th[j], om[j], a, b, c, Jj, Lj)
                th[j], om[j], pp[j] = a, b, c
                if not in_bounds(a, b, c, crank_reach(Jj), pressure_bound(P_B[j], Jj, Lj)):
                    bad = k
        if bad >= 0:
            break
        above = probe and th[stop_joint] + stop_offset > stop_angle
        # a probe at a fixed point: its later records would all repeat this state
        if k % record_every == 0 or (fixed and above and k <= last_record):
            tk = t0 + k * h
            T[rec] = tk
            for j in range(nj):
                TH[rec, j] = th[j]
                OM[rec, j] = om[j]
                PPr[rec, j] = pp[j]
                Y[rec, j] = _lever(tk, TT, TY, NT, SINE, j)
                if comp[j]:
                    CSR[rec, j] = cs[j]
            PS[rec] = ps
            rec += 1
            if above or fixed:
                break
        elif fixed:
            break
    nc = rec if any_comp else 1
    return T[:rec], TH[:rec], OM[:rec], PPr[:rec], Y[:rec], PS[:rec], bad, CSR[:nc]


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
        CS0[j] = component_initial_state(CP[j], th0[j], float(levers[j](0.0)[0]))
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


def simulate_decoupled(
    sc: ArmScenario, *, check_stability: bool = True, probe: tuple[str, float] | None = None
):
    """Run an `ArmScenario` on the decoupled arm model's own loop (`arm_integrate`: the
    diagonal pose inertia, the algebraic power pack); returns an `ArmResult`. No product
    path runs it: the arm runs on the system kernel
    (`hydroarm.arm.simulate_arm`); it stays, with `arm_integrate`, as
    the reference of `hydroarm.arm.stepper.ArmStepper` until that moves to the system
    kernel too.

    ``probe`` (joint name, articulation angle): the run stops once it is decided whether a
    recorded angle of that joint is above the angle (`arm_integrate`); the result then
    holds the records up to there only, with the full run's answer to that question."""
    if check_stability:
        sc.check_step()
    nj = len(sc.joints)
    k = kernel_inputs(sc)
    levers: list[LeverInput] = [sc.inputs[j.name] for j in sc.joints]
    code = registry.method(sc.method).code
    nsteps = int(round(sc.duration / sc.step))
    stop = (-1, 0.0, 0.0, math.inf)
    if probe is not None:
        settle = max(float(lv.times[-1]) for lv in levers)
        if any(float(lv.sine[0]) != 0.0 for lv in levers):
            settle = math.inf
        i = [aj.name for aj in sc.joints].index(probe[0])
        stop = (i, float(sc.joints[i].angle_offset), float(probe[1]), settle)
    t, th, om, pp, y, ps, bad, cstates = arm_integrate(
        code,
        k["TH0"],
        np.zeros(nj),
        k["PP0"],
        0.0,
        sc.step,
        nsteps,
        sc.record_every,
        k["TT"],
        k["TY"],
        k["NT"],
        k["SINE"],
        k["PM"],
        k["kinds"],
        k["pose"],
        k["offsets"],
        k["own_inertia"],
        k["G"],
        float(sc.power_pack.pump_flow),
        float(sc.power_pack.supply_pressure),
        k["comp"],
        k["CS0"],
        k["CP"],
        *stop,
    )
    if bad >= 0:
        raise HydroarmError(
            "solver.step",
            f"the run left the physical bounds at t = {bad * sc.step:.6g} s (a state non-finite, "
            "past a crank's dead centre or beyond the pressure bound): reduce the step",
        )
    return ArmResult(
        t=t,
        theta=th,
        omega=om,
        p=pp,
        y=y,
        supply_pressure=ps,
        scenario=sc,
        component_states=cstates if k["comp"].any() else None,
    )
