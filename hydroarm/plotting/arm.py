"""Plots of a whole-arm run: joints against time, stick-figure frames, an animation."""

from __future__ import annotations

import os
import tempfile

import numpy as np
from PIL import Image

from ..core.kinematics import crank_angle_trace
from .joint import _plt

ANIMATION_FPS = 20.0  # frames per second of arm.gif (the run's real time)
ANIMATION_DPI = 100.0  # 8 × 4 in: 800 × 400 pixels


def fig_joints(res):
    """Every joint's articulation angle, its load pressure and the supply pressure."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for i, n in enumerate(res.names):
        a1.plot(res.t, np.degrees(res.angle(n)), lw=1.3, label=n)
        a1.plot(
            res.t,
            np.degrees(res.scenario.joint(n).angle_offset + _lever_angle(res, i)),
            "--",
            lw=0.7,
            color=f"C{i}",
        )
        a2.plot(res.t, res.p[:, i] * 1e-5, lw=1.0, label=f"{n} load pressure")
    a2.plot(res.t, res.supply_pressure * 1e-5, "k", lw=1.4, label="supply pressure")
    a1.set_ylabel("joint angle [deg] (dashed: lever)")
    a2.set_ylabel("pressure [bar]")
    a2.set_xlabel("time [s]")
    a1.legend(fontsize=8, loc="best")
    a2.legend(fontsize=7, loc="best")
    a1.grid(alpha=0.3)
    a2.grid(alpha=0.3)
    a1.set_title(res.scenario.name)
    fig.tight_layout()
    return fig


def fig_energy(res, traces=None):
    """The power pack's cumulative energies against time: the pump's hydraulic energy, what
    passed the relief valve, what the joints' valves drew, what their jacks handed to the
    arm and, with the efficiencies, the electric energy drawn from the battery.
    ``traces``: those of ``res.power_traces()`` (names with units), computed when not
    given."""
    plt = _plt()
    tr = res.power_traces() if traces is None else traces
    fig, ax = plt.subplots(figsize=(8, 4.5))
    rows = (
        ("electric", "electric (battery)", "k"),
        ("pump", "pump, hydraulic", "C0"),
        ("relief", "relief valve loss", "C3"),
        ("valves", "drawn by the valves", "C1"),
        ("jacks", "work of the jacks", "C2"),
    )
    for key, label, color in rows:
        e = tr[f"cumulative_{key}_j"]
        if e is not None:
            ax.plot(tr["t_s"], e, lw=1.4, color=color, label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("cumulative energy [J]")
    ax.set_title(f"{res.scenario.name}: power pack energy")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return fig


def _lever_angle(res, i):
    j = res.scenario.joints[i]
    r, n = j.servo.crank_radius, j.servo.gear_ratio
    return crank_angle_trace(np.ascontiguousarray(res.y[:, i]), r, n)


def _draw(ax, pts, alpha=1.0, color="C0"):
    """Side view (x forward, z up) of shoulder–elbow–wrist–hand."""
    chain = np.vstack([np.zeros(3), pts[0], pts[1], pts[2]])
    ax.plot(chain[:, 0], chain[:, 2], "-o", color=color, alpha=alpha, lw=2, ms=3)


def fig_frames(res, n: int = 12):
    """A grid of stick-figure frames (side view) of the arm moving."""
    plt = _plt()
    pts = res.points()
    idx = np.linspace(0, res.t.size - 1, n).astype(int)
    cols = 4
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(2.6 * cols, 2.6 * rows))
    for ax, k in zip(axes.ravel(), idx, strict=False):
        _draw(ax, pts[k])
        ax.plot(pts[: k + 1, 2, 0], pts[: k + 1, 2, 2], lw=0.6, color="grey")
        ax.set_xlim(-0.55, 0.55)
        ax.set_ylim(-0.6, 0.5)
        ax.set_aspect("equal")
        ax.set_title(f"t = {res.t[k]:.2f} s", fontsize=8)
        ax.tick_params(labelsize=6)
    for ax in axes.ravel()[len(idx) :]:
        ax.axis("off")
    fig.suptitle("Arm side view (x forward, z up) [m]; grey: hand path")
    fig.tight_layout()
    return fig


def animation_frames(res, fps: float = ANIMATION_FPS, dpi: float = ANIMATION_DPI):
    """RGB frames (PIL images) of the arm's side and top views at ``fps``.

    The states are decimated to the frame rate first (only those poses are computed), the
    static parts (axes, grid, titles) are drawn once, and each frame redraws only the arm and
    its time label over them (Agg blitting).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    n = res.t.size
    step = max(1, int(round(1.0 / (fps * (res.t[1] - res.t[0]))))) if n > 1 else 1
    idx = np.arange(0, n, step)
    pts = res.points(idx)
    fig = Figure(figsize=(8, 4), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    side, top = fig.subplots(1, 2)
    for ax, title in ((side, "side (x, z)"), (top, "top (x, y)")):
        ax.set_xlim(-0.55, 0.55)
        ax.set_ylim(-0.6, 0.5)
        ax.set_aspect("equal")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    (ls,) = side.plot([], [], "-o", lw=2, animated=True)
    (lt,) = top.plot([], [], "-o", lw=2, color="C1", animated=True)
    txt = side.text(-0.5, 0.42, "", fontsize=8, animated=True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    frames = []
    for i, k in enumerate(idx):
        c = np.vstack([np.zeros(3), pts[i]])
        ls.set_data(c[:, 0], c[:, 2])
        lt.set_data(c[:, 0], c[:, 1])
        txt.set_text(f"t = {res.t[k]:.2f} s")
        canvas.restore_region(background)
        side.draw_artist(ls)
        side.draw_artist(txt)
        top.draw_artist(lt)
        rgba = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba())
        frames.append(rgba.convert("RGB"))  # a copy, made in C
    return frames


def save_animation(res, path, fps: float = ANIMATION_FPS, dpi: float = ANIMATION_DPI) -> None:
    """A GIF of the arm (side and top views, `animation_frames`)."""
    write_gif(animation_frames(res, fps, dpi), path, fps)


def write_gif(frames, path, fps: float) -> None:
    """RGB frames as a looping GIF, every frame mapped to one shared palette (taken from the
    first, middle and last frames); written to a temporary name, then moved."""
    w, h = frames[0].size
    sample = Image.new("RGB", (w, 3 * h))
    for i, f in enumerate((frames[0], frames[len(frames) // 2], frames[-1])):
        sample.paste(f, (0, i * h))
    palette = sample.quantize(colors=255, method=Image.Quantize.MEDIANCUT)
    images = [f.quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    path = os.fspath(path)
    fd, tmp = tempfile.mkstemp(suffix=".gif", dir=os.path.dirname(path) or ".")
    os.close(fd)
    try:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(round(1000 / fps)),
            loop=0,
        )
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
