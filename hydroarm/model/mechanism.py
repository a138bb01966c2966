"""Mechanisms: links and joints forming a tree (issue 30; docs/mechanism.md).

A `Mechanism` is validated data in SI units: its `Link` s (mass, centre of mass,
rotational inertia about the centre of mass), its `Joint` s (revolute, continuous,
prismatic or fixed; parent and child link, axis, origin, limits, damping, dry friction), the
gravity vector and `Payload` s (point masses or small bodies fixed to a link). It is
the same description as a URDF's ``<link>`` s and ``<joint>`` s (`hydroarm.io.mechanism`
reads both hydroarm TOML and URDF). Its `Coupling` s make a joint follow another,
q_s = ratio·q_m + offset (URDF's ``<mimic>``): the coupled joint is no free coordinate.

`Mechanism.compile` gives the arrays of the numeric kernel
(`hydroarm.core.tree.TreeModel`): fixed joints are merged into their parent link (their
inertias combined, as Pinocchio does), payloads are added to their links' inertias, and the
moving joints are numbered depth first from the base (parents before children, each subtree
contiguous, Pinocchio's order).

Every problem is a [`HydroarmError`][hydroarm.HydroarmError] naming the field
(``mechanism.joint.knee.axis: is zero``), raised when the mechanism is made: a cycle, a missing
link, two roots, a link that is the child of two joints, a non-positive-definite inertia or one
whose principal moments no rigid body has, a negative mass or a moving link with no mass
beyond it, a zero axis, an unknown joint type, limits out of order; a coupling of a joint to
itself, to a missing or a fixed joint, a joint coupled twice, couplings in a loop, and a
coupling whose joint's limits cannot be met within its master's.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field

import numpy as np

from ..core.tree import PRISMATIC, REVOLUTE, STANDARD_GRAVITY, TreeModel, spatial_inertias
from ..errors import HydroarmError, check_number

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
MOVING = {"revolute": REVOLUTE, "continuous": REVOLUTE, "prismatic": PRISMATIC}
DEFAULT_GRAVITY = (0.0, 0.0, -STANDARD_GRAVITY)  # [m/s²], −z as URDF tools assume
ZERO3 = (0.0, 0.0, 0.0)
ZERO6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
PREFIX = "mechanism"


@dataclass(frozen=True)
class Link:
    """A rigid link: ``mass`` [kg], centre of mass ``com`` in the link frame [m] and the
    rotational ``inertia`` about the centre of mass, in the link frame's axes, as
    (ixx, iyy, izz, ixy, ixz, iyz) [kg·m²] (URDF's order). A link with no mass (0 kg, no
    inertia) is allowed where a link beyond it carries mass (between two joints in series)."""

    name: str
    mass: float = 0.0
    com: tuple[float, float, float] = ZERO3
    inertia: tuple[float, float, float, float, float, float] = ZERO6


@dataclass(frozen=True)
class Joint:
    """A joint moving ``child`` relative to ``parent`` (link names).

    ``type``: ``revolute`` (about ``axis``, angle [rad]), ``continuous`` (revolute without
    limits), ``prismatic`` (along ``axis``, position [m]) or ``fixed`` (merged into the parent
    link). The joint frame sits at ``origin`` [m] in the parent link's frame, rotated by
    ``rpy`` [rad] (roll, pitch, yaw about fixed x, y, z: R = Rz·Ry·Rx, as URDF); the child
    link's frame is the joint frame moved by the joint. ``axis`` is a direction in the joint
    frame (normalised here). ``lower``, ``upper``: position limits [rad or m] (±inf: none);
    ``damping`` [N·m·s/rad or N·s/m] and dry ``friction`` [N·m or N] act at the joint."""

    name: str
    type: str
    parent: str
    child: str
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    origin: tuple[float, float, float] = ZERO3
    rpy: tuple[float, float, float] = ZERO3
    lower: float = -math.inf
    upper: float = math.inf
    damping: float = 0.0
    friction: float = 0.0


@dataclass(frozen=True)
class Payload:
    """A body fixed to ``link``: ``mass`` [kg] with its centre at ``point`` [m] of the link
    frame and its rotational ``inertia`` about that point (ixx, iyy, izz, ixy, ixz, iyz)
    [kg·m²] (zero: a point mass)."""

    name: str
    link: str
    mass: float
    point: tuple[float, float, float] = ZERO3
    inertia: tuple[float, float, float, float, float, float] = ZERO6


@dataclass(frozen=True)
class Coupling:
    """A kinematic coupling (URDF's ``<mimic>``): the moving joint ``joint`` follows the
    moving joint ``follows``, q_joint = ``ratio``·q_follows + ``offset``. ``ratio`` [-]
    between two joints of one kind, [m/rad] for a prismatic joint following a revolute one,
    [rad/m] the other way; ``offset`` [rad or m], the coupled joint's unit. A chain (a joint
    following a coupled joint) is resolved to the free joint at its end."""

    joint: str
    follows: str
    ratio: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class CompiledMechanism:
    """A mechanism as the numeric kernel takes it (`Mechanism.compile`).

    ``tree``: the `TreeModel`; joint ``i`` of the tree is
    ``joint_names[i]`` (a moving joint of the mechanism), moving the link ``link_names[i]``
    (with every link fixed to it merged in). ``lower``, ``upper``, ``damping``, ``friction``:
    per joint, in the tree's order, SI (each joint's own). ``base``: the base link's name.
    ``master``, ``ratio``, ``offset``: the couplings, per joint: joint ``i`` is
    ``ratio[i]``·q[``master[i]``] + ``offset[i]``, its master a free joint (``master[i] == i``,
    ratio 1, offset 0: a free joint)."""

    tree: TreeModel
    joint_names: tuple[str, ...]
    link_names: tuple[str, ...]
    joint_types: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    base: str
    master: np.ndarray
    ratio: np.ndarray
    offset: np.ndarray

    @property
    def n(self) -> int:
        """Number of moving joints (the tree's coordinates, coupled ones included)."""
        return len(self.joint_names)

    @property
    def couplings(self) -> np.ndarray:
        """(k, 2) int64: each coupled joint's index and its (free) master's, in tree order."""
        rows = [(i, int(m)) for i, m in enumerate(self.master) if m != i]
        return np.array(rows, np.int64).reshape(len(rows), 2)

    @property
    def coupling_laws(self) -> np.ndarray:
        """(k, 2): each coupled joint's ratio and offset, in the rows of `couplings`."""
        rows = [(self.ratio[i], self.offset[i]) for i, m in enumerate(self.master) if m != i]
        return np.array(rows, np.float64).reshape(len(rows), 2)

    def kernel_limits(self) -> np.ndarray:
        """(n, 4): each joint's damping, dry friction, lower and upper limit as the system
        kernel applies them. A coupled joint's friction and limits act through its master
        (docs/mechanism.md "Kinematic couplings"): its friction F_s opposes q̇_s, so the
        master feels |ratio|·F_s (virtual work), added to its own; its limits, mapped
        through q_s = ratio·q_m + offset, narrow the master's. The coupled joint's own row
        keeps its damping (the kernel carries its torque through the coupling) and has no
        friction and no limits of its own."""
        out = np.column_stack([self.damping, self.friction, self.lower, self.upper])
        out = out.reshape(self.n, 4).astype(float)
        for s, m in self.couplings:
            r, o = float(self.ratio[s]), float(self.offset[s])
            out[m, 1] += abs(r) * self.friction[s]
            if r != 0.0:
                a, b = (self.lower[s] - o) / r, (self.upper[s] - o) / r
                out[m, 2] = max(out[m, 2], min(a, b))
                out[m, 3] = min(out[m, 3], max(a, b))
            out[s, 1:] = (0.0, -math.inf, math.inf)
        return out

    def index(self, joint: str) -> int:
        """Position of a joint in the tree's arrays."""
        try:
            return self.joint_names.index(joint)
        except ValueError:
            raise HydroarmError(
                f"{PREFIX}.joint", f"no moving joint named {joint!r} ({_known(self.joint_names)})"
            ) from None


def _known(names) -> str:
    return "known: " + ", ".join(names) if names else "there are none"


def _unknown(field: str, what: str, name: str, known) -> HydroarmError:
    close = difflib.get_close_matches(str(name), list(known), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return HydroarmError(field, f"no {what} named {name!r}{hint} ({_known(known)})")


def rpy_matrix(rpy) -> np.ndarray:
    """Rotation of roll, pitch, yaw [rad] about fixed x, y, z: Rz(yaw)·Ry(pitch)·Rx(roll)
    (URDF's convention)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (math.cos(r), math.sin(r), math.cos(p), math.sin(p),
                              math.cos(y), math.sin(y))  # fmt: skip
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def inertia_matrix(i6) -> np.ndarray:
    """The symmetric 3×3 matrix of (ixx, iyy, izz, ixy, ixz, iyz) [kg·m²]."""
    ixx, iyy, izz, ixy, ixz, iyz = i6
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)


def check_inertia(field: str, i6) -> None:
    """Refuse an inertia that is not positive (semi-)definite, or whose principal moments
    break the triangle inequality I₁ ≤ I₂ + I₃ (no rigid body has them); round-off allowed.
    A point mass (all zero) and a thin rod (one zero moment) are the limits allowed."""
    moments = np.linalg.eigvalsh(inertia_matrix(i6))
    tol = 1e-9 * max(float(np.abs(moments).max()), 1e-300)
    shown = ", ".join(f"{m:.6g}" for m in moments)
    if moments[0] < -tol:
        raise HydroarmError(field, f"is not positive definite (principal moments {shown} kg*m**2)")
    if moments[2] > moments[0] + moments[1] + tol:
        raise HydroarmError(
            field,
            f"principal moments {shown} kg*m**2 break the triangle inequality "
            "(the largest must not exceed the sum of the other two): no rigid body has them",
        )


def _vector(field: str, v, n: int) -> tuple[float, ...]:
    if not isinstance(v, tuple | list | np.ndarray) or len(v) != n:
        raise HydroarmError(field, f"must be {n} numbers, got {v!r}")
    return tuple(float(check_number(f"{field}[{i}]", x)) for i, x in enumerate(v))


def _check_name(field: str, name) -> None:
    if not isinstance(name, str) or not name.strip():
        raise HydroarmError(field, f"must be a non-empty name, got {name!r}")


@dataclass(frozen=True)
class Mechanism:
    """A tree of links and joints fixed at one base link (a link that is no joint's child),
    with gravity [m/s²] in the base (world) frame and payloads; SI units. Validated when
    made (module docstring); `compile` gives the kernel's arrays."""

    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    gravity: tuple[float, float, float] = DEFAULT_GRAVITY
    payloads: tuple[Payload, ...] = ()
    name: str = "mechanism"
    couplings: tuple[Coupling, ...] = ()
    _order: tuple[int, ...] = field(default=(), init=False, repr=False, compare=False)
    _masters: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "links", tuple(self.links))
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "payloads", tuple(self.payloads))
        object.__setattr__(self, "couplings", tuple(self.couplings))
        object.__setattr__(self, "gravity", _vector(f"{PREFIX}.gravity", self.gravity, 3))
        self._check_links()
        self._check_joints()
        object.__setattr__(self, "_order", self._check_tree())
        self._check_payloads()
        self._check_masses()
        object.__setattr__(self, "_masters", self._check_couplings())

    # --- validation ----------------------------------------------------------------------

    def _check_links(self) -> None:
        if not self.links:
            raise HydroarmError(f"{PREFIX}.link", "a mechanism needs at least one link")
        seen: set[str] = set()
        for i, link in enumerate(self.links):
            _check_name(f"{PREFIX}.link[{i}].name", link.name)
            f = f"{PREFIX}.link.{link.name}"
            if link.name in seen:
                raise HydroarmError(f"{f}.name", "two links have this name")
            seen.add(link.name)
            check_number(f"{f}.mass", link.mass, nonnegative=True)
            object.__setattr__(link, "com", _vector(f"{f}.com", link.com, 3))
            object.__setattr__(link, "inertia", _vector(f"{f}.inertia", link.inertia, 6))
            check_inertia(f"{f}.inertia", link.inertia)

    def _check_joints(self) -> None:
        links = [link.name for link in self.links]
        known = set(links)
        seen: set[str] = set()
        child_of: dict[str, str] = {}
        for i, j in enumerate(self.joints):
            _check_name(f"{PREFIX}.joint[{i}].name", j.name)
            f = f"{PREFIX}.joint.{j.name}"
            if j.name in seen:
                raise HydroarmError(f"{f}.name", "two joints have this name")
            seen.add(j.name)
            if j.type not in JOINT_TYPES:
                close = difflib.get_close_matches(str(j.type), JOINT_TYPES, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise HydroarmError(
                    f"{f}.type",
                    f"unknown joint type {j.type!r}{hint} (known: {', '.join(JOINT_TYPES)})",
                )
            for key in ("parent", "child"):
                name = getattr(j, key)
                _check_name(f"{f}.{key}", name)
                if name not in known:
                    raise _unknown(f"{f}.{key}", "link", name, links)
            if j.parent == j.child:
                raise HydroarmError(f"{f}.child", f"link {j.child!r} is its own parent (a cycle)")
            if j.child in child_of:
                raise HydroarmError(
                    f"{f}.child",
                    f"link {j.child!r} is already the child of joint {child_of[j.child]!r}: a "
                    "link has one parent joint in a tree (closed loops are not supported)",
                )
            child_of[j.child] = j.name
            for key in ("axis", "origin", "rpy"):
                object.__setattr__(j, key, _vector(f"{f}.{key}", getattr(j, key), 3))
            if j.type != "fixed" and math.sqrt(sum(a * a for a in j.axis)) < 1e-12:
                raise HydroarmError(f"{f}.axis", f"is zero: {list(j.axis)}")
            for key in ("lower", "upper"):
                v = getattr(j, key)
                if isinstance(v, bool) or not isinstance(v, int | float) or math.isnan(v):
                    raise HydroarmError(f"{f}.{key}", f"expected a number, got {v!r}")
            if not j.lower <= j.upper:
                raise HydroarmError(
                    f"{f}.upper", f"{j.upper:g} is below the lower limit {j.lower:g}"
                )
            if j.type == "continuous" and (math.isfinite(j.lower) or math.isfinite(j.upper)):
                raise HydroarmError(f"{f}.lower", "a continuous joint has no limits")
            check_number(f"{f}.damping", j.damping, nonnegative=True)
            check_number(f"{f}.friction", j.friction, nonnegative=True)

    def _check_tree(self) -> tuple[int, ...]:
        """The joints in depth-first order from the single root; refuses two roots and
        cycles."""
        children = {j.child for j in self.joints}
        roots = [link.name for link in self.links if link.name not in children]
        if len(roots) > 1:
            raise HydroarmError(
                f"{PREFIX}.link",
                f"{len(roots)} roots ({', '.join(repr(r) for r in roots[:4])}): links that are "
                "no joint's child; a mechanism is one tree fixed at one base link",
            )
        if not roots:
            j = self.joints[0]
            raise HydroarmError(
                f"{PREFIX}.joint.{j.name}",
                f"is part of a cycle: every link is some joint's child ({self._cycle(j)})",
            )
        by_parent: dict[str, list[int]] = {}
        for i, j in enumerate(self.joints):
            by_parent.setdefault(j.parent, []).append(i)
        order = self._depth_first(roots[0], by_parent)
        if len(order) < len(self.joints):
            reached = set(order)
            j = next(j for i, j in enumerate(self.joints) if i not in reached)
            raise HydroarmError(
                f"{PREFIX}.joint.{j.name}",
                f"is part of a cycle not connected to the base link {roots[0]!r} "
                f"({self._cycle(j)})",
            )
        return tuple(order)

    def _depth_first(self, root: str, by_parent: dict[str, list[int]]) -> list[int]:
        """Joint indices depth first from ``root``, children in file order."""
        order: list[int] = []
        stack = list(reversed(by_parent.get(root, [])))
        while stack:
            i = stack.pop()
            order.append(i)
            stack.extend(reversed(by_parent.get(self.joints[i].child, [])))
        return order

    def _cycle(self, start: Joint) -> str:
        parent_joint = {j.child: j for j in self.joints}
        path = [start.child]
        j: Joint | None = start
        while j is not None and j.parent not in path:
            path.append(j.parent)
            j = parent_joint.get(j.parent)
        if j is not None:
            path.append(j.parent)
        return " <- ".join(path)

    def _check_payloads(self) -> None:
        links = [link.name for link in self.links]
        seen: set[str] = set()
        for i, p in enumerate(self.payloads):
            _check_name(f"{PREFIX}.payload[{i}].name", p.name)
            f = f"{PREFIX}.payload.{p.name}"
            if p.name in seen:
                raise HydroarmError(f"{f}.name", "two payloads have this name")
            seen.add(p.name)
            if p.link not in links:
                raise _unknown(f"{f}.link", "link", p.link, links)
            check_number(f"{f}.mass", p.mass, positive=True)
            object.__setattr__(p, "point", _vector(f"{f}.point", p.point, 3))
            object.__setattr__(p, "inertia", _vector(f"{f}.inertia", p.inertia, 6))
            check_inertia(f"{f}.inertia", p.inertia)

    def _check_masses(self) -> None:
        """Every moving joint must move some mass: the links beyond it (its child and all
        below) must weigh something, or its row of the mass matrix is zero."""
        mass = {link.name: link.mass for link in self.links}
        for p in self.payloads:
            mass[p.link] += p.mass
        below = dict(mass)
        for i in reversed(self._order):
            j = self.joints[i]
            below[j.parent] += below[j.child]
        for i in self._order:
            j = self.joints[i]
            if j.type != "fixed" and not below[j.child] > 0:
                raise HydroarmError(
                    f"{PREFIX}.link.{j.child}.mass",
                    f"must be positive: joint {j.name!r} moves this link and nothing beyond it "
                    "has mass",
                )

    def _check_couplings(self) -> dict[str, tuple[str, float, float]]:
        """Each coupled joint's free master (a chain followed to its end), ratio and offset,
        q_s = ratio·q_m + offset; refuses a coupling of a joint to itself, to a missing or a
        fixed joint, a joint coupled twice, loops of couplings, and limits that no position
        of the master meets."""
        joints = {j.name: j for j in self.joints}
        names = [j.name for j in self.joints]
        follows: dict[str, Coupling] = {}
        for i, c in enumerate(self.couplings):
            _check_name(f"{PREFIX}.coupling[{i}].joint", c.joint)
            if c.joint not in joints:
                raise _unknown(f"{PREFIX}.coupling[{i}].joint", "joint", c.joint, names)
            f = f"{PREFIX}.coupling.{c.joint}"
            _check_name(f"{f}.follows", c.follows)
            if c.follows not in joints:
                raise _unknown(f"{f}.follows", "joint", c.follows, names)
            if c.follows == c.joint:
                raise HydroarmError(f"{f}.follows", "a joint cannot follow itself")
            for key, name in (("joint", c.joint), ("follows", c.follows)):
                if joints[name].type == "fixed":
                    raise HydroarmError(
                        f"{f}.{key}", f"{name!r} is a fixed joint: it has no position to couple"
                    )
            if c.joint in follows:
                raise HydroarmError(
                    f"{f}.joint",
                    f"already follows {follows[c.joint].follows!r}: a joint follows one joint",
                )
            check_number(f"{f}.ratio", c.ratio)
            check_number(f"{f}.offset", c.offset)
            follows[c.joint] = c
        resolved: dict[str, tuple[str, float, float]] = {}
        for name in follows:
            path, ratio, offset = [name], 1.0, 0.0
            while path[-1] in follows:
                c = follows[path[-1]]
                ratio, offset = ratio * c.ratio, offset + ratio * c.offset
                if c.follows in path:
                    loop = " -> ".join([*path[path.index(c.follows) :], c.follows])
                    raise HydroarmError(
                        f"{PREFIX}.coupling.{name}",
                        f"the couplings form a loop ({loop}): one joint of it must be free",
                    )
                path.append(c.follows)
            resolved[name] = (path[-1], ratio, offset)
        lower = {j.name: j.lower for j in self.joints}
        upper = {j.name: j.upper for j in self.joints}
        for name, (m, r, o) in resolved.items():
            j = joints[name]
            own = f"[{j.lower:g}, {j.upper:g}]"
            if r == 0.0:
                if not j.lower <= o <= j.upper:
                    raise HydroarmError(
                        f"{PREFIX}.coupling.{name}.offset",
                        f"holds {name!r} at {o:g}, outside its limits {own} (SI: rad or m)",
                    )
                continue
            a, b = sorted(((j.lower - o) / r, (j.upper - o) / r))
            lo, hi = max(lower[m], a), min(upper[m], b)
            if not lo <= hi:
                raise HydroarmError(
                    f"{PREFIX}.coupling.{name}",
                    f"its limits {own} need {m!r} within [{a:g}, {b:g}], outside the range "
                    f"[{lower[m]:g}, {upper[m]:g}] {m!r} may move in (SI: rad or m)",
                )
            lower[m], upper[m] = lo, hi
        return resolved

    # --- derived -------------------------------------------------------------------------

    @property
    def base(self) -> str:
        """The base link (fixed to the world; no joint's child)."""
        children = {j.child for j in self.joints}
        return next(link.name for link in self.links if link.name not in children)

    @property
    def moving_joints(self) -> tuple[str, ...]:
        """Names of the moving joints in the tree's (depth-first) order."""
        return tuple(self.joints[i].name for i in self._order if self.joints[i].type != "fixed")

    def compile(self) -> CompiledMechanism:
        """The numeric kernel's arrays: fixed joints merged into their parent links (inertias
        combined about the merged centre of mass), payloads added, joints depth first."""
        links = {link.name: link for link in self.links}
        # each link's body (the moving link it is rigidly part of) and its frame in the body's
        body = {self.base: self.base}
        place = {self.base: (np.eye(3), np.zeros(3))}
        moving: list[Joint] = []
        joint_place: list[tuple[np.ndarray, np.ndarray]] = []
        for i in self._order:
            j = self.joints[i]
            Rp, pp = place[j.parent]
            R = Rp @ rpy_matrix(j.rpy)
            p = Rp @ np.asarray(j.origin) + pp
            if j.type == "fixed":
                body[j.child] = body[j.parent]
                place[j.child] = (R, p)
            else:
                body[j.child] = j.child
                place[j.child] = (np.eye(3), np.zeros(3))
                moving.append(j)
                joint_place.append((R, p))
        parts: dict[str, list[tuple[float, np.ndarray, np.ndarray]]] = {b: [] for b in body}
        for name, b in body.items():
            R, p = place[name]
            link = links[name]
            parts[b].append(
                (link.mass, R @ np.asarray(link.com) + p, R @ inertia_matrix(link.inertia) @ R.T)
            )
        for pl in self.payloads:
            R, p = place[pl.link]
            parts[body[pl.link]].append(
                (pl.mass, R @ np.asarray(pl.point) + p, R @ inertia_matrix(pl.inertia) @ R.T)
            )
        n = len(moving)
        index = {j.child: k for k, j in enumerate(moving)}
        links_of = {j.name: j.child for j in moving}
        parent = np.array([index.get(body[j.parent], -1) for j in moving], dtype=np.int64)
        axis = np.array([np.asarray(j.axis) / np.linalg.norm(j.axis) for j in moving]).reshape(n, 3)
        mass = np.zeros(n)
        com = np.zeros((n, 3))
        inertia = np.zeros((n, 3, 3))
        for k, j in enumerate(moving):
            mass[k], com[k], inertia[k] = combine_inertias(parts[j.child])
        tree = TreeModel(
            parent=parent,
            joint_type=np.array([MOVING[j.type] for j in moving], dtype=np.int64),
            axis=axis,
            rotation=np.array([R for R, _ in joint_place]).reshape(n, 3, 3),
            translation=np.array([p for _, p in joint_place]).reshape(n, 3),
            mass=mass,
            com=com,
            inertia=inertia,
            gravity=np.array(self.gravity, dtype=float),
            spatial=spatial_inertias(mass, com, inertia),
        )
        masters = self._masters
        return CompiledMechanism(
            tree=tree,
            joint_names=tuple(j.name for j in moving),
            link_names=tuple(j.child for j in moving),
            joint_types=tuple(j.type for j in moving),
            lower=np.array([j.lower for j in moving]),
            upper=np.array([j.upper for j in moving]),
            damping=np.array([j.damping for j in moving]),
            friction=np.array([j.friction for j in moving]),
            base=self.base,
            master=np.array(
                [
                    index[links_of[masters[j.name][0]]] if j.name in masters else k
                    for k, j in enumerate(moving)
                ],
                dtype=np.int64,
            ).reshape(n),
            ratio=np.array([masters[j.name][1] if j.name in masters else 1.0 for j in moving]),
            offset=np.array([masters[j.name][2] if j.name in masters else 0.0 for j in moving]),
        )


def combine_inertias(parts) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass [m] and rotational inertia about it [kg·m²] of rigidly
    joined bodies, each (mass, centre of mass, inertia about its centre) in one frame
    (parallel-axis theorem: I = Σ I_k + m_k·(|d_k|²·1 − d_k·d_kᵀ), d_k = c_k − c)."""
    m = sum(mk for mk, _, _ in parts)
    if m <= 0:
        return 0.0, np.zeros(3), sum((Ik for _, _, Ik in parts), np.zeros((3, 3)))
    c = sum(mk * ck for mk, ck, _ in parts) / m
    inertia = np.zeros((3, 3))
    for mk, ck, Ik in parts:
        d = ck - c
        inertia += Ik + mk * (d @ d * np.eye(3) - np.outer(d, d))
    return float(m), c, inertia
