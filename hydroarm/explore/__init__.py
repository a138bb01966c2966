"""``hydroarm explore``: the arm live in a browser (docs/explore.md).

The state of each view is a plain class, testable without a browser:
`JointExplorer` (the single joint), `LiveArm` (the live arm and
its levers), `StackingTask` (the block-stacking task), and for any system file
`SystemModel` (the file read, checked and run once, shared) and
`SystemExplorer` (one visitor's sliders, outputs and runs) and, for a
mechanism, `LiveSystem` (its levers live); `app` and
`system_app` draw them with NiceGUI, imported only when the server starts
(`serve`, `serve_system`), behind the guard of `pages`
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
