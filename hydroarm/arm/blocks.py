"""A Box-and-Blocks-style score of the whole arm: blocks per minute from its joint speeds.

The Box and Block Test (Mathiowetz et al. 1985) counts the blocks a hand moves over a
partition in one minute. The arm's estimate of it (docs/evaluate.md) is plain arithmetic on
speeds measured by simulation: one block is a move from the pick pose to the place pose, the
release, the move back and the grasp. The joints move together, so a move takes as long as
its slowest joint needs for its travel at its own saturation speed in that direction:

    t_move = max_j |q_j(place) − q_j(pick)| / ω_j(direction)
    t_block = t_move(pick → place) + t_release + t_move(place → pick) + t_grasp
    blocks per minute = 60 s / t_block

Neglected (so the score is an upper bound of what the joints allow): the acceleration and
settling of each move (a few 63 % time constants, tens of ms), the user's reaction and
aiming time, the hand's own opening and closing beyond the stated grasp and release times.
Angles are articulation angles [rad], speeds [rad/s], times [s].
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from ..errors import HydroarmError
from ..files import csv_text

SECONDS_PER_MINUTE = 60.0


def _deg(v: float) -> float:
    return math.radians(v)


@dataclass(frozen=True)
class BlockTask:
    """The poses of one block transfer and the hand's stated times.

    ``pick`` and ``place``: {joint name: articulation angle [rad]} (joints left out do not
    move); ``grasp_time`` and ``release_time`` [s]: the terminal device closing on and
    letting go of a block (stated, not simulated: the UCL arm's hand is not modelled)."""

    pick: Mapping[str, float]
    place: Mapping[str, float]
    grasp_time: float
    release_time: float
    name: str = "block transfer"
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self):
        for which, pose in (("pick", self.pick), ("place", self.place)):
            for k, v in pose.items():
                if not math.isfinite(v):
                    raise HydroarmError(f"block_task.{which}.{k}", f"must be finite, got {v}")
        for k in ("grasp_time", "release_time"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v >= 0.0):
                raise HydroarmError(f"block_task.{k}", f"must be a time ≥ 0, got {v}")

    def travel(self) -> dict[str, float]:
        """{joint: q(place) − q(pick)} [rad] of the joints the task moves."""
        names = dict.fromkeys([*self.pick, *self.place])
        return {
            n: self.place.get(n, self.pick.get(n, 0.0)) - self.pick.get(n, self.place.get(n, 0.0))
            for n in names
        }


# The default transfer: the pick and the place poses of the block-stacking replay
# (examples/block_stacking.csv: the hand at the block, wrist turned, at 1.7 s; over the stack
# at 4.7 s): the shoulder raised 35° → 40°, the elbow 95° → 100°, the humeral rotation 0° →
# −30° (the hand carried sideways, over the partition), the wrist back 60° → 0°; the hand's times
# are stated (docs/evaluate.md: a powered hand of the era closes in about half a second).
DEFAULT_TASK = BlockTask(
    pick={
        "shoulder_elevation": _deg(35.0),
        "elbow_reach": _deg(95.0),
        "humeral_rotation": _deg(0.0),
        "wrist_rotation": _deg(60.0),
    },
    place={
        "shoulder_elevation": _deg(40.0),
        "elbow_reach": _deg(100.0),
        "humeral_rotation": _deg(-30.0),
        "wrist_rotation": _deg(0.0),
    },
    grasp_time=0.5,
    release_time=0.3,
    name="pick to place of examples/block_stacking.csv",
)


