"""The whole UCL arm: four hydraulic servo joints, shared power pack, 3-D kinematics."""

from .config import load_arm, load_arm_text
from .model import (
    JOINT_NAMES,
    ArmGeometry,
    ArmJoint,
    ArmScenario,
    PowerPack,
    arm_points,
    simulate_arm,
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
