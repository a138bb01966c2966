"""The whole UCL arm: four hydraulic servo joints, shared power pack, 3-D kinematics; run as
one mechanism on the system kernel (`simulate_arm`, `hydroarm.arm.expand`)."""

from ..core.arm_kinematics import JOINT_NAMES, arm_points
from .config import load_arm, load_arm_text
from .expand import simulate_arm
from .model import (
    ArmGeometry,
    ArmJoint,
    ArmScenario,
    PowerPack,
)
from .result import ArmResult

__all__ = [
    "JOINT_NAMES",
    "ArmGeometry",
    "ArmJoint",
    "ArmResult",
    "ArmScenario",
    "PowerPack",
    "arm_points",
    "load_arm",
    "load_arm_text",
    "simulate_arm",
]
