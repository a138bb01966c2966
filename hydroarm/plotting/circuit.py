"""Figures of a circuit's run: chosen outputs against time, one panel per unit."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def _unit(name: str) -> str:
    for suffix, label in (
        ("_pressure_bar", "pressure [bar]"),
        ("_flow_lpm", "flow [L/min]"),
        ("_power_w", "power [W]"),
        ("_position_m", "position [m]"),
        ("_velocity_m_s", "velocity [m/s]"),
        ("_angle_deg", "angle [°]"),
        ("_force_n", "force [N]"),
        ("_torque_n_m", "torque [N m]"),
        ("_signal", "signal [SI]"),
    ):
        if name.endswith(suffix):
            return label
    return "value"


def plot_outputs(t: np.ndarray, outputs: Mapping[str, np.ndarray], title: str = "", ax=None):
    """Outputs (name → values) against time t [s], grouped by unit into stacked panels (or
    all on ``ax`` when given). Returns the figure."""
    import matplotlib.pyplot as plt

    groups: dict[str, list[str]] = {}
    for name in outputs:
        groups.setdefault(_unit(name), []).append(name)
    if ax is not None:
        axes = [ax] * len(groups)
        fig = ax.figure
    else:
        fig, axs = plt.subplots(
            max(len(groups), 1), 1, sharex=True, figsize=(8, 2.4 * max(len(groups), 1) + 0.6)
        )
        axes = list(np.atleast_1d(axs))
    for a, (label, names) in zip(axes, groups.items(), strict=False):
        for name in names:
            a.plot(t, outputs[name], label=name)
        a.set_ylabel(label)
        a.grid(True, alpha=0.3)
        a.legend(fontsize="small", loc="best")
    axes[-1].set_xlabel("time [s]")
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return fig
