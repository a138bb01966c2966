"""The UCL arm's joint speeds and time constants three ways, beside the paper's
(docs/mechanism.md, "The card of the UCL arm as a mechanism file"):

- the arm model's card (``hydroarm arm --config examples/ucl-arm.toml``: each joint alone,
  decoupled, on the arm model; :func:`hydroarm.paper.arm_card.joint_speed`'s motions);
- the same motions on the arm as one mechanism (``--mechanism``: the arm file expanded,
  :func:`hydroarm.arm.expand.simulate_arm`, the joint alone in the tree);
- the mechanism file's own card (``hydroarm arm --config examples/ucl-arm-mechanism.toml
  --card``: every joint present, the others held by their servos, the file's pumped supply;
  :func:`hydroarm.analysis.mechanism_card.mechanism_card`).

The time constant is the paper's: from the lever's step until the jack has moved 63 % of
the full valve opening e_o (the servo jacks; the elbow's jack is valve-fed on the
mechanism, so its card has the velocity's time constant only).

Usage: python examples/ucl_card_compare.py <folder>
(writes <folder>/ucl_card_compare.md and <folder>/ucl_card_compare.png)
"""

import math
import pathlib
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hydroarm.analysis.mechanism_card import mechanism_card  # noqa: E402
from hydroarm.arm.config import load_arm  # noqa: E402
from hydroarm.arm.expand import simulate_arm as simulate_expanded  # noqa: E402
from hydroarm.io.circuit import load_circuit  # noqa: E402
from hydroarm.metrics.step import step_metrics  # noqa: E402
from hydroarm.model.lever import step  # noqa: E402
from hydroarm.paper.arm_card import SPEED_DURATION, SPEED_MOTIONS, joint_speeds  # noqa: E402
from hydroarm.paper.arm_validation import _single  # noqa: E402
from hydroarm.paper.data import measurement  # noqa: E402
from hydroarm.reference.arm_decoupled import simulate_decoupled as simulate_arm  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
JOINTS = ("shoulder_elevation", "humeral_rotation", "elbow_reach", "wrist_rotation")
TC = "time constant, start (63 % of e_o)"
REST = 0.5  # [s]: the arm at rest, its servo holding, before the lever's step


def paper() -> dict:
    """{joint: (speed up, speed down [rad/s], time constant up, down [ms])} as the paper
    gives them: the shoulder's Table I means and its no-load transients' mean (24–28 ms,
    theory 23 ms; loaded up to 40 ms), the rotation's 100° in 0.6 s, the reach's speeds."""
    t = measurement("shoulder_rotation_time_s")
    rot = math.radians(measurement("shoulder_rotation_range_deg")) / t
    return {
        "shoulder_elevation": (
            measurement("mean_raise_rad_s"),
            measurement("mean_lower_rad_s"),
            25.8,
            25.8,
        ),
        "humeral_rotation": (rot, rot, math.nan, math.nan),
        "elbow_reach": (
            measurement("elbow_reach_raise_rad_s"),
            measurement("elbow_reach_lower_rad_s"),
            math.nan,
            math.nan,
        ),
        "wrist_rotation": (math.nan, math.nan, math.nan, math.nan),
    }


def arm_runs(arm, simulate) -> dict:
    """{joint: (speed up, speed down [rad/s], time constant up, down [ms])}: the arm card's
    speeds (:func:`~hydroarm.paper.arm_card.joint_speeds`, its motions: each joint alone,
    the lever stepped at t = 0), and the time constants of the same motions from rest (the
    lever held for :data:`REST` first, so that the servo holds its load when it is moved,
    as the paper's transients and the mechanism card start; the jack's position from the
    angle through the crank, x = r·sin(θ/n))."""
    speeds = joint_speeds(arm, simulate=simulate)
    joints = {j.name: j for j in arm.joints}
    out = {}
    for name, ((a0, a1), others) in SPEED_MOTIONS.items():
        j, s = joints[name], joints[name].servo
        taus = []
        for start, end in ((a0, a1), (a1, a0)):
            if name == "elbow_reach":  # valve-fed on the mechanism: no lever time constant
                taus.append(math.nan)
                continue
            held = {k: v for k, v in others.items() if k in joints}
            sc = _single(arm, name, start, end, duration=SPEED_DURATION + REST, others=held)
            y0, y1 = j.lever_for_angle(start), j.lever_for_angle(end)
            sc = sc.replace(inputs={**sc.inputs, name: step(y0, y1, REST)})
            r = simulate(sc)
            t = np.asarray(r.t)
            k = t >= REST
            angle = np.asarray(r.angle(name))[k]
            x = s.crank_radius * np.sin((angle - j.angle_offset) / s.gear_ratio)
            m = step_metrics(t[k], x, valve_opening=s.valve_saturation, target=y1, t_start=REST)
            taus.append(1e3 * m["time_constant_start"])
        out[name] = (*speeds[name], *taus)
    return out


