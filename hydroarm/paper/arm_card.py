"""The whole arm's evaluation card (``hydroarm arm``: ``arm_card.csv``, ``arm_card.png``).

Per joint: its saturation speeds in both directions and its stall, each from a simulation of
the arm built from the user's config at the arm validation's scheme (the paper's Euler at
10 µs, `hydroarm.paper.arm_validation`), beside what the paper reports; then the
Box-and-Blocks-style score of `hydroarm.arm.blocks` from those speeds.

- Speeds [rad/s]: mean over the middle 80 % of a saturated motion of the joint alone (the
  others held), the validation's measure (``reach_velocity``): shoulder elevation from the arm
  hanging to 120° (the paper's saturation test, ±60° about the servo's datum), humeral rotation
  over the paper's 100° (the validation's motion), elbow reach over the paper's 110° (the
  validation's numbers, reused), wrist rotation over ±80°.
- Stall: the shoulder elevation's stall mass in the hand (the single-joint search of
  ``hydroarm validate``, `hydroarm.paper.validation.stall_mass`, on the joint's servo), the
  elbow's stall mass at the hand (the validation's, reused); the rotations carry no gravity
  load, so their theoretical stall torque A·p_s·r/n [N m] (no loss).
"""

from __future__ import annotations

import math

from ..arm.blocks import DEFAULT_TASK, BlockTask, block_score
from ..arm.expand import simulate_motion
from ..arm.model import ArmScenario
from .arm_validation import REACH_RANGE, ROTATION_SPAN, _single
from .data import measurement
from .validation import stall_mass

# the motion each joint's speed is measured on: (from, to) articulation angles [rad], and the
# joints held (articulation angles) while it moves
SPEED_MOTIONS = {
    "shoulder_elevation": ((0.0, math.radians(120.0)), {}),
    "humeral_rotation": ((-0.5 * ROTATION_SPAN, 0.5 * ROTATION_SPAN), {}),
    "elbow_reach": (REACH_RANGE, {"shoulder_elevation": 0.0}),
    "wrist_rotation": ((math.radians(-80.0), math.radians(80.0)), {}),
}
SPEED_DURATION = 2.0  # [s]: every motion above ends within it (the slowest, the reach, ~0.9 s)


def joint_speed(
    arm: ArmScenario, name: str, a0: float, a1: float, others=None, *, simulate=simulate_motion
) -> float:
    """Mean |angular velocity| [rad/s] of joint ``name`` over the middle 80 % of its motion
    a0 → a1 [rad] (articulation angles), the joints of ``others`` held; the arm validation's
    run (``_single``: Euler at 10 µs) and measure (``joint_metric_values``). ``simulate``
    runs the arm (by default on the system kernel, `hydroarm.arm.expand.simulate_motion`),
    as the validation takes it."""
    r = simulate(_single(arm, name, a0, a1, duration=SPEED_DURATION, others=others))
    return abs(r.joint_metric_values(name)["saturation_velocity"])


def joint_speeds(
    arm: ArmScenario, validation_rows=(), *, simulate=simulate_motion
) -> dict[str, tuple[float, float]]:
    """{joint: (increasing, decreasing) [rad/s]} of each of the arm's joints; the reach's the
    validation's rows when given (the same runs); ``simulate`` as `joint_speed`."""
    by = {r["quantity"]: r["model"] for r in validation_rows}
    names = {j.name for j in arm.joints}
    out = {}
    for name, ((a0, a1), others) in SPEED_MOTIONS.items():
        if name not in names:
            continue
        held = {k: v for k, v in others.items() if k in names}
        if name == "elbow_reach" and "elbow_reach_raise_rad_s" in by:
            out[name] = (by["elbow_reach_raise_rad_s"], by["elbow_reach_lower_rad_s"])
            continue
        out[name] = (
            joint_speed(arm, name, a0, a1, held, simulate=simulate),
            joint_speed(arm, name, a1, a0, held, simulate=simulate),
        )
    return out


