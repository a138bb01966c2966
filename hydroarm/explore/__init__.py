"""``hydroarm explore``: the arm live in a browser (docs/explore.md).

The state of each view is a plain class, testable without a browser:
:class:`~.joint.JointExplorer` (the single joint), :class:`~.live.LiveArm` (the live arm and
its levers), :class:`~.blocks.StackingTask` (the block-stacking task); :mod:`.app` draws them
with NiceGUI, imported only when the server starts (:func:`~.launch.serve`)."""

from .blocks import StackingTask
from .joint import JointExplorer, JointSettings
from .launch import DEFAULT_PORT, HOST, check, default_arm, explore_arm, serve
from .live import KEYS, LiveArm

__all__ = [
    "DEFAULT_PORT",
    "HOST",
    "KEYS",
    "JointExplorer",
    "JointSettings",
    "LiveArm",
    "StackingTask",
    "check",
    "default_arm",
    "explore_arm",
    "serve",
]
