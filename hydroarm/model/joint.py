"""Data that describe a hydraulic servo joint and its load, in SI units.

A joint is *data*, not code: any hydraulic servo driven articulation with a valve, a jack,
a crank and a gearbox is described by a [`ServoJoint`][hydroarm.ServoJoint] and a
[`Load`][hydroarm.Load]. The paper's shoulder elevation (Appendix I of the UCL arm paper) is the
first built-in configuration (see `hydroarm.scenarios.paper`).

Glossary (paper symbol -> field): A piston_area, K flow_coefficient, e_o valve_saturation,
L leakage_coefficient, V trapped_volume, β bulk_modulus, p_s supply_pressure, r crank_radius,
n gear_ratio, W weight, X arm (centre-of-mass distance), I inertia.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from ..core.kinematics import crank_angle, crank_torque_arm
from ..core.params import (
    J_AREA,
    J_BETA,
    J_CRANK,
    J_E_SAT,
    J_F_COULOMB,
    J_F_STATIC,
    J_FLOW_COEFF,
    J_GB_EXP,
    J_GB_LOSS,
    J_GB_T0,
    J_HORIZ,
    J_LEAK,
    J_NULL_LEAK,
    J_P_ATM,
    J_P_TRANS,
    J_RATED,
    J_RATIO,
    J_STOP,
    J_SUPPLY,
    J_TORQUE_ARM,
    J_VALVE,
    J_VISCOUS,
    J_VOLUME,
    L_ARM,
    L_INERTIA,
    L_TORQUE,
    L_WEIGHT,
    N_ROW,
    TORQUE_ARM_KINEMATIC,
    TORQUE_ARM_PAPER,
    JointParams,
    LoadParams,
    joint_params,
    load_params,
)
from ..errors import HydroarmError
from .quantities import plain
from .rules import FIELD_RULES, check_object

VALVE_MODELS = ("linear", "orifice")  # index: the VALVE_* code of hydroarm.core.params
TORQUE_ARMS = {"paper": TORQUE_ARM_PAPER, "kinematic": TORQUE_ARM_KINEMATIC}


@dataclass(frozen=True)
class ServoJoint:
    """A valve-controlled jack driving an articulation through a crank and gearbox.

    Parameters
    ----------
    piston_area : float
        Jack piston area A [m²].
    flow_coefficient : float
        Valve flow coefficient K [m² s⁻¹ Pa⁻¹ᐟ²]: flow per unit valve opening per root
        pressure. The flow gain is K_q = K·√(p_s/2) [m²/s] (reading of eq. (1), docs/model.md).
    valve_saturation : float
        Full valve opening e_o [m]; the error e = y − x saturates at ±e_o (eq. (2)).
    leakage_coefficient : float
        Leakage coefficient L [m³ s⁻¹ Pa⁻¹]; leakage flow is 2·L·p (eq. (1)).
    trapped_volume : float
        Oil volume V [m³] in the compressibility term (V/β)·ṗ of eq. (1).
    bulk_modulus : float
        Oil bulk modulus β [Pa].
    supply_pressure : float
        Supply pressure p_s [Pa].
    crank_radius : float
        Crank radius r [m].
    gear_ratio : float
        Gearbox ratio n [-]; θ₂ = n·asin(x/r) (eq. (4)).
    horizontal_angle : float
        Joint angle θ₂ [rad] at which the load arm is horizontal (30° in the paper's datum).
    torque_arm : str
        ``"paper"``: jack torque A·p·r/n as eq. (3) prints it; ``"kinematic"``: A·p·r·cos(θ₂/n)/n,
        the torque arm consistent with eq. (4) (virtual work).
    name : str
        Label.
    valve_model : str
        ``"linear"``: eq. (1) of the paper; ``"orifice"``: critically-centred 4-way valve with
        square-root flow per metering edge, Q = K·e·√((p_s − sgn(e)·p)/2).
    transition_pressure : float
        Pressure drop [Pa] below which the orifice's √Δp is regularised to a linear law.
    atmospheric_pressure : float
        Return-line absolute pressure [Pa]; no chamber may fall below zero absolute pressure
        (cavitation floor), so |p| ≤ p_s + 2·p_atm with the orifice valve.
    coulomb_friction : float
        Sliding friction force at the piston [N] (paper: 18 N).
    static_friction : float or None
        Breakaway (stiction) force at the piston [N] (paper: 30 N); None: equal to Coulomb.
    viscous_friction : float
        Viscous friction coefficient at the piston [N s/m].
    gearbox_friction_torque : float
        Load-independent gearbox/linkage friction torque at the joint [N m].
    gearbox_loss_at_stall : float
        Fraction of the actuator torque lost in the gearbox at full load (γ = 1) [-].
    gearbox_loss_exponent : float
        Exponent k of the load-dependent loss c(γ) = c_stall·γᵏ [-].
    end_stop_angle : float or None
        Joint angle |θ₂| [rad] of the jack's end stops (inelastic); None: no stops.
    backlash : float
        Total gearbox backlash at the joint [rad] (play operator on the output angle).
    null_leakage_coefficient : float
        Valve leakage at null L₀ [m³ s⁻¹ Pa⁻¹]: a flow 2·L₀·p·(1 − (e/e_o)²) across the
        valve, the null flow-pressure coefficient K_c0 = 2·L₀ of a real critically-centred
        spool, fading to none at full opening (docs/physics.md, O6).

    Notes
    -----
    The physics options, ``valve_model`` to ``null_leakage_coefficient``, are all off by
    default: the paper's model. Their equations are in docs/physics.md.
    """

    piston_area: float
    flow_coefficient: float
    valve_saturation: float
    leakage_coefficient: float
    trapped_volume: float
    bulk_modulus: float
    supply_pressure: float
    crank_radius: float
    gear_ratio: float
    horizontal_angle: float = math.radians(30.0)
    torque_arm: str = "paper"
    name: str = "joint"
    valve_model: str = "linear"
    transition_pressure: float = 1.0e4
    atmospheric_pressure: float = 101325.0
    coulomb_friction: float = 0.0
    static_friction: float | None = None
    viscous_friction: float = 0.0
    gearbox_friction_torque: float = 0.0
    gearbox_loss_at_stall: float = 0.0
    gearbox_loss_exponent: float = 1.0
    end_stop_angle: float | None = None
    backlash: float = 0.0
    null_leakage_coefficient: float = 0.0

    def __post_init__(self):
        # sign and cross-field rules: hydroarm.model.rules (shared with files and sweeps)
        check_object(self, _JOINT_RULE_FIELDS)
        if self.torque_arm not in ("paper", "kinematic"):
            raise HydroarmError(
                "joint.torque_arm", f"must be 'paper' or 'kinematic', got {self.torque_arm!r}"
            )
        if self.valve_model not in VALVE_MODELS:
            raise HydroarmError(
                "physics.valve_model", f"must be 'linear' or 'orifice', got {self.valve_model!r}"
            )

    # --- derived quantities -------------------------------------------------------------
    @property
    def flow_gain(self) -> float:
        """Valve flow gain K_q = K·√(p_s/2) [m²/s]."""
        return self.flow_coefficient * math.sqrt(self.supply_pressure / 2.0)

    @property
    def no_load_time_constant(self) -> float:
        """Standard-formula no-load time constant τ = A/K_q [s] (paper: 23 ms)."""
        return self.piston_area / self.flow_gain

    @property
    def no_load_velocity(self) -> float:
        """Saturated no-load jack velocity K_q·e_o/A [m/s]."""
        return self.flow_gain * self.valve_saturation / self.piston_area

    @property
    def stall_force(self) -> float:
        """Theoretical stall force A·p_s [N] (paper: 0.94 kN)."""
        return self.piston_area * self.supply_pressure

    @property
    def stall_torque(self) -> float:
        """Theoretical stall torque at the joint A·p_s·r/n [N m] (paper: 9.4 N m)."""
        return self.stall_force * self.crank_radius / self.gear_ratio

    @property
    def hydraulic_stiffness(self) -> float:
        """β·A²/V [N/m], the oil-column spring (the paper's λ_o reading)."""
        return self.bulk_modulus * self.piston_area**2 / self.trapped_volume

    @property
    def max_angle(self) -> float:
        """|θ₂| at full crank stroke x = ±r [rad]."""
        return self.gear_ratio * math.pi / 2.0

    @property
    def breakaway_friction(self) -> float:
        """Piston breakaway force [N] (static friction, or Coulomb when none is given)."""
        return self.coulomb_friction if self.static_friction is None else self.static_friction

    @property
    def has_dry_friction(self) -> bool:
        return (
            self.breakaway_friction > 0
            or self.gearbox_friction_torque > 0
            or self.gearbox_loss_at_stall > 0
        )

    @property
    def is_paper_model(self) -> bool:
        """True when no physics option beyond the paper's model is switched on."""
        return (
            self.valve_model == "linear"
            and not self.has_dry_friction
            and self.viscous_friction == 0
            and self.end_stop_angle is None
            and self.backlash == 0
            and self.null_leakage_coefficient == 0
        )

    def gearbox_efficiency(self, gamma, theta: float | None = None):
        """Gearbox torque efficiency η = 1 − c_stall·γᵏ − T_g0/T_act when the actuator drives.

        ``gamma`` is the actuator force as a fraction of its stall force A·p_s (the paper's
        γ = W_in/940 of Fig. 6). ``theta`` sets the crank's torque arm (default: θ₂ = 0).
        """
        g = np.asarray(gamma, dtype=float)
        th = 0.0 if theta is None else theta
        lever = crank_torque_arm(
            th, self.crank_radius, self.gear_ratio, self.torque_arm == "kinematic"
        )
        t_act = g * self.stall_force * lever
        with np.errstate(divide="ignore", invalid="ignore"):
            eta = (
                1.0
                - self.gearbox_loss_at_stall * g**self.gearbox_loss_exponent
                - np.where(t_act > 0, self.gearbox_friction_torque / t_act, np.inf)
            )
        return np.maximum(eta, 0.0)

    def jack_position(self, theta: float) -> float:
        """x = r·sin(θ₂/n) [m] (eq. (4))."""
        # libm's sin of θ/n, as before the kernels' kinematics moved to core.kinematics:
        # crank_position (inlined fdlibm sin of θ·(1/n)) differs in the last bit for some
        # angles (e.g. ±57°), and this sets the lever positions of scenario files
        return self.crank_radius * math.sin(theta / self.gear_ratio)

    def joint_angle(self, x: float) -> float:
        """θ₂ = n·asin(x/r) [rad] (eq. (4))."""
        if abs(x) > self.crank_radius:
            raise HydroarmError(
                "position",
                f"jack position {x * 1e3:g} mm is beyond the crank "
                f"radius {self.crank_radius * 1e3:g} mm",
            )
        return crank_angle(x, self.crank_radius, self.gear_ratio)

    def params(self) -> JointParams:
        """The joint as the compiled kernels take it."""
        return joint_params(
            self.piston_area,
            self.flow_coefficient,
            self.valve_saturation,
            self.leakage_coefficient,
            self.trapped_volume,
            self.bulk_modulus,
            self.supply_pressure,
            self.crank_radius,
            self.gear_ratio,
            self.horizontal_angle,
            TORQUE_ARMS[self.torque_arm],
            VALVE_MODELS.index(self.valve_model),
            self.transition_pressure,
            self.atmospheric_pressure,
            self.coulomb_friction,
            self.breakaway_friction,
            self.viscous_friction,
            self.gearbox_friction_torque,
            self.gearbox_loss_at_stall,
            self.gearbox_loss_exponent,
            math.inf if self.end_stop_angle is None else self.end_stop_angle,
            rated_supply_pressure=self.supply_pressure,
            null_leakage_coefficient=self.null_leakage_coefficient,
        )

    def replace(self, **changes) -> ServoJoint:
        """A copy with fields changed: numbers in SI, or pint quantities (converted to the
        field's SI unit; one of another dimension is refused)."""
        changes = {k: plain(f"joint.{k}", v, JOINT_UNITS.get(k, "-")) for k, v in changes.items()}
        return replace(self, **changes)

    def as_dict(self) -> dict:
        return asdict(self)


# each numeric field's SI unit (the class docstring's), for pint quantities in replace()
JOINT_UNITS = {
    "piston_area": "m²",
    "flow_coefficient": "m² s⁻¹ Pa⁻¹ᐟ²",
    "valve_saturation": "m",
    "leakage_coefficient": "m³/(s Pa)",
    "trapped_volume": "m³",
    "bulk_modulus": "Pa",
    "supply_pressure": "Pa",
    "crank_radius": "m",
    "gear_ratio": "-",
    "horizontal_angle": "rad",
    "transition_pressure": "Pa",
    "atmospheric_pressure": "Pa",
    "coulomb_friction": "N",
    "static_friction": "N",
    "viscous_friction": "N s/m",
    "gearbox_friction_torque": "N m",
    "gearbox_loss_at_stall": "-",
    "gearbox_loss_exponent": "-",
    "end_stop_angle": "rad",
    "backlash": "rad",
    "null_leakage_coefficient": "m³/(s Pa)",
}

_JOINT_RULE_FIELDS = tuple(
    k
    for k, (section, _) in FIELD_RULES.items()
    if section in ("joint", "physics")
    if k != "hydraulic_stiffness"
)


@dataclass(frozen=True)
class Load:
    """Gravity and inertia load on a joint (the paper's W, X, I).

    Parameters
    ----------
    weight : float
        Load weight W [N].
    arm : float
        Distance X [m] of the load's centre of mass from the joint axis.
    inertia : float
        Moment of inertia I [kg m²] about the joint axis (the paper gives N mm s²).
    name : str
        Label (``"load 6"``).
    """

    weight: float
    arm: float
    inertia: float
    name: str = "load"

    def __post_init__(self):
        check_object(self, ("weight", "arm", "inertia"))

    @property
    def gravity_torque(self) -> float:
        """Largest gravity torque W·X [N m] (arm horizontal)."""
        return self.weight * self.arm

    def params(self) -> LoadParams:
        """The load as the compiled kernels take it."""
        return load_params(self.weight, self.arm, self.inertia)


def pack(joint: ServoJoint, load: Load) -> np.ndarray:
    """A joint and load as one row of the batch table (columns ``J_*``, ``L_*`` of
    `hydroarm.core.params`; `joint_at` and
    `load_at` read it back)."""
    J = joint.params()
    L = load.params()
    row = np.zeros(N_ROW)
    row[J_AREA] = J.piston_area
    row[J_FLOW_COEFF] = J.flow_coefficient
    row[J_E_SAT] = J.valve_saturation
    row[J_LEAK] = J.leakage_coefficient
    row[J_VOLUME] = J.trapped_volume
    row[J_BETA] = J.bulk_modulus
    row[J_SUPPLY] = J.supply_pressure
    row[J_CRANK] = J.crank_radius
    row[J_RATIO] = J.gear_ratio
    row[J_HORIZ] = J.horizontal_angle
    row[J_TORQUE_ARM] = J.torque_arm
    row[J_VALVE] = J.valve_model
    row[J_P_TRANS] = J.transition_pressure
    row[J_P_ATM] = J.atmospheric_pressure
    row[J_F_COULOMB] = J.coulomb_friction
    row[J_F_STATIC] = J.breakaway_friction
    row[J_VISCOUS] = J.viscous_friction
    row[J_GB_T0] = J.gearbox_friction_torque
    row[J_GB_LOSS] = J.gearbox_loss_at_stall
    row[J_GB_EXP] = J.gearbox_loss_exponent
    row[J_STOP] = J.end_stop_angle
    row[J_RATED] = J.rated_supply_pressure
    row[L_WEIGHT] = L.weight
    row[L_ARM] = L.arm
    row[L_INERTIA] = L.inertia
    row[L_TORQUE] = L.torque
    row[J_NULL_LEAK] = J.null_leakage_coefficient
    return row
