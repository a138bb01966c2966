"""``hydroarm explore``: the arm live in a browser (docs/explore.md).

The state of each view is a plain class, testable without a browser:
:class:`~.joint.JointExplorer` (the single joint), :class:`~.live.LiveArm` (the live arm and
its levers), :class:`~.blocks.StackingTask` (the block-stacking task), and for any system file
:class:`~.system.SystemModel` (the file read, checked and run once, shared) and
:class:`~.system.SystemExplorer` (one visitor's sliders, outputs and runs) and, for a
mechanism, :class:`~.live_system.LiveSystem` (its levers live); :mod:`.app` and
:mod:`.system_app` draw them with NiceGUI, imported only when the server starts
(:func:`~.launch.serve`, :func:`~.launch.serve_system`), behind the guard of :mod:`.pages`
(who may connect, what a page may send)."""

from .blocks import StackingTask
from .joint import JointExplorer, JointSettings
from .launch import DEFAULT_PORT, HOST, check, default_arm, explore_arm, explore_target, serve
from .live import KEYS, LiveArm
from .live_system import LiveSystem
from .system import SystemExplorer, SystemModel, load_system_model

__all__ = [
    "DEFAULT_PORT",
    "HOST",
    "KEYS",
    "JointExplorer",
    "JointSettings",
    "LiveArm",
    "LiveSystem",
    "StackingTask",
    "SystemExplorer",
    "SystemModel",
    "check",
    "default_arm",
    "explore_arm",
    "explore_target",
    "load_system_model",
    "serve",
]