def card_runs(circuit) -> tuple[dict, object]:
    """{joint: (speed up, speed down, time constant up, down)} of a mechanism file's card
    (the elbow, valve-fed, has no lever time constant: NaN), and the card."""
    card = mechanism_card(circuit)
    out = {}
    for name in JOINTS:
        out[name] = (
            card.value(name, "speed", "increasing"),
            card.value(name, "speed", "decreasing"),
            card.value(name, TC, "increasing"),
            card.value(name, TC, "decreasing"),
        )
    return out, card


def rigid_reach() -> object:
    """The mechanism file with its reach coupling replaced by a rigid shoulder extension
    (the coupling's ratio 0: the elbow no longer carries the upper arm): the coupling's
    share of the card."""
    text = (HERE / "ucl-arm-mechanism.toml").read_text()
    rigid = text.replace("ratio = -0.5", "ratio = 0.0")
    assert rigid != text
    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "ucl-arm-rigid-reach.toml"
        path.write_text(rigid)
        return load_circuit(path)


def _f(v, fmt="{:.3g}"):
    return "—" if v != v else fmt.format(v)


def main(folder: str) -> pathlib.Path:
    out = pathlib.Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    arm = load_arm(HERE / "ucl-arm.toml")
    model = arm_runs(arm, simulate_arm)
    expanded = arm_runs(arm, simulate_expanded)
    card, full = card_runs(load_circuit(HERE / "ucl-arm-mechanism.toml"))
    rigid, _ = card_runs(rigid_reach())
    ref = paper()
    lines = [
        "| joint, quantity | paper | arm model (decoupled) | mechanism, joint alone "
        "| mechanism file's card | card, reach rigid | coupling's share |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in JOINTS:
        for k, what in (
            (0, "speed up [rad/s]"),
            (1, "speed down [rad/s]"),
            (2, "time constant up [ms]"),
            (3, "time constant down [ms]"),
        ):
            fmt = "{:.3f}" if k < 2 else "{:.3g}"
            d = 100.0 * (card[name][k] / rigid[name][k] - 1.0)
            lines.append(
                f"| {name.replace('_', ' ')}, {what} | {_f(ref[name][k])} | "
                f"{_f(model[name][k], fmt)} | {_f(expanded[name][k], fmt)} | "
                f"{_f(card[name][k], fmt)} | {_f(rigid[name][k], fmt)} | "
                f"{_f(d, '{:+.1f} %')} |"
            )
    md = out / "ucl_card_compare.md"
    md.write_text("\n".join(lines) + "\n")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    x = np.arange(len(JOINTS))
    series = (
        ("paper", ref),
        ("arm model", model),
        ("joint alone", expanded),
        ("card", card),
        ("card, reach rigid", rigid),
    )
    for ax, ks, title, unit in (
        (axes[0], (0, 1), "speed over the middle 80 % (up solid, down hatched)", "rad/s"),
        (axes[1], (2, 3), "time constant at the start (63 % of e_o)", "ms"),
    ):
        w = 0.08
        for i, (label, data) in enumerate(series):
            for k in ks:
                vals = [data[n][k] for n in JOINTS]
                off = (i * 2 + (k - ks[0]) - 4.5) * w
                ax.bar(
                    x + off,
                    vals,
                    w,
                    color=f"C{i}",
                    hatch="//" if k == ks[1] else None,
                    label=label if k == ks[0] else None,
                )
        ax.set_xticks(x, [n.replace("_", " ") for n in JOINTS], fontsize=8)
        ax.set_ylabel(unit)
        ax.set_title(title, fontsize=10)
        ax.legend(fontsize=8)
    fig.suptitle("UCL arm: the paper, the arm model, the mechanism (joint alone), its card")
    fig.tight_layout()
    png = out / "ucl_card_compare.png"
    fig.savefig(png, dpi=110)
    print(md.read_text())
    for line in full.lines():
        print(line)
    return png


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
