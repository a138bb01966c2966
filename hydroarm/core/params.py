"""Parameters of the compiled kernels.

The kernels take a joint and its load as two typed records that numba compiles (module-level
``typing.NamedTuple`` s, so that compiled functions taking them are cached on disk):

* `JointParams` — valve, jack, crank, gearbox and the physics options (options as
  integers and flags, not floats compared with a threshold);
* `LoadParams` — the load W, X, I and an extra gravity torque T (the whole arm gives
  its pose-dependent gravity torque through T, with W = X = 0);
* `ArmGeometryParams` — segment lengths and masses of the whole arm.

They are built by `joint_params`, `load_params` and `arm_geometry_params`
(or from the dataclasses of `hydroarm.model.joint` by ``Scenario.params``).

The batch engine runs many scenarios from one 2-D float64 table, one row per scenario; its
columns are named by the ``J_*`` (joint) and ``L_*`` (load) constants below and
`joint_at` / `load_at` build the records of a row inside compiled code.
`hydroarm.model.joint.pack` gives the row of a joint and load.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

STANDARD_GRAVITY = 9.80665  # g₀ [m/s²] (CGPM 1901): loads given as a mass, the arm's weights
HORIZONTAL_ANGLE = math.radians(30.0)  # θ_h of the paper's datum [rad]

# torque arm of the jack force at the joint (JointParams.torque_arm)
TORQUE_ARM_PAPER = 0  # eq. (3) as printed: A·p·r/n
TORQUE_ARM_KINEMATIC = 1  # consistent with eq. (4): A·p·r·cos(θ₂/n)/n
# valve model (JointParams.valve_model)
VALVE_LINEAR = 0  # eq. (1): linearised valve with leakage
VALVE_ORIFICE = 1  # critically-centred orifice valve (docs/physics.md, O1)


class JointParams(NamedTuple):
    """A hydraulic servo joint in SI units (fields as
    [`hydroarm.model.joint.ServoJoint`][hydroarm.ServoJoint])."""

    piston_area: float  # A [m²]
    flow_coefficient: float  # K [m² s⁻¹ Pa⁻¹ᐟ²]
    valve_saturation: float  # e_o [m]
    leakage_coefficient: float  # L [m³ s⁻¹ Pa⁻¹]
    trapped_volume: float  # V [m³]
    bulk_modulus: float  # β [Pa]
    supply_pressure: float  # p_s [Pa]
    crank_radius: float  # r [m]
    gear_ratio: float  # n [-]
    horizontal_angle: float  # θ_h [rad]
    torque_arm: int  # TORQUE_ARM_PAPER or TORQUE_ARM_KINEMATIC
    valve_model: int  # VALVE_LINEAR or VALVE_ORIFICE
    transition_pressure: float  # orifice regularisation pressure [Pa]
    atmospheric_pressure: float  # return (atmospheric) pressure [Pa], the cavitation floor
    coulomb_friction: float  # piston Coulomb (sliding) friction [N]
    breakaway_friction: float  # piston breakaway (stiction) force [N]
    viscous_friction: float  # piston viscous friction [N s/m]
    gearbox_friction_torque: float  # gearbox no-load friction torque at the joint [N m]
    gearbox_loss_at_stall: float  # gearbox loss fraction at full actuator load
    gearbox_loss_exponent: float  # exponent of the gearbox loss law
    end_stop_angle: float  # end-stop angle |θ₂| [rad] (inf: none)
    # rated supply pressure [Pa]: the gearbox load fraction γ = |p|/p_rated and the cavitation
    # floor; supply_pressure is the momentary one the valve sees (sagging on a whole arm's
    # pump), equal to it for a single joint
    rated_supply_pressure: float
    dry_friction: bool  # derived: breakaway, gearbox torque or gearbox loss is on
    null_leakage_coefficient: float  # valve leakage at null L₀ [m³ s⁻¹ Pa⁻¹] (option O6)


class LoadParams(NamedTuple):
    """The load on a joint: gravity torque W·X·cos(θ₂ − θ_h) + T, inertia I."""

    weight: float  # W [N]
    arm: float  # X [m]
    inertia: float  # I [kg m²]
    torque: float  # T [N m], gravity torque added to W·X·cos(θ₂ − θ_h) (the arm's pose load)


class ArmGeometryParams(NamedTuple):
    """Segment lengths [m], masses [kg] and gravity of the whole arm (docs/arm.md)."""

    upper_arm_length: float
    forearm_length: float
    hand_length: float
    upper_arm_mass: float
    upper_arm_com: float
    forearm_mass: float
    forearm_com: float
    hand_mass: float
    reach_shoulder_ratio: float
    gravity: float


def joint_params(
    piston_area,
    flow_coefficient,
    valve_saturation,
    leakage_coefficient,
    trapped_volume,
    bulk_modulus,
    supply_pressure,
    crank_radius,
    gear_ratio,
    horizontal_angle=HORIZONTAL_ANGLE,
    torque_arm=TORQUE_ARM_PAPER,
    valve_model=VALVE_LINEAR,
    transition_pressure=1.0e4,
    atmospheric_pressure=101325.0,
    coulomb_friction=0.0,
    breakaway_friction=None,
    viscous_friction=0.0,
    gearbox_friction_torque=0.0,
    gearbox_loss_at_stall=0.0,
    gearbox_loss_exponent=1.0,
    end_stop_angle=math.inf,
    rated_supply_pressure=None,
    null_leakage_coefficient=0.0,
) -> JointParams:
    """`JointParams` with every field of its kernel type (floats, int options) and the
    derived flag; ``breakaway_friction`` None: equal to the Coulomb friction;
    ``rated_supply_pressure`` None: equal to the supply pressure."""
    if breakaway_friction is None:
        breakaway_friction = coulomb_friction
    if end_stop_angle is None:
        end_stop_angle = math.inf
    if rated_supply_pressure is None:
        rated_supply_pressure = supply_pressure
    return JointParams(
        float(piston_area),
        float(flow_coefficient),
        float(valve_saturation),
        float(leakage_coefficient),
        float(trapped_volume),
        float(bulk_modulus),
        float(supply_pressure),
        float(crank_radius),
        float(gear_ratio),
        float(horizontal_angle),
        int(torque_arm),
        int(valve_model),
        float(transition_pressure),
        float(atmospheric_pressure),
        float(coulomb_friction),
        float(breakaway_friction),
        float(viscous_friction),
        float(gearbox_friction_torque),
        float(gearbox_loss_at_stall),
        float(gearbox_loss_exponent),
        float(end_stop_angle),
        float(rated_supply_pressure),
        bool(
            breakaway_friction > 0.0 or gearbox_friction_torque > 0.0 or gearbox_loss_at_stall > 0.0
        ),
        float(null_leakage_coefficient),
    )


def load_params(weight, arm, inertia, torque=0.0) -> LoadParams:
    """`LoadParams` with float fields."""
    return LoadParams(float(weight), float(arm), float(inertia), float(torque))


def arm_geometry_params(
    upper_arm_length,
    forearm_length,
    hand_length,
    upper_arm_mass,
    upper_arm_com,
    forearm_mass,
    forearm_com,
    hand_mass,
    reach_shoulder_ratio,
    gravity=STANDARD_GRAVITY,
) -> ArmGeometryParams:
    """`ArmGeometryParams` with float fields."""
    return ArmGeometryParams(
        float(upper_arm_length),
        float(forearm_length),
        float(hand_length),
        float(upper_arm_mass),
        float(upper_arm_com),
        float(forearm_mass),
        float(forearm_com),
        float(hand_mass),
        float(reach_shoulder_ratio),
        float(gravity),
    )


# Columns of the batch table (one row per scenario; pack() in hydroarm.model.joint).
J_AREA = 0
J_FLOW_COEFF = 1
J_E_SAT = 2
J_LEAK = 3
J_VOLUME = 4
J_BETA = 5
J_SUPPLY = 6
J_CRANK = 7
J_RATIO = 8
J_HORIZ = 9
J_TORQUE_ARM = 10  # TORQUE_ARM_* as a float
J_VALVE = 11  # VALVE_* as a float
J_P_TRANS = 12
J_P_ATM = 13
J_F_COULOMB = 14
J_F_STATIC = 15  # breakaway force
J_VISCOUS = 16
J_GB_T0 = 17
J_GB_LOSS = 18
J_GB_EXP = 19
J_STOP = 20
L_WEIGHT = 21
L_ARM = 22
L_INERTIA = 23
L_TORQUE = 24
J_RATED = 25  # rated supply pressure (JointParams.rated_supply_pressure)
J_NULL_LEAK = 26  # valve leakage at null (option O6)
N_ROW = 27

# Columns that switch physics beyond the paper on; a row with all of them 0 runs the paper's
# physics (the batch engine compiles such blocks with these columns as constants).
OPTION_COLUMNS = (
    J_TORQUE_ARM,
    J_VALVE,
    J_F_COULOMB,
    J_F_STATIC,
    J_VISCOUS,
    J_GB_T0,
    J_GB_LOSS,
    L_TORQUE,
    J_NULL_LEAK,
)


@njit(inline="always", error_model="numpy")
def joint_from_columns(
    area,
    flow_coefficient,
    e_sat,
    leak,
    volume,
    beta,
    supply,
    crank,
    ratio,
    horiz,
    torque_arm,
    valve,
    p_trans,
    p_atm,
    f_coulomb,
    f_static,
    viscous,
    gb_t0,
    gb_loss,
    gb_exp,
    stop,
    rated,
    null_leak,
):
    """`JointParams` from the table's joint columns, in order (floats; the option
    columns are converted to their integer codes and the dry-friction flag derived)."""
    return JointParams(
        area,
        flow_coefficient,
        e_sat,
        leak,
        volume,
        beta,
        supply,
        crank,
        ratio,
        horiz,
        int(torque_arm),
        int(valve),
        p_trans,
        p_atm,
        f_coulomb,
        f_static,
        viscous,
        gb_t0,
        gb_loss,
        gb_exp,
        stop,
        rated,
        (f_static > 0.0) | (gb_t0 > 0.0) | (gb_loss > 0.0),
        null_leak,
    )


@njit(cache=True, nogil=True, error_model="numpy")
def joint_at(table, row):
    """`JointParams` of one row of a batch table (read in place: a row view would
    cost an atomic reference-count pair per call in the kernels' inner loops)."""
    return joint_from_columns(
        table[row, J_AREA],
        table[row, J_FLOW_COEFF],
        table[row, J_E_SAT],
        table[row, J_LEAK],
        table[row, J_VOLUME],
        table[row, J_BETA],
        table[row, J_SUPPLY],
        table[row, J_CRANK],
        table[row, J_RATIO],
        table[row, J_HORIZ],
        table[row, J_TORQUE_ARM],
        table[row, J_VALVE],
        table[row, J_P_TRANS],
        table[row, J_P_ATM],
        table[row, J_F_COULOMB],
        table[row, J_F_STATIC],
        table[row, J_VISCOUS],
        table[row, J_GB_T0],
        table[row, J_GB_LOSS],
        table[row, J_GB_EXP],
        table[row, J_STOP],
        table[row, J_RATED],
        table[row, J_NULL_LEAK],
    )


@njit(cache=True, nogil=True, error_model="numpy")
def load_at(table, row):
    """`LoadParams` of one row of a batch table (read in place)."""
    return LoadParams(
        table[row, L_WEIGHT], table[row, L_ARM], table[row, L_INERTIA], table[row, L_TORQUE]
    )
