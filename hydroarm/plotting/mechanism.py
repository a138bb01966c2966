"""Plots of a mechanism's run (``hydroarm arm`` on a mechanism file): joints against time,
stick-figure frames and an animation, in the side view (world x across, z up)."""

from __future__ import annotations

import numpy as np
from PIL import Image

from ..core.tree import forward_kinematics, make_tree_work
from .arm import ANIMATION_DPI, ANIMATION_FPS, write_gif
from .joint import _plt


def stick_points(mechanism, q: np.ndarray) -> np.ndarray:
    """The world positions [m] (records × points × 3) of the stick figure of a mechanism at
    joint positions q (records × joints): the base origin, each joint's origin, and each
    leaf link's centre of mass (its tip). Point k > 0 is drawn from its parent's point."""
    tree = mechanism.tree
    n = mechanism.n
    work = make_tree_work(n)
    R = np.zeros((n, 3, 3))
    p = np.zeros((n, 3))
    leaves = [i for i in range(n) if i not in set(tree.parent.tolist())]
    out = np.zeros((q.shape[0], 1 + n + len(leaves), 3))
    for r in range(q.shape[0]):
        forward_kinematics(tree, np.ascontiguousarray(q[r]), work, R, p)
        out[r, 1 : n + 1] = p
        for k, i in enumerate(leaves):
            out[r, n + 1 + k] = p[i] + R[i] @ tree.com[i]
    return out


def stick_parents(mechanism) -> list[int]:
    """The point each point of `stick_points` is drawn from (−1: none)."""
    tree = mechanism.tree
    n = mechanism.n
    leaves = [i for i in range(n) if i not in set(tree.parent.tolist())]
    return [-1] + [int(j) + 1 for j in tree.parent] + [i + 1 for i in leaves]


def _segments(points: np.ndarray, parents: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """x and z of the figure's segments, NaN-separated, for one line artist."""
    xs, zs = [], []
    for k, j in enumerate(parents):
        if j < 0:
            continue
        xs += [points[j, 0], points[k, 0], np.nan]
        zs += [points[j, 2], points[k, 2], np.nan]
    return np.array(xs), np.array(zs)


def _limits(points: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]]:
    lo = np.nanmin(points, axis=(0, 1))
    hi = np.nanmax(points, axis=(0, 1))
    span = max(hi[0] - lo[0], hi[2] - lo[2], 1e-3) * 0.55
    cx, cz = (hi[0] + lo[0]) / 2, (hi[2] + lo[2]) / 2
    return (cx - span, cx + span), (cz - span, cz + span)


def fig_joints(t: np.ndarray, columns: dict, joints: tuple[str, ...]):
    """Each joint's angle (or position) and the torque (force) the components put on it."""
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name in joints:
        for key, ax in ((f"{name}_angle_deg", ax1), (f"{name}_position_m", ax1),
                        (f"{name}_torque_n_m", ax2), (f"{name}_force_n", ax2)):  # fmt: skip
            if key in columns:
                ax.plot(t, columns[key], label=key)
    ax1.set_ylabel("joint angle [deg] / position [m]")
    ax2.set_ylabel("actuation [N m] / [N]")
    ax2.set_xlabel("time [s]")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


def fig_frames(t: np.ndarray, points: np.ndarray, parents: list[int], n: int = 12):
    """A grid of stick-figure frames (side view: x across, z up)."""
    plt = _plt()
    idx = np.linspace(0, t.size - 1, n).astype(int)
    cols = 4
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 2.6 * rows))
    xlim, zlim = _limits(points)
    for ax, k in zip(axes.ravel(), idx, strict=False):
        x, z = _segments(points[k], parents)
        ax.plot(x, z, "-o", lw=2, ms=3)
        ax.set_xlim(*xlim)
        ax.set_ylim(*zlim)
        ax.set_aspect("equal")
        ax.set_title(f"t = {t[k]:.2f} s", fontsize=8)
        ax.tick_params(labelsize=6)
    for ax in axes.ravel()[len(idx) :]:
        ax.axis("off")
    fig.suptitle(
        "Mechanism side view (x across, z up) [m]; a leaf link drawn to its centre of mass"
    )
    fig.tight_layout()
    return fig


def save_animation(
    t: np.ndarray,
    points: np.ndarray,
    parents: list[int],
    path,
    fps: float = ANIMATION_FPS,
    dpi: float = ANIMATION_DPI,
) -> None:
    """A GIF of the stick figure in the side view at ``fps`` (the run's real time)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    step = max(1, int(round(1.0 / (fps * (t[1] - t[0]))))) if t.size > 1 else 1
    idx = np.arange(0, t.size, step)
    fig = Figure(figsize=(5, 5), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.subplots()
    xlim, zlim = _limits(points)
    ax.set_xlim(*xlim)
    ax.set_ylim(*zlim)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_title("side view (x, z) [m]")
    (line,) = ax.plot([], [], "-o", lw=2, animated=True)
    txt = ax.text(0.02, 0.95, "", transform=ax.transAxes, fontsize=8, animated=True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    frames = []
    for k in idx:
        line.set_data(*_segments(points[k], parents))
        txt.set_text(f"t = {t[k]:.2f} s")
        canvas.restore_region(background)
        ax.draw_artist(line)
        ax.draw_artist(txt)
        rgba = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba())
        frames.append(rgba.convert("RGB"))
    write_gif(frames, path, fps)


def fig_card(name: str, rows: list[dict], traces: dict):
    """The evaluation card of a mechanism file (`hydroarm.analysis.mechanism_card`):
    each joint's speed runs against time, its speeds and time constants each way, and its
    stall payload, one bar per joint."""
    plt = _plt()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    joints = list(traces)
    ax = axes[0, 0]
    for j in joints:
        for k, (t, x) in enumerate(traces[j]):
            ax.plot(t, x, "-" if k == 0 else "--", label=f"{j} ({'up' if k == 0 else 'down'})")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("joint position [deg or m]")
    ax.set_title("speed runs: each valve fully open (a servo's lever end to end)")
    ax.legend(fontsize=7)

    def value(j, q, d=""):
        for r in rows:
            if r["joint"] == j and r["quantity"] == q and r["direction"] == d:
                return r["value"], r["unit"]
        return float("nan"), ""

    x = np.arange(len(joints))
    labels = [j.replace("_", "\n") for j in joints]  # long joint names side by side
    for ax, q, title in (
        (axes[0, 1], "speed", "speed over the middle 80 % of the travel"),
        (axes[1, 0], "time constant (63 %)", "time constant (63 % of the speed) [ms]"),
    ):
        for k, d in enumerate(("increasing", "decreasing")):
            vals = [value(j, q, d)[0] for j in joints]
            ax.bar(x + (k - 0.5) * 0.38, vals, 0.38, label=d)
        units = sorted({value(j, q, "increasing")[1] for j in joints})
        ax.set_xticks(x, labels)
        ax.set_ylabel(", ".join(units))
        ax.set_title(title)
        ax.legend(fontsize=8)
    ax = axes[1, 1]
    vals = [value(j, "stall payload")[0] for j in joints]
    ax.bar(x, vals, 0.5, color="tab:red")
    ax.set_xticks(x, labels)
    ax.set_ylabel("kg")
    ax.set_title("stall payload (worst pose over the travel)")
    fig.suptitle(f"Evaluation card: {name}", fontsize=11)
    fig.tight_layout()
    return fig
