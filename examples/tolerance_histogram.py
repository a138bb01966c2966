"""Histogram of a tolerance study's spread (saturation velocity and time constant).

Usage: python examples/tolerance_histogram.py tolerance.csv tolerance.png
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402


def main(src, dst):
    df = pd.read_csv(src)
    ok = df[~df["failed"]]
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    panels = (
        (axes[0], "saturation_velocity_m_s", 1e3, "saturation velocity [mm/s]"),
        (axes[1], "time_constant_start_s", 1e3, "time constant T' [ms]"),
    )
    for ax, col, scale, label in panels:
        v = ok[col].dropna() * scale
        ax.hist(v, bins=50, color="C0", alpha=0.8)
        ax.axvline(v.mean(), color="k", lw=1)
        ax.set_xlabel(label)
        ax.set_title(
            f"mean {v.mean():.3g}, sd {v.std():.2g} ({100 * v.std() / v.mean():.1f} %)", fontsize=9
        )
    axes[0].set_ylabel("scenarios")
    fig.suptitle(f"Tolerance study: {len(ok)} arms, K, L, V, friction ±10 % (1 sd)")
    fig.tight_layout()
    fig.savefig(dst, dpi=120)
    print(f"written {dst}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
