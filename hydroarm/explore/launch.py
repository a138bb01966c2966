"""Starting ``hydroarm explore``: the arm or the system it shows (``--config``: an arm file,
or any system file: `system`), the checks made before the server starts, the server
itself (NiceGUI: the optional ``explore`` extra, imported when the page is built)."""

from __future__ import annotations

import errno
import socket
from importlib import resources
from pathlib import Path

from ..arm import ArmScenario, load_arm, load_arm_text
from ..errors import HydroarmError
from ..files import check_output_folder
from ..io.sections import read_toml_file
from . import app, system_app
from .joint import JointExplorer
from .live import LiveArm
from .system import NOT_A_SYSTEM, SystemModel, is_arm_doc, is_explorable

HOST = "127.0.0.1"  # the app listens on the loopback interface unless --host says otherwise
DEFAULT_PORT = 8050


def default_arm() -> ArmScenario:
    """The arm shown without ``--config``: examples/ucl-arm.toml's arm with its levers held
    (packaged as ``hydroarm/data/explore-arm.toml``)."""
    text = resources.files("hydroarm.data").joinpath("explore-arm.toml").read_text("utf-8")
    return load_arm_text(text, source="explore-arm.toml")


def explore_arm(config=None) -> ArmScenario:
    """The arm file ``config`` (its joints, geometry, power pack, initial angles and solver;
    its inputs are not used: the levers are live), or `default_arm`."""
    return default_arm() if config is None else load_arm(config)


def explore_target(config=None, progress=None) -> ArmScenario | SystemModel:
    """What ``--config`` names: an arm file (``[joints]``: `explore_arm`'s page) or any
    system file (a circuit, a mechanism, a component servo, a reference file or a study
    naming one: the system page, its `SystemModel` read, checked and run
    once here); without it
    `default_arm`. Anything else is refused with one line."""
    if config is None:
        return default_arm()
    doc, p = read_toml_file(config)
    if is_explorable(doc):
        if progress is not None:
            progress(f"reading and running {p.name} (the kernels may compile on a first run)")
        return SystemModel(doc, p)
    if is_arm_doc(doc):
        return load_arm(config)
    raise HydroarmError("--config", f"{p.name}: {NOT_A_SYSTEM}")


def check_nicegui() -> None:
    """Refuse to start without NiceGUI (the optional explore extra)."""
    try:
        import nicegui  # noqa: F401  (the optional explore extra)
    except ImportError:
        raise HydroarmError(
            "explore", 'needs NiceGUI, not installed: pip install "hydroarm[explore]"'
        ) from None


def check_port(port: int, host: str = HOST) -> None:
    """Refuse a port that cannot be listened on (in use, not allowed) before starting."""
    if not 1 <= port <= 65535:
        raise HydroarmError("--port", f"must be between 1 and 65535, got {port}")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            why = (
                "is in use" if exc.errno == errno.EADDRINUSE else f"cannot be used ({exc.strerror})"
            )
            raise HydroarmError("--port", f"{host}:{port} {why}: choose another port") from None


def check(scenario: ArmScenario, port: int, out_dir, progress=None, host: str = HOST) -> Path:
    """Everything checked before the server starts: the port, the folder for recorded
    attempts, the arm (a live arm built and stepped once, the single joint run once).
    ``progress(label)`` is told of each stage (the kernels may compile on a first run).
    Returns the output folder."""
    tick = progress or (lambda label: None)
    check_nicegui()
    check_port(port, host)
    out = check_output_folder("--out", out_dir)
    live = LiveArm(scenario)
    live.tick(0.01)
    tick("the live arm stepped")
    JointExplorer()
    tick("the single joint run")
    return out


def check_system(port: int, host: str = HOST) -> None:
    """The checks before a system page's server starts (its file was read and run by
    `explore_target`): NiceGUI and the port."""
    check_nicegui()
    check_port(port, host)


def check_host(host: str) -> str:
    """Refuse a ``--host`` that is not an address of this machine (it cannot be listened on)."""
    if not host or any(c.isspace() for c in host) or len(host) > 253:
        raise HydroarmError("--host", f"must be a host name or address, got {host!r}")
    try:
        socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_STREAM)
    except (OSError, UnicodeError):
        raise HydroarmError("--host", f"{host!r} is not an address of this machine") from None
    return host


def serve(
    scenario: ArmScenario,
    *,
    port: int,
    show: bool,
    out_dir: Path,
    host: str = HOST,
    token: str | None = None,
) -> None:
    """Serve the app on ``host``:``port`` until interrupted (Ctrl-C)."""
    app.serve(scenario, port=port, show=show, out_dir=out_dir, host=host, token=token)


def serve_system(
    model: SystemModel, *, port: int, show: bool, host: str = HOST, token: str | None = None
) -> None:
    """Serve the system page on ``host``:``port`` until interrupted (Ctrl-C)."""
    system_app.serve(model, port=port, show=show, host=host, token=token)
