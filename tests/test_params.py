"""Typed kernel parameters and the crank kinematics (hydroarm.core.params, core.kinematics)."""

import math

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.core import params as kp
from hydroarm.core.equations import gravity_torque, holding_pressure
from hydroarm.core.kinematics import (
    crank_angle,
    crank_angle_trace,
    crank_position,
    crank_position_trace,
    crank_torque_arm,
    crank_velocity,
)
from hydroarm.io.catalog import paper_load
from hydroarm.model.joint import pack


@pytest.mark.parametrize("options", [False, True])
def test_params_match_the_table_row(options):
    joint = ha.parameter_set("paper-calibrated")
    if options:
        joint = joint.replace(
            torque_arm="kinematic",
            valve_model="orifice",
            coulomb_friction=18.0,
            static_friction=30.0,
            viscous_friction=5.0,
            gearbox_friction_torque=0.3,
            gearbox_loss_at_stall=0.4,
            gearbox_loss_exponent=6.0,
            end_stop_angle=math.radians(80.0),
        )
    load = paper_load(6)
    J, L = joint.params(), load.params()
    row = pack(joint, load)
    assert row.shape == (kp.N_ROW,)
    table = np.vstack([row, row])
    assert kp.joint_at(table, 1) == J
    assert kp.load_at(table, 1) == L
    assert isinstance(J, kp.JointParams) and isinstance(L, kp.LoadParams)
    # field by field against the dataclasses, and the option codes as integers
    assert J.piston_area == joint.piston_area == row[kp.J_AREA]
    assert J.gear_ratio == joint.gear_ratio == row[kp.J_RATIO]
    assert J.horizontal_angle == row[kp.J_HORIZ]
    assert L == kp.LoadParams(load.weight, load.arm, load.inertia, 0.0)
    assert row[kp.L_WEIGHT] == load.weight and row[kp.L_INERTIA] == load.inertia
    assert isinstance(J.torque_arm, int) and isinstance(J.valve_model, int)
    if options:
        assert J.torque_arm == kp.TORQUE_ARM_KINEMATIC and J.valve_model == kp.VALVE_ORIFICE
        assert J.breakaway_friction == 30.0 and J.dry_friction
        assert J.end_stop_angle == math.radians(80.0)
    else:
        assert J.torque_arm == kp.TORQUE_ARM_PAPER and J.valve_model == kp.VALVE_LINEAR
        assert not J.dry_friction and J.end_stop_angle == math.inf
        assert all(row[c] == 0.0 for c in kp.OPTION_COLUMNS)
    # the keyword constructor gives the same record
    assert (
        kp.joint_params(**{f: getattr(J, f) for f in kp.JointParams._fields if f != "dry_friction"})
        == J
    )
    assert kp.load_params(load.weight, load.arm, load.inertia) == L


def test_crank_kinematics_round_trip():
    r, n = 0.02, 2.0
    theta = np.linspace(-0.95, 0.95, 201) * n * math.pi / 2
    x = crank_position_trace(theta, r, n)
    back = crank_angle_trace(x, r, n)
    np.testing.assert_allclose(back, theta, rtol=0, atol=1e-12)
    for th in theta[::20]:
        x1 = crank_position(th, r, n)
        assert crank_angle(x1, r, n) == pytest.approx(th, abs=1e-12)
        assert x1 == pytest.approx(r * math.sin(th / n), rel=1e-15, abs=1e-18)
        # ẋ = dx/dθ·ω
        d = 1e-6
        slope = (crank_position(th + d, r, n) - crank_position(th - d, r, n)) / (2 * d)
        assert crank_velocity(th, 3.0, r, n) == pytest.approx(3.0 * slope, rel=1e-7)
        # torque arm: r/n (paper) or the kinematic r·cos(θ/n)/n = dx/dθ (virtual work)
        assert crank_torque_arm(th, r, n, False) == r / n
        assert crank_torque_arm(th, r, n, True) == pytest.approx(slope, rel=1e-7)


def test_crank_angle_clips_to_the_reach():
    r, n = 0.02, 2.0
    assert crank_angle(2 * r, r, n) == n * math.pi / 2
    assert crank_angle(-2 * r, r, n) == -n * math.pi / 2
    assert crank_angle(2 * r, r, n, 0.999) == n * math.asin(0.999 * r / r)
    np.testing.assert_array_equal(
        crank_angle_trace(np.array([-1.0, 0.5 * r, 1.0]), r, n),
        [-n * math.pi / 2, n * math.asin(0.5), n * math.pi / 2],
    )


def test_load_torque_adds_to_gravity():
    J = ha.parameter_set("paper-calibrated").params()
    L = kp.load_params(10.0, 0.2, 0.01)
    th = 0.3
    g = gravity_torque(th, J, L)
    assert g == pytest.approx(10.0 * 0.2 * math.cos(th - J.horizontal_angle), rel=1e-15)
    assert gravity_torque(th, J, L._replace(torque=1.5)) == pytest.approx(g + 1.5, rel=1e-15)
    pose = kp.load_params(0.0, 0.0, 0.01, torque=2.0)
    assert gravity_torque(th, J, pose) == 2.0
    assert holding_pressure(th, J, pose) == pytest.approx(
        2.0 / (J.piston_area * J.crank_radius / J.gear_ratio), rel=1e-15
    )
