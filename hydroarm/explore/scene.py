"""What the two 3-D views (the UCL arm's live tab and a mechanism's live panel) share: the
rotation that lays a three.js cylinder along a link, a link placed between two points, and
the record of what each scene object shows, so that only changes go to the browser."""

from __future__ import annotations

import math

import numpy as np

UP = np.array([0.0, 0.0, 1.0])  # world z: the direction a zero-length link is drawn along


def link_frame(d: np.ndarray, up: np.ndarray = UP, roll: float = 0.0) -> list[list[float]]:
    """A rotation matrix taking the local y axis (a three.js cylinder's axis) to the direction
    of ``d`` (``up`` where ``d`` has no length), turned by ``roll`` [rad] about it."""
    n = float(np.linalg.norm(d))
    y = np.asarray(d, dtype=float) / n if n > 1e-12 else np.asarray(up, dtype=float)
    ref = np.array([0.0, 0.0, 1.0]) if abs(y[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(y, ref)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    if roll:
        c, s = math.cos(roll), math.sin(roll)
        x, z = c * x + s * z, -s * x + c * z
    return np.column_stack([x, y, z]).tolist()


def place_link(obj, a: np.ndarray, b: np.ndarray, up: np.ndarray = UP) -> None:
    """Move, turn and stretch a unit-length cylinder ``obj`` to run from point ``a`` to ``b``
    [m]."""
    d = b - a
    obj.move(*((a + b) / 2).tolist())
    obj.rotate_R(link_frame(d, up))
    obj.scale(1.0, max(float(np.linalg.norm(d)), 1e-6), 1.0)


class Shown:
    """What each scene object last got, rounded to ``digits`` decimals: `changed` says
    whether a new value differs (and records it), so a frame sends only what moved."""

    def __init__(self, digits: int) -> None:
        self.digits = digits
        self.values: dict = {}

    def changed(self, key, value) -> bool:
        v = tuple(round(float(x), self.digits) for x in value)
        if self.values.get(key) == v:
            return False
        self.values[key] = v
        return True
