"""Derived-parameter slots (issue 28 speed): a component declares constants of its parameters
(:class:`hydroarm.core.circuit.declare.Derived`), which the kernel computes once a run in
its own copy of P (:func:`hydroarm.core.circuit.system.with_derived`) and the laws read
like parameters.

Checks that can fail: the slots sit after the parameters and before the arrays; a formula
that names no parameter is refused at import; the kernel's values (the generated
``derive_of``) equal the Python ones of the compiled P bit for bit and do not depend on the
slots' contents; a row whose parameter was written into the table without its derived
quantities runs as the row built by ``parameter_vector`` (the kernel derives them itself).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hydroarm.core.circuit.components import TYPES
from hydroarm.core.circuit.declare import Component, Derived, Param
from hydroarm.core.circuit.system import with_derived
from hydroarm.io.circuit import load_circuit
from hydroarm.model.circuit import build, simulate_many

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _twice(gain):
    return 2.0 * gain


def test_derived_slots_follow_the_parameters_before_the_arrays():
    decl = Component(
        "probe",
        "",
        parameters=(Param("gain", "", 1.0), Param("bias", "", 0.0)),
        states=(),
        ports=(),
        derived=(Derived("double_gain", "", _twice),),
        arrays=(Param("times", "s", None),),
    )
    par, _, _ = decl.indices()
    assert (par.gain, par.bias, par.double_gain, par.times) == (0, 1, 2, 3)
    assert decl.derive({"gain": 1.5, "bias": 0.0}) == [3.0]


def test_a_formula_naming_no_parameter_is_refused():
    def bad(gian):
        return gian

    with pytest.raises(ValueError, match="gian"):
        Component("probe", "", (Param("gain", "", 1.0),), (), (), derived=(Derived("g", "", bad),))


def test_the_valves_and_orifices_declare_their_flow_coefficients():
    declared = [m.DECLARATION for m in TYPES.values() if m.DECLARATION.derived]
    assert {d.type for d in declared} >= {"valve_4_3", "relief_valve", "orifice", "check_valve"}


@pytest.mark.parametrize(
    "name", ["circuit_position_servo.toml", "orifice_rig.toml", "counterbalance.toml"]
)
def test_kernel_derives_what_python_does_whatever_the_slots_hold(name):
    compiled = build(load_circuit(EXAMPLES / name))
    np.testing.assert_array_equal(with_derived(compiled.P, compiled.net), compiled.P)
    scrambled = compiled.P.copy()
    for c, decl in enumerate(compiled.decls):
        n, po = len(decl.parameters), compiled.poff[c]
        scrambled[po + n : po + n + len(decl.derived)] = np.nan
    assert with_derived(scrambled, compiled.net).tobytes() == compiled.P.tobytes()


def test_a_table_column_written_without_its_derived_quantities_runs_right():
    circuit = load_circuit(EXAMPLES / "circuit_position_servo.toml").replace(duration=0.02)
    compiled = build(circuit)
    key = "valve.spool_diameter"
    refreshed = compiled.parameter_vector({key: 0.011})
    stale = compiled.P.copy()
    stale[compiled.parameter_index[key]] = 0.011
    assert stale.tobytes() != refreshed.tobytes()  # the valve's k is still the old one
    _, S, bad = simulate_many(compiled, np.stack([refreshed, stale, compiled.P]))
    assert (bad == -1).all()
    assert S[0].tobytes() == S[1].tobytes()
    assert S[0].tobytes() != S[2].tobytes()