def move_time(travel: Mapping[str, float], speeds: Mapping[str, tuple[float, float]]):
    """(time [s], governing joint) of a move: each joint covers ``travel[j]`` [rad] at its
    speed ``speeds[j]`` = (increasing, decreasing) [rad/s], all at once; the slowest decides.
    A joint that does not move takes no time; a joint that must move with no speed makes the
    move impossible (infinite time)."""
    worst, name = 0.0, ""
    for j, d in travel.items():
        if d == 0.0:
            continue
        if j not in speeds:
            raise HydroarmError("block_task", f"no speed for joint {j!r}")
        up, down = speeds[j]
        v = up if d > 0 else down
        t = abs(d) / v if v > 0 and math.isfinite(v) else math.inf
        if t > worst or not name:
            worst, name = t, j
    return worst, name


def block_score(
    task: BlockTask, speeds: Mapping[str, tuple[float, float]]
) -> dict[str, float | str]:
    """The task's time per block and blocks per minute (module docstring); ``speeds``:
    {joint: (increasing, decreasing) [rad/s]}, each direction's saturation speed."""
    travel = task.travel()
    out, j_out = move_time(travel, speeds)
    back, j_back = move_time({k: -v for k, v in travel.items()}, speeds)
    cycle = out + task.release_time + back + task.grasp_time
    return {
        "move_out_s": out,
        "move_back_s": back,
        "governing_out": j_out,
        "governing_back": j_back,
        "grasp_s": task.grasp_time,
        "release_s": task.release_time,
        "block_time_s": cycle,
        "blocks_per_minute": SECONDS_PER_MINUTE / cycle if cycle > 0 else math.inf,
    }


# Published Box and Block Test scores to set the arm's beside (docs/evaluate.md cites them):
# (label, low, high) [blocks per minute].
BBT_REFERENCES = (
    ("able-bodied adults, Mathiowetz et al. 1985 (age-group means)", 60.0, 90.0),
    ("prosthesis users (body-powered and myoelectric), typical", 15.0, 30.0),
)


CARD_COLUMNS = ["joint", "quantity", "value", "unit", "paper"]


def card_rows(card: dict) -> list[dict]:
    """The rows of ``arm_card.csv`` (`CARD_COLUMNS`): per joint its speeds and stall
    (``card["rows"]``: joint, increasing_rad_s, decreasing_rad_s, stall, stall_value,
    stall_unit, paper_speed (increasing, decreasing), paper_stall), then the arm's
    block-transfer score."""
    out = []
    for r in card["rows"]:
        j = r["joint"]
        for q, key, unit, scale in (
            ("speed increasing", "increasing_rad_s", "rad/s", 1.0),
            ("speed decreasing", "decreasing_rad_s", "rad/s", 1.0),
            ("speed increasing", "increasing_rad_s", "deg/s", 180.0 / math.pi),
            ("speed decreasing", "decreasing_rad_s", "deg/s", 180.0 / math.pi),
        ):
            paper = r["paper_speed"]["decreasing" in key] if unit == "rad/s" else ""
            out.append(
                {"joint": j, "quantity": q, "value": r[key] * scale, "unit": unit, "paper": paper}
            )
        out.append(
            {
                "joint": j,
                "quantity": r["stall"],
                "value": r["stall_value"],
                "unit": r["stall_unit"],
                "paper": r["paper_stall"],
            }
        )
    s = card["score"]
    for q, key, unit in (
        ("move pick to place", "move_out_s", "s"),
        ("move place to pick", "move_back_s", "s"),
        ("grasp (stated)", "grasp_s", "s"),
        ("release (stated)", "release_s", "s"),
        ("time per block", "block_time_s", "s"),
        ("block transfer score", "blocks_per_minute", "blocks/min"),
    ):
        paper = ""
        if key == "blocks_per_minute":
            paper = "; ".join(f"{lbl}: {lo:g}-{hi:g}" for lbl, lo, hi in BBT_REFERENCES)
        out.append(
            {"joint": "arm", "quantity": q, "value": float(s[key]), "unit": unit, "paper": paper}
        )
    return out


def card_csv(card: dict) -> str:
    """``arm_card.csv`` text of `card_rows`."""
    return csv_text(CARD_COLUMNS, card_rows(card))
