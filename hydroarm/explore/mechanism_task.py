"""The block task of a mechanism file (issue 32; docs/explore.md "A mechanism's block task").

A mechanism file's optional ``[block_task]`` (read by ``hydroarm explore`` only; the other
commands accept the section and leave it alone), the arm file's section (docs/evaluate.md)
with its ``pick`` and ``place`` poses, for any mechanism::

    [block_task]
    hand = "bucket"                  # the link the load is carried by
    payload = "soil"                 # a [[mechanism.payload]] of the file: the load ...
    # mass = "2 kg"                  # ... or a load of its own (with point, optional)
    # point = ["0.1 m", "0 m", "0 m"]  # where it sits on the hand link (default: its origin)
    tip = ["1.5 m", "0 m", "0 m"]    # the hand's tip on the hand link: what the floor stops
    table = "-2.3 m"                 # the floor's (table top's) height along up [m]
    size = "1 m"                     # the load's edge (a cube)
    pick = { boom = "0 deg", stick = "-80 deg", bucket = "-60 deg" }   # the load under the tip
    place = { boom = "30 deg", stick = "-60 deg", bucket = "-45 deg" } # the target under it

The load (a cube of edge ``size``) lies on the table under the hand's tip at the ``pick``
pose; the target is a pad one ``size`` under the tip at the ``place`` pose. A pose names
joints of the mechanism (a free joint left out: its initial position; SI or any unit of the
joint's kind). The grasp takes the load when the tip is within one ``size`` of its centre;
while held, the load's mass is on the hand link (a payload of the live stepper,
`set_payloads`); released, it drops
straight down onto the target (delivered: the tip within one ``size`` of the target's centre
across) or the table. A file ``payload`` named is the load itself: the live task starts
without it (the start's equilibrium is the empty hand's). The table is a floor for the tip
(`tick`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..core.tree import forward_kinematics, make_tree_work
from ..errors import HydroarmError
from ..io.sections import as_table, reject_unknown_keys, text_value
from ..io.units import value_in
from ..model.mechanism import CompiledMechanism, Mechanism, Payload

SECTION = "block_task"
KEYS = {"hand", "payload", "mass", "point", "tip", "table", "size", "pick", "place"}


@dataclass
class BlockTask:
    """A mechanism's block task (module doc), read and checked; the load's state while live:
    ``where`` (``table``, ``held``, ``target``), ``centre`` [m] (world), the last release's
    distance from the target across [m] (nan: none yet)."""

    hand: str
    hand_index: int  # the hand link's joint in the tree
    load: Payload
    removes: str  # the file payload the load is ("": none)
    tip: np.ndarray
    table: float
    size: float
    pick: np.ndarray  # joint positions (tree order) [rad, m]
    place: np.ndarray
    up: np.ndarray
    block0: np.ndarray  # the load's centre at the start [m]
    target: np.ndarray  # the target pad's centre (its top) [m]
    where: str = "table"
    centre: np.ndarray = field(default_factory=lambda: np.zeros(3))
    miss: float = math.nan

    def reset(self) -> None:
        self.where = "table"
        self.centre = self.block0.copy()
        self.miss = math.nan

    def height(self, p: np.ndarray) -> float:
        return float(p @ self.up)

    def within_reach(self, tip: np.ndarray) -> bool:
        return self.where != "held" and float(np.linalg.norm(tip - self.centre)) <= self.size

    def across(self, a: np.ndarray, b: np.ndarray) -> float:
        """The distance of two points across (perpendicular to up) [m]."""
        d = a - b
        return float(np.linalg.norm(d - (d @ self.up) * self.up))

    def release(self, tip: np.ndarray) -> None:
        """Drop the held load from the tip: onto the target (delivered) or the table."""
        self.miss = self.across(tip, self.target)
        self.where = "target" if self.miss <= self.size else "table"
        rest = self.height(self.target) if self.where == "target" else self.table
        self.centre = tip + (rest + self.size / 2 - self.height(tip)) * self.up

    def describe(self) -> str:
        if self.where == "held":
            return f"the load ({self.load.mass:g} kg) held on {self.hand}"
        if self.where == "target":
            return f"the load delivered, {self.miss * 1e3:.0f} mm from the target's centre"
        if math.isfinite(self.miss):
            return f"the load dropped on the table, {self.miss:.2f} m from the target"
        return "the load on the table: bring the tip to it and grasp"


def full_q(mech: CompiledMechanism, q: np.ndarray) -> np.ndarray:
    """Joint positions with the coupled joints set from their masters."""
    out = np.asarray(q, dtype=float).copy()
    for s, m in mech.couplings:
        out[s] = mech.ratio[s] * out[m] + mech.offset[s]
    return out


class TipOf:
    """The world position [m] of a point of one link of a mechanism at joint positions q."""

    def __init__(self, mech: CompiledMechanism, link: int, point: np.ndarray):
        self.mech, self.link, self.point = mech, link, np.asarray(point, dtype=float)
        n = mech.n
        self.work = make_tree_work(n)
        self.R, self.p = np.zeros((n, 3, 3)), np.zeros((n, 3))

    def __call__(self, q: np.ndarray) -> np.ndarray:
        q = np.ascontiguousarray(full_q(self.mech, q))
        forward_kinematics(self.mech.tree, q, self.work, self.R, self.p)
        return self.p[self.link] + self.R[self.link] @ self.point


def _vector(field: str, v) -> np.ndarray:
    if not isinstance(v, list) or len(v) != 3:
        raise HydroarmError(field, f"must be a list of 3 lengths, got {v!r}")
    return np.array([value_in(f"{field}[{i}]", x, "m") for i, x in enumerate(v)])


def _pose(field: str, table, mech: CompiledMechanism, start: np.ndarray) -> np.ndarray:
    given = as_table(field, table)
    free = [n for i, n in enumerate(mech.joint_names) if mech.master[i] == i]
    reject_unknown_keys(field, given, set(free))
    q = start.copy()
    for name, v in given.items():
        i = mech.index(name)
        unit = "m" if mech.joint_types[i] == "prismatic" else "rad"
        x = value_in(f"{field}.{name}", v, unit)
        if not mech.lower[i] <= x <= mech.upper[i]:
            raise HydroarmError(f"{field}.{name}", "is outside the joint's limits")
        q[i] = x
    return q


def read_block_task(
    table, mechanism: Mechanism, compiled: CompiledMechanism, start: np.ndarray, up
) -> BlockTask:
    """``[block_task]`` of a mechanism file (module doc), checked: one line naming the field
    for a problem. ``start``: the joints' initial positions (tree order), ``up``: against
    gravity."""
    t = as_table(SECTION, table)
    reject_unknown_keys(SECTION, t, KEYS)
    for key in ("hand", "table", "size", "pick", "place"):
        if key not in t:
            raise HydroarmError(f"{SECTION}.{key}", "is missing")
    hand = text_value(f"{SECTION}.hand", t["hand"])
    if hand not in compiled.link_names:
        known = ", ".join(compiled.link_names)
        raise HydroarmError(
            f"{SECTION}.hand", f"{hand!r} is not a link a moving joint moves (links: {known})"
        )
    if "payload" in t and "mass" in t:
        raise HydroarmError(f"{SECTION}.mass", "give the load as payload or as mass, not both")
    if "payload" not in t and "mass" not in t:
        raise HydroarmError(f"{SECTION}.mass", "is missing (or name a payload of the file)")
    if "payload" in t:
        if "point" in t:
            raise HydroarmError(f"{SECTION}.point", "the payload named sets its own point")
        name = text_value(f"{SECTION}.payload", t["payload"])
        found = [p for p in mechanism.payloads if p.name == name]
        if not found:
            known = ", ".join(p.name for p in mechanism.payloads) or "none"
            raise HydroarmError(
                f"{SECTION}.payload", f"no payload {name!r} in the mechanism (payloads: {known})"
            )
        if found[0].link != hand:
            raise HydroarmError(
                f"{SECTION}.payload", f"{name!r} is on {found[0].link!r}, not on the hand {hand!r}"
            )
        load, removes = found[0], name
    else:
        mass = value_in(f"{SECTION}.mass", t["mass"], "kg")
        if not mass > 0:
            raise HydroarmError(f"{SECTION}.mass", f"must be > 0, got {t['mass']!r}")
        point = _vector(f"{SECTION}.point", t["point"]) if "point" in t else np.zeros(3)
        load, removes = Payload("block_task_load", hand, mass, tuple(point.tolist())), ""
    tip = _vector(f"{SECTION}.tip", t["tip"]) if "tip" in t else np.array(load.point)
    height = value_in(f"{SECTION}.table", t["table"], "m")
    size = value_in(f"{SECTION}.size", t["size"], "m")
    if not size > 0:
        raise HydroarmError(f"{SECTION}.size", f"must be > 0, got {t['size']!r}")
    pick = _pose(f"{SECTION}.pick", t["pick"], compiled, start)
    place = _pose(f"{SECTION}.place", t["place"], compiled, start)
    up = np.asarray(up, dtype=float)
    k = compiled.link_names.index(hand)
    tip_of = TipOf(compiled, k, tip)
    at_pick, at_place = tip_of(pick), tip_of(place)
    for which, p in (("pick", at_pick), ("place", at_place)):
        below = height - float(p @ up)
        if below > 0:
            raise HydroarmError(
                f"{SECTION}.{which}", f"puts the hand's tip {below:.3g} m below the table"
            )
    block0 = at_pick + (height + size / 2 - float(at_pick @ up)) * up
    target = at_place - size * up
    task = BlockTask(
        hand, k, load, removes, tip, height, size, pick, place, up, block0, target
    )  # fmt: skip
    task.reset()
    return task


def without_payload(mechanism: Mechanism, name: str) -> Mechanism:
    """The mechanism without its payload ``name`` (the live task's empty hand)."""
    return replace(mechanism, payloads=tuple(p for p in mechanism.payloads if p.name != name))
