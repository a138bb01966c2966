"""Margins of each loop of a circuit with several controllers (issue 29; docs/linear.md
"Several loops"): ``hydroarm linearize --loop <controller>`` breaks that controller's loop
at its output, the others closed. Checked on the two-joint hydraulic leg against the model
itself: the hip loop's gain margin predicts the factor on the hip controller's gains at
which the linearised closed loop, rebuilt from the circuit with those gains, has a pole on
the imaginary axis, at the margin's phase crossover frequency."""

import json
import math
import pathlib

import numpy as np

from hydroarm.analysis.circuit_linear import linearize_circuit, loops
from hydroarm.cli import main
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import build

EXAMPLES = pathlib.Path(__file__).resolve().parent.parent / "examples"
LEG = (EXAMPLES / "hydraulic_leg.toml").as_posix()


def _closest_pole(model, w: float) -> complex:
    """The closed loop's pole nearest +jw."""
    p = model.poles
    return complex(p[np.argmin(np.abs(p - 1j * w))])


def test_the_gain_margin_of_one_loop_predicts_where_the_closed_loop_crosses(capsys):
    assert main(["linearize", "--config", LEG, "--loop", "hip_controller", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["loop"] == "hip_controller"
    table = {x["loop"]: x for x in got["loops"]}
    assert set(table) == {"hip_controller", "knee_controller"}
    hip = table["hip_controller"]
    assert hip["valves"] == ["hip_valve"] and hip["loop_open"] is None
    # the loop named is the table's row (the same broken loop)
    assert got["gain_margin_db"] == hip["gain_margin_db"]
    assert got["phase_margin_deg"] == hip["phase_margin_deg"]
    gm, w180 = hip["gain_margin_db"], hip["phase_crossover_rad_s"]
    assert 0.0 < gm < 20.0 and w180 > 0.0
    k = 10.0 ** (gm / 20.0)  # the factor on the loop gain that makes |L(jω₁₈₀)| = 1
    leg = load_circuit(LEG)
    gains = {
        f"hip_controller.{g}": float(
            next(c for c in leg.components if c.name == "hip_controller").values[g]
        )
        for g in ("proportional_gain", "integral_gain")
    }

    def rebuilt(factor: float):
        scaled = {name: v * factor for name, v in gains.items()}
        return linearize_circuit(leg.with_values(scaled), loop="hip_controller")

    at = _closest_pole(rebuilt(k), w180)
    # on the imaginary axis at ω₁₈₀: the rebuilt model's steady state is solved to a
    # residual of 1e-8 and its Jacobian by central differences (error ~ε^(2/3) ≈ 4e-11);
    # 1e-6 of |p| is a factor of 1e-5 on the gain (Re p moves by 1e-3 of |p| per 1 % of
    # gain, below), far inside what any use of a margin needs
    assert abs(at.real) < 1e-6 * abs(at), at
    assert math.isclose(abs(at.imag), w180, rel_tol=1e-6), (at, w180)
    # and it crosses there: 1 % more gain puts the pole in the right half-plane
    above = _closest_pole(rebuilt(1.01 * k), w180)
    assert above.real > 1e-4 * abs(above), above


def test_the_loops_of_the_leg_and_a_bad_loop_is_one_line(capsys):
    leg = load_circuit(LEG)
    found = loops(build(leg))
    assert [(lp.controller, lp.valves) for lp in found] == [
        ("hip_controller", ("hip_valve",)),
        ("knee_controller", ("knee_valve",)),
    ]
    assert main(["linearize", "--config", LEG, "--loop", "hip_valve"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("hydroarm: error: --loop: 'hip_valve'"), err
    assert "hip_controller, knee_controller" in err
    assert main(["linearize", "--load", "1", "--loop", "hip_controller"]) == 2
    assert "--loop: is for circuit files" in capsys.readouterr().err
