"""Write examples/fit_circuit_measured.csv: a SYNTHETIC measured run of the orifice rig
(examples/orifice_rig.toml) for the fit example examples/fit_circuit.toml (docs/fit.md,
"Any system").

Truth: orifice.area = 2.6 mm², hose.bulk_modulus = 1.5 GPa (the rig file says 3 mm² and
1.2 GPa: the fit starts there). The rig's run (`hydroarm simulate`) is sampled every 2 ms
from 0 to 0.3 s; seeded white noise is added: 0.5 bar on the pressure (written in psi, as a
bench transducer might log it) and 0.1 L/min on the orifice flow; time in ms. Run:

    python examples/fit_circuit_data.py [OUT.csv]

The file is rewritten byte for byte (tests/test_fit_system.py checks it).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import simulate

HERE = Path(__file__).resolve().parent
TRUTH = {"orifice.area": 2.6e-6, "hose.bulk_modulus": 1.5e9}  # [m²], [Pa]
NOISE_BAR = 0.5
NOISE_LPM = 0.1
PSI = 0.0689475729  # bar per psi
SEED = 29


def measured() -> str:
    rig = load_circuit(HERE / "orifice_rig.toml").with_values(TRUTH)
    cols = simulate(rig).columns()
    t = np.arange(0.0, 0.3 + 1e-9, 0.002)
    rng = np.random.default_rng(SEED)
    p = np.interp(t, cols["t_s"], cols["supply_pressure_bar"]) + rng.normal(0, NOISE_BAR, t.size)
    q = np.interp(t, cols["t_s"], cols["orifice_flow_lpm"]) + rng.normal(0, NOISE_LPM, t.size)
    lines = [
        "# SYNTHETIC data (examples/fit_circuit_data.py): the orifice rig run with",
        "# orifice.area = 2.6 mm**2 and hose.bulk_modulus = 1.5 GPa, sampled every 2 ms,",
        f"# white noise {NOISE_BAR} bar on the pressure and {NOISE_LPM} L/min on the flow "
        f"(seed {SEED})",
        "time,pressure,flow",
    ]
    lines += [f"{a * 1e3:.1f},{b / PSI:.3f},{c:.4f}" for a, b, c in zip(t, p, q, strict=True)]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE / "fit_circuit_measured.csv"
    out.write_text(measured())
    print(f"written {out}")