def _paper_speeds(name: str) -> tuple[str, str]:
    """What the paper reports for the joint's (increasing, decreasing) speed."""
    if name == "humeral_rotation":
        t = measurement("shoulder_rotation_time_s")
        span = measurement("shoulder_rotation_range_deg")
        each = f"{span:g}° in {t:g} s (mean {math.radians(span) / t:.3g} rad/s)"
        return each, each
    if name == "elbow_reach":
        up, down = measurement("elbow_reach_raise_rad_s"), measurement("elbow_reach_lower_rad_s")
        return f"{up:g} rad/s", f"{down:g} rad/s"
    if name == "shoulder_elevation":
        up, down = measurement("mean_raise_rad_s"), measurement("mean_lower_rad_s")
        return (f"{up:g} rad/s (Table I mean, loads 1 and 5)", f"{down:g} rad/s (Table I mean)")
    return "", ""


def arm_card(
    arm: ArmScenario,
    validation_rows=(),
    *,
    task: BlockTask | None = None,
    progress=None,
    simulate=simulate_motion,
) -> dict:
    """{"rows": one per joint (joint, increasing and decreasing speed [rad/s] and [deg/s],
    the paper's (increasing, decreasing) speeds, stall, stall_value, stall_unit, the paper's
    stall), "score": `block_score` of ``task`` (default: the arm file's
    ``[block_task]``, else `DEFAULT_TASK`), "task": ``task``}.
    ``simulate`` runs the speeds' motions (`joint_speed`; by default the arm as its
    mechanism on the system kernel); the shoulder's stall is its joint's alone (the stall
    test of one joint)."""
    tick = progress or (lambda label: None)
    if task is None:
        task = arm.block_task or DEFAULT_TASK
    tick("arm card: joint speeds")
    speeds = joint_speeds(arm, validation_rows, simulate=simulate)
    by = {r["quantity"]: r["model"] for r in validation_rows}
    rows = []
    for j in arm.joints:
        if j.name not in speeds:
            continue
        up, down = speeds[j.name]
        row = {
            "joint": j.name,
            "increasing_rad_s": up,
            "decreasing_rad_s": down,
            "increasing_deg_s": math.degrees(up),
            "decreasing_deg_s": math.degrees(down),
            "paper_speed": _paper_speeds(j.name),
        }
        if j.name == "shoulder_elevation":
            tick("arm card: shoulder elevation stall mass (bisection)")
            row.update(
                stall="stall mass in the hand",
                stall_value=stall_mass(j.servo),
                stall_unit="kg",
                paper_stall=f"{measurement('stall_hand_mass_kg'):g} kg",
            )
        elif j.name == "elbow_reach" and "elbow_stall_mass_kg" in by:
            row.update(
                stall="stall mass at the hand",
                stall_value=by["elbow_stall_mass_kg"],
                stall_unit="kg",
                paper_stall=f"{measurement('elbow_stall_mass_kg'):g} kg",
            )
        else:
            row.update(
                stall="stall torque A·p_s·r/n (no loss)",
                stall_value=j.servo.stall_torque,
                stall_unit="N m",
                paper_stall="",
            )
        rows.append(row)
    moved = {k for k, v in task.travel().items() if v != 0.0}
    missing = moved - set(speeds)
    if missing:  # an arm without one of the task's joints: those joints stay where they are
        task = BlockTask(
            pick={k: v for k, v in task.pick.items() if k not in missing},
            place={k: v for k, v in task.place.items() if k not in missing},
            grasp_time=task.grasp_time,
            release_time=task.release_time,
            name=task.name + f" (without {', '.join(sorted(missing))})",
        )
    return {"rows": rows, "score": block_score(task, speeds), "task": task}


def card_lines(card: dict) -> list[str]:
    """The card as the terminal lines of ``hydroarm arm``."""
    lines = []
    for r in card["rows"]:
        lines.append(
            f"{r['joint']:<20} speed {r['increasing_rad_s']:5.3g} / {r['decreasing_rad_s']:5.3g}"
            f" rad/s ({r['increasing_deg_s']:.0f} / {r['decreasing_deg_s']:.0f} deg/s); "
            f"{r['stall']} {r['stall_value']:.3g} {r['stall_unit']}"
        )
    s = card["score"]
    lines.append(
        f"block transfer score             {s['blocks_per_minute']:9.3g} blocks/min "
        f"({s['block_time_s']:.3g} s per block: moves {s['move_out_s']:.3g} + "
        f"{s['move_back_s']:.3g} s, grasp {s['grasp_s']:.2g} s, release {s['release_s']:.2g} s)"
    )
    return lines
