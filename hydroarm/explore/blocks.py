"""The block-stacking task of the live arm: blocks on a waist-high table, grasped and released
with a key, the attempt timed and scored.

Plain geometry on the hand point of the arm's kinematics (x forward, y left, z up, the
shoulder at the origin; metres, seconds). The hand is not modelled (as in the arm's card,
docs/evaluate.md): a block within `GRASP_RADIUS` of the hand point is taken when the
grasp key is pressed, hangs centred on the hand point while held, and on release drops
straight down onto the highest surface under it (the table or a block it overlaps). The
layout puts the first block under the hand at the pick pose of the default block transfer
(`hydroarm.arm.blocks.DEFAULT_TASK`) and the target pad under the hand at its place
pose, so that the poses of ``examples/block_stacking.csv`` do the task.

Score: the blocks in the stack on the pad (resting on the pad or on a block of the stack),
the mean horizontal placement error of the stacked blocks from the pad's centre [m], and the
time from the first lever movement to the last block stacked [s] (running while unfinished).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

BLOCK_SIZE = 0.025  # [m] the Box and Block Test's 2.5 cm cubes (Mathiowetz et al. 1985)
# [kg] one block: a 25 mm wooden cube, 15.6 cm³ at about 0.7 g/cm³ (a hardwood such as beech
# or maple, 0.65-0.75 g/cm³): 10.9 g, in the 10-12 g such blocks weigh (an estimate: the test's
# manual gives the size, not the mass). Added to the hand's payload while the block is held.
BLOCK_MASS = 0.011
GRASP_RADIUS = 0.035  # [m] hand point to block centre for a grasp: a block and a half
# the table top [m]: the hand point at the default task's pick pose (z = -0.278 m, 0.28 m
# below the shoulder: "waist-high" for a seated user) is at the centre of a block on it,
# raised by a fifth of a block so that the hand reaches the block without entering the table
TABLE_TOP = -0.2975
# the table top's extent (x, y) [m]: from 60 mm in front of the shoulder (the arm hanging at
# rest is beside its near edge, not over it) to 360 mm, and 450 mm wide towards the body
TABLE_X = (0.06, 0.36)
TABLE_Y = (-0.195, 0.255)
# where the blocks start (x, y) [m]: the first under the hand at the pick pose, the others
# beside it, on the outer side (a right arm: the body is on its left, +y; the pad lies
# towards the body's midline)
BLOCK_STARTS = ((0.204, 0.0), (0.204, -0.05), (0.164, -0.05))
PAD = (0.183, 0.128)  # [m] the target pad: under the hand at the place pose
PAD_RADIUS = 0.03  # [m] a block whose centre lies within this of the pad centre is on it


@dataclass
class Block:
    """One block: its centre [m] and whether the hand holds it."""

    centre: np.ndarray
    held: bool = False


class StackingTask:
    """The blocks, the hand's grasp, the clock and the score of one attempt."""

    def __init__(self, starts=BLOCK_STARTS, pad=PAD, table_top: float = TABLE_TOP):
        self.table_top = float(table_top)
        self.table_x = TABLE_X
        self.table_y = TABLE_Y
        self.pad = (float(pad[0]), float(pad[1]))
        self.starts = tuple((float(x), float(y)) for x, y in starts)
        self.reset()

    def reset(self) -> None:
        """Blocks back at their starts, nothing held, the clock stopped."""
        z = self.table_top + 0.5 * BLOCK_SIZE
        self.blocks = [Block(np.array([x, y, z])) for x, y in self.starts]
        self.started: float | None = None  # simulated time of the first lever movement [s]
        self.finished: float | None = None  # simulated time the last block was stacked [s]
        self.last_place: float | None = None
        self.events: list[str] = []

    def over_table(self, point) -> bool:
        """Whether the point's (x, y) [m] lies within the table top's extent."""
        x, y = float(point[0]), float(point[1])
        return self.table_x[0] <= x <= self.table_x[1] and self.table_y[0] <= y <= self.table_y[1]

    def through_table(self, before, after) -> bool:
        """Whether a move of the hand point from ``before`` to ``after`` [m] passes down
        through the table top: ``before`` at or above the top, ``after`` below it and within
        the table's extent (the table as a floor; a point already below the top, beside or
        under the table, is free)."""
        return (
            float(before[2]) >= self.table_top
            and float(after[2]) < self.table_top
            and self.over_table(after)
        )

    # the attempt -----------------------------------------------------------------------
    def start(self, t: float) -> None:
        """The first lever movement at simulated time ``t`` [s] starts the clock."""
        if self.started is None:
            self.started = float(t)

    @property
    def held(self) -> int | None:
        """Index of the held block (None: the hand is empty)."""
        for i, b in enumerate(self.blocks):
            if b.held:
                return i
        return None

    def follow(self, hand) -> None:
        """The held block follows the hand point ``hand`` (x, y, z) [m]."""
        i = self.held
        if i is not None:
            self.blocks[i].centre = np.asarray(hand, dtype=float).copy()

    def toggle(self, hand, t: float) -> str:
        """The grasp key at simulated time ``t`` [s] with the hand point at ``hand`` [m]:
        release the held block, or grasp the nearest free block within reach. Returns what
        happened (``grasped k``, ``released k``, ``nothing in reach``)."""
        hand = np.asarray(hand, dtype=float)
        i = self.held
        if i is not None:
            self.blocks[i].centre = hand.copy()
            self._drop(i)
            self.last_place = float(t)
            if self.finished is None and self.stacked() == len(self.blocks):
                self.finished = float(t)
            what = f"released {i + 1}"
        else:
            best, best_d = None, GRASP_RADIUS
            for k, b in enumerate(self.blocks):
                d = float(np.linalg.norm(b.centre - hand))
                if d <= best_d and not self._covered(k):
                    best, best_d = k, d
            if best is None:
                what = "nothing in reach"
            else:
                self.blocks[best].held = True
                self.blocks[best].centre = hand.copy()
                what = f"grasped {best + 1}"
        self.events.append(f"{t:.2f} s: {what}")
        return what

    def _covered(self, k: int) -> bool:
        """Whether another block rests on block ``k`` (only the top of a stack can be taken)."""
        c = self.blocks[k].centre
        for j, b in enumerate(self.blocks):
            if j == k or b.held:
                continue
            if _overlap(b.centre, c) and abs(b.centre[2] - (c[2] + BLOCK_SIZE)) < 1e-9:
                return True
        return False

    def _drop(self, i: int) -> None:
        """Release block ``i``: it falls straight down onto the highest surface under it."""
        b = self.blocks[i]
        b.held = False
        floor = self.table_top
        for j, o in enumerate(self.blocks):
            if j != i and not o.held and _overlap(o.centre, b.centre):
                top = o.centre[2] + 0.5 * BLOCK_SIZE
                if top <= b.centre[2] + 1e-9:
                    floor = max(floor, top)
        b.centre = np.array([b.centre[0], b.centre[1], floor + 0.5 * BLOCK_SIZE])

    # the score -------------------------------------------------------------------------
    def stack(self) -> list[int]:
        """Indices of the blocks in the stack on the pad, bottom first: one resting on the
        table within `PAD_RADIUS` of the pad's centre, then each block resting on the
        previous one."""
        z0 = self.table_top + 0.5 * BLOCK_SIZE
        free = [k for k, b in enumerate(self.blocks) if not b.held]
        base = [
            k
            for k in free
            if abs(self.blocks[k].centre[2] - z0) < 1e-9
            and math.dist(self.blocks[k].centre[:2], self.pad) <= PAD_RADIUS
        ]
        if not base:
            return []
        out = [min(base, key=lambda k: math.dist(self.blocks[k].centre[:2], self.pad))]
        while True:
            below = self.blocks[out[-1]].centre
            on = [
                k
                for k in free
                if k not in out
                and _overlap(self.blocks[k].centre, below)
                and abs(self.blocks[k].centre[2] - (below[2] + BLOCK_SIZE)) < 1e-9
            ]
            if not on:
                return out
            out.append(on[0])

    def stacked(self) -> int:
        """Blocks in the stack on the pad."""
        return len(self.stack())

    def score(self, t: float) -> dict:
        """{stacked, blocks, placement_error [m] (nan: none stacked), time [s] (0 before the
        first lever movement; running until the last block is stacked), done}."""
        st = self.stack()
        err = (
            float(np.mean([math.dist(self.blocks[k].centre[:2], self.pad) for k in st]))
            if st
            else math.nan
        )
        if self.started is None:
            elapsed = 0.0
        else:
            end = self.finished if self.finished is not None else float(t)
            elapsed = max(end - self.started, 0.0)
        return {
            "stacked": len(st),
            "blocks": len(self.blocks),
            "placement_error": err,
            "time": elapsed,
            "done": self.finished is not None,
        }


def _overlap(a, b) -> bool:
    """Whether two blocks' footprints overlap (centres closer than a block in x and y)."""
    return abs(a[0] - b[0]) < BLOCK_SIZE and abs(a[1] - b[1]) < BLOCK_SIZE
