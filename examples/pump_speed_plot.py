"""Figure of examples/pump_speed.toml: the supply pressure against its closed forms (the
compressed hose before the relief cracks, the relief's steady state after the run-up), and
the pump's and the relief's flows.

Usage: python examples/pump_speed_plot.py OUTDIR      (writes OUTDIR/pump_speed.png)

The closed forms are the ones tests/test_circuit_pump_speed.py checks the run against.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from hydroarm.core.components import relief_flow, relief_static_opening
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import Circuit, build, simulate

EXAMPLE = Path(__file__).resolve().parent / "pump_speed.toml"


def values(circuit: Circuit) -> dict[str, float]:
    """The example's numbers in SI, read from the compiled circuit (defaults included), so
    that the closed forms follow the file."""
    cc = build(circuit)
    comp = {c.name: vals for c, vals in zip(circuit.components, cc.values, strict=True)}
    rv = comp["relief"]
    return {
        "p_t": comp["tank"]["pressure"],
        "p_0": circuit.initial_pressure,
        "accel": comp["motor"]["rate"],
        "ramp_end": comp["motor"]["end_time"],
        "D": comp["pump"]["displacement"],
        "C_l": comp["pump"]["leakage"],
        "C": comp["hose"]["volume"] / comp["hose"]["bulk_modulus"],
        "p_c": rv["cracking_pressure"],
        "p_nom": rv["nominal_pressure_drop"],
        "k_cs": rv["spring_slope"],
        "k_cf": rv["flow_force_slope"],
        "q_nom": rv["nominal_flow"],
        "p_trans": rv["transition_pressure"],
    }


def hose_pressure(t, v: dict[str, float]):
    """Supply pressure [Pa] while the relief is shut, the speed ramping ω = α·t: with
    u = p − p_T, C·u̇ = D·α·t − C_l·u, so (T = C/C_l)
    u(t) = (D·α/C_l)·(t − T·(1 − e^(−t/T))) + u(0)·e^(−t/T)."""
    t = np.asarray(t, float)
    T = v["C"] / v["C_l"]
    u0 = v["p_0"] - v["p_t"]
    return (
        v["p_t"]
        + v["D"] * v["accel"] / v["C_l"] * (t - T * (1.0 - np.exp(-t / T)))
        + u0 * (np.exp(-t / T))
    )


def relief_steady_pressure(v: dict[str, float], w: float | None = None) -> float:
    """Supply pressure [Pa] at which the static relief valve (Hopsan's defaults) passes the
    pump's flow at speed w [rad/s] (default: full speed, the ramp's end),
    D·ω − C_l·(p − p_T) = x*(p)·√(p − p_T): bisection on the shared laws of the relief valve
    (hydroarm.core.components)."""
    if w is None:
        w = v["accel"] * v["ramp_end"]
    root = math.sqrt(v["p_nom"])
    c_s = root / v["k_cs"]
    c_f = 1.0 / (v["k_cf"] * root)
    x_max = v["q_nom"] / root

    def excess(p: float) -> float:
        x = relief_static_opening(p, v["p_t"], v["p_c"], c_s, c_f, x_max)
        q_relief = relief_flow(x, p, v["p_t"], v["p_trans"])
        return v["D"] * w - v["C_l"] * (p - v["p_t"]) - q_relief

    lo, hi = v["p_c"], v["p_c"] + 50.0e5
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) > 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


def main(outdir: str) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    circuit = load_circuit(EXAMPLE)
    v = values(circuit)
    df = simulate(circuit).to_pandas()
    t = df["t_s"].to_numpy()
    shut = df["relief_open"].to_numpy() < 0.5
    p_ss = relief_steady_pressure(v)
    fig, (a1, a3, a2) = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    a1.plot(t, df["supply_pressure_bar"], label="supply (simulated)")
    a1.plot(t[shut], hose_pressure(t[shut], v) * 1e-5, "k--", lw=1, label="∫q dt / C (relief shut)")
    a1.axhline(p_ss * 1e-5, color="C3", ls=":", label=f"relief steady state {p_ss * 1e-5:.2f} bar")
    a1.axhline(v["p_c"] * 1e-5, color="0.6", lw=0.8, label="cracking pressure")
    a1.set_ylabel("pressure [bar]")
    a1.legend(fontsize="small", loc="lower right")
    a1.grid(True, alpha=0.3)
    a1.set_title("pump run-up 0 → 1500 rpm in 1 s against a relief valve")
    p_c = v["p_c"] * 1e-5
    a3.plot(t[~shut], df["supply_pressure_bar"].to_numpy()[~shut] - p_c, label="simulated")
    speed = df["motor_speed_signal"].to_numpy()
    quasi = [relief_steady_pressure(v, w) * 1e-5 - p_c for w in speed[~shut]]
    a3.plot(t[~shut], quasi, "k--", lw=1, label="relief's steady state at the pump's flow")
    a3.set_ylabel("above cracking [bar]")
    a3.legend(fontsize="small", loc="lower right")
    a3.grid(True, alpha=0.3)
    a2.plot(t, df["pump_flow_lpm"], label="pump")
    a2.plot(t, df["relief_flow_lpm"], label="relief valve")
    a2.set_ylabel("flow [L/min]")
    a2.set_xlabel("time [s]")
    a2.legend(fontsize="small")
    a2.grid(True, alpha=0.3)
    fig.tight_layout()
    out = Path(outdir) / "pump_speed.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"written {out}")
    return out


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
