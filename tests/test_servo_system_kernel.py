"""A component servo's single run steps its circuit on the system kernel (issue 28: one
physics; hydroarm/model/servo.py ``ServoScenario.run``), and the circuit's energy account
(hydroarm/core/circuit/system.py ``energy_rates``, docs/components.md "Energy").

The servo kernel (hydroarm/reference/servo_kernel.py, on hydroarm/core/servo.py's
declarations) stays as the oracle:
the two are independent codings of the same equations, stepped by the same method at the
same step, so they differ by the order of floating-point operations only. Columns are
compared to 1e-9 of their range, as tests/test_servo_circuit.py does (round-off amplified by
the closed loop measured below 1e-12 of it; a wrong law shows at 1e-4 or more). Energies are
the integrals of powers computed from those states, by the same method: each is compared to
1e-9 of the largest energy of the run (the supply's), the scale its round-off has (a term
summed from pieces of the supply's size, such as the throttle's, carries their absolute
error, not its own relative one).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.cli import main
from hydroarm.core.servo import PARAMETERS, STATE_INDEX
from hydroarm.errors import HydroarmError
from hydroarm.io.schema import load_scenario
from hydroarm.io.sections import parse_toml
from hydroarm.io.servo_circuit import load_servo_circuit, servo_circuit
from hydroarm.metrics.servo import METRIC_INDEX
from hydroarm.model.circuit import build, simulate
from hydroarm.model.servo import run_servos
from hydroarm.model.servo_stepper import ServoStepper
from hydroarm.reference import metrics_on_servo_kernel, run_on_servo_kernel

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "servo_circuit"
# every servo file that ``hydroarm simulate`` runs (an [actuator] section), and a duration
# long enough for its first move (the files' own durations are seconds)
SERVO_FILES = {
    "position_servo": (ROOT / "examples" / "position_servo.toml", 0.1),
    "boom_servo": (ROOT / "examples" / "boom_servo.toml", 0.3),
    "rotary_joint": (ROOT / "examples" / "rotary_joint.toml", 0.2),
    "crank_pump": (DATA / "crank_pump.toml", 0.2),
    "linear_mechanical": (DATA / "linear_mechanical.toml", 0.2),
    "single_rod_pid": (DATA / "single_rod_pid.toml", 0.2),
}
TOLERANCE = 1e-9  # of a column's range, of the run's largest energy (module doc)


def scenario(name):
    path, duration = SERVO_FILES[name]
    return load_scenario(path).replace(duration=duration)


def test_every_servo_example_is_listed():
    """The examples with an [actuator] section that simulate runs are all in SERVO_FILES
    (servo_sensitivity.toml, a [sensitivity] study, runs on the sweep path)."""
    found = {
        p.stem
        for p in (ROOT / "examples").glob("*.toml")
        if "\n[actuator]" in p.read_text() and "\n[sensitivity]" not in p.read_text()
    }
    assert found <= set(SERVO_FILES), found - set(SERVO_FILES)


def column_bound(sc, columns, column):
    """How far a column of the system kernel's run may be from the servo kernel's
    (``columns``): `TOLERANCE` of its range (module doc)."""
    x = columns[column]
    bound = TOLERANCE * max(np.ptp(x), np.max(np.abs(x)))
    if column == "spool_m" and sc.parameters.get("spool_order", 0) == 0:
        # a spool with no dynamics records its demand at the step's end: the servo kernel
        # after the load's dry-friction projection, the circuit's valve before it (the
        # projections run in component order); the friction moves the position by at
        # most h·|v| (the paper joint's rule), the demand by the feedback gain times that
        # (measured: 7.5e-12 m in linear_mechanical, 7.5e-9 of its range)
        gain = sc.parameters.get("feedback_gain", sc.parameters.get("proportional_gain", 1))
        speed = np.max(np.abs(columns.get("velocity_m_s", columns.get("angular_velocity_deg_s"))))
        bound = max(bound, abs(gain) * sc.step * speed)
    return bound


@pytest.mark.parametrize("name", sorted(SERVO_FILES))
def test_servo_run_on_the_system_kernel_gives_the_servo_kernel_numbers(name):
    agrees_with_the_servo_kernel(scenario(name))


def agrees_with_the_servo_kernel(sc):
    """``sc.run()`` steps its circuit on the system kernel and gives the servo kernel's
    columns, energies and summary (module doc)."""
    new = sc.run()
    old = run_on_servo_kernel(sc)
    a, b = old.columns(), new.columns()
    assert list(a) == list(b)
    assert len(a["t_s"]) == len(b["t_s"])
    for column in a:
        x, y = a[column], b[column]
        assert np.max(np.abs(x - y)) <= column_bound(sc, a, column), column
    e_old, e_new = old.energies(), new.energies()
    scale = abs(e_old["supply_energy_j"])
    assert scale > 0.0
    for k in e_old:
        assert abs(e_old[k] - e_new[k]) <= TOLERANCE * scale, (k, e_old[k], e_new[k])
    s_old, s_new = old.summary(), new.summary()
    assert list(s_old) == list(s_new)
    for k in s_old:
        assert math.isclose(s_old[k], s_new[k], rel_tol=1e-8, abs_tol=TOLERANCE * scale), k
    return b


def component(sc, name):
    """The component ``name`` of the scenario's circuit."""
    return next(c for c in sc.circuit.components if c.name == name)


def test_air_at_another_atmosphere_runs_on_the_system_kernel():
    """Air measured at a non-standard atmosphere (the chambers' ``atmospheric_pressure``):
    the servo kernel's numbers, and not those of air at 101325 Pa."""
    base = scenario("crank_pump").replace(duration=0.15)
    assert base.parameters["air_fraction"] > 0.0
    sc = base.replace(atmospheric_pressure=9.0e4)
    assert component(sc, "actuator").values["atmospheric_pressure"] == 9.0e4
    cols = agrees_with_the_servo_kernel(sc)
    at_1_atm = run_on_servo_kernel(base).columns()["pressure_b_bar"]
    assert np.max(np.abs(cols["pressure_b_bar"] - at_1_atm)) > 1e3 * TOLERANCE * np.ptp(at_1_atm)


@pytest.mark.parametrize(
    ("times", "positions"),
    [((0.0, 0.05, 0.15), (0.002, 0.004, 0.003)), ((0.0, 0.05, 0.05), (0.002, 0.002, 0.004))],
    ids=["table", "steps"],
)
def test_a_sine_on_top_of_a_table_runs_on_the_system_kernel(times, positions):
    """A reference table (or steps) plus a sine from its start (`hydroarm.core.lever.evaluate`):
    the signal source's added sine, the servo kernel's numbers to 1e-9 of each column."""
    sc = scenario("crank_pump")
    ref = dataclasses.replace(sc.reference, times=np.array(times), positions=np.array(positions))
    sc = dataclasses.replace(sc, reference=ref)
    assert ref.sine_amplitude != 0.0 and np.ptp(ref.positions) > 0.0
    source = component(sc, "reference")
    assert source.values["amplitude"] == ref.sine_amplitude
    assert source.values["waveform"] == ("table" if times[1] != times[2] else "steps")
    agrees_with_the_servo_kernel(sc)


# Radau on the circuit (integrate_circuit_adaptive: rtol 1e-8, atol 1e-9 of each state's start
# or 1) against Radau on the servo's right-hand side (rtol 1e-9): each holds its local error to
# its rtol, and the closed loop is damped, so the two differ by a small multiple of the looser
# rtol: 1e-7 of each column's range, 10 x that rtol (measured: 4e-10 of A's pressure range
# over the first 50 ms of position_servo, 1.1e-8 of B's over 0.1 s of crank_pump, where no
# projection acts); a wrong law shows far above.
ADAPTIVE_TOLERANCE = 1e-7
# the circuit's absolute tolerance on a state that starts at 0, 1e-9 x max(|s0|, 1), the spool
# [m]: the bound its error may reach where the spool's travel is small (measured on crank_pump:
# 3e-11 m of a 4.8e-4 m travel)
ADAPTIVE_SPOOL_ATOL = 1e-9


@pytest.mark.parametrize(("name", "duration"), [("position_servo", 0.05), ("crank_pump", 0.1)])
def test_the_adaptive_servo_agrees_with_the_servo_kernels_radau(name, duration):
    """method = "adaptive" steps the servo's circuit with Radau on the system kernel
    (docs/components.md), the servo kernel's Radau the oracle, where no projection acts (an
    electronic PI servo on a pump before its chamber touches the cavitation floor; a crank
    under mechanical feedback, a first-order spool, a lagged relief valve that stays shut, an
    accumulator and air)."""
    sc = dataclasses.replace(
        scenario(name).replace(duration=duration), method="adaptive", record_every=100
    )
    new, old = sc.run(), run_on_servo_kernel(sc)
    a, b = old.columns(), new.columns()
    assert len(a["t_s"]) == len(b["t_s"]) == round(duration / (100 * sc.step)) + 1
    # the same record times, written as k·(K·h) and as k·h·K (round-off)
    np.testing.assert_allclose(a["t_s"], b["t_s"], rtol=0.0, atol=1e-15)
    moved = "position_m" if "position_m" in a else "angle_deg"
    speed = "velocity_m_s" if "velocity_m_s" in a else "angular_velocity_deg_s"
    for column in (moved, speed, "spool_m", "pressure_a_bar", "pressure_b_bar", "supply_bar"):
        x, y = a[column], b[column]
        bound = ADAPTIVE_TOLERANCE * max(np.ptp(x), np.max(np.abs(x)))
        if column == "spool_m":  # the circuit's atol on the spool, which starts at 0 [m]
            bound += ADAPTIVE_SPOOL_ATOL
        assert np.max(np.abs(x - y)) <= bound, column
    assert np.ptp(a[moved]) > 0.1 * np.max(np.abs(a[moved]))  # the run moved


# rk4 at 1 µs on the same circuit (its error: ~1e-9 of A's pressure range, a tenth of its
# 10 µs error, which is 1e-8 of it here) against Radau at rtol 1e-8 (measured: 4e-9 of each
# column's range with either record spacing; the old split at the records: 3e-3 of A's range
# with 1 ms records, 4e-5 with 0.1 ms); 1e-6 leaves room for the global error's growth on
# another machine's round-off while far below a projection acting at the records
FLOOR_TOLERANCE = 1e-6


def test_the_adaptive_servo_resolves_the_cavitation_floor():
    """Chamber A of position_servo sits at the cavitation floor from 52 ms and leaves it at
    69 ms: Radau projected after each of its own steps (not at the records) agrees with rk4
    at 1 µs there, and the records, 1 ms or 0.1 ms apart, sample one trajectory."""
    base = scenario("position_servo").replace(duration=0.08)
    fine = dataclasses.replace(base, method="rk4", step=1e-6, record_every=100).run().columns()
    a = fine["pressure_a_bar"]
    floor = a <= a.min()  # on the floor, and off it before the end
    assert np.any(floor) and not floor[-1]
    runs = {}
    for every in (100, 10):  # records every 1 ms and every 0.1 ms
        sc = dataclasses.replace(base, method="adaptive", record_every=every)
        runs[every] = sc.run().columns()
        sub = slice(None, None, every // 10)  # the 0.1 ms rk4 records at these times
        for column in ("pressure_a_bar", "pressure_b_bar", "position_m", "spool_m"):
            ref = fine[column][sub]
            bound = FLOOR_TOLERANCE * np.ptp(fine[column])
            assert np.max(np.abs(runs[every][column] - ref)) <= bound, (every, column)
    for column in ("pressure_a_bar", "position_m"):  # the common times: one trajectory
        x, y = runs[100][column], runs[10][column][::10]
        assert np.max(np.abs(x - y)) <= FLOOR_TOLERANCE * np.ptp(fine[column]), column


def test_the_adaptive_servo_refuses_what_it_cannot_do():
    """Dry friction is refused before work as on the servo kernel; a stepper (fixed steps)
    and the on-the-fly metrics (no fixed step to observe) refuse the method; the summary is
    the records'."""
    sc = dataclasses.replace(
        scenario("position_servo").replace(duration=0.01), method="adaptive", record_every=100
    )
    new = sc.run()
    friction = dataclasses.replace(
        scenario("linear_mechanical").replace(duration=0.01), method="adaptive"
    )
    with pytest.raises(HydroarmError) as err:
        friction.run()
    assert err.value.field == "solver.method" and "dry friction" in str(err.value)
    with pytest.raises(HydroarmError) as err:
        new.metrics()
    assert err.value.field == "solver.method" and "fixed-step" in str(err.value)
    with pytest.raises(HydroarmError) as err:
        ServoStepper(sc)
    assert err.value.field == "solver.method"
    assert math.isfinite(new.summary()["peak_pressure_bar"])  # from the records


def _initial_cases():
    """(file, state, its start as a function of the servo's named parameters): every state
    of the servo that is not the load's, the chambers' or the spool's position."""
    return [
        ("position_servo", "integral", lambda p: 0.3 * p["spool_max"] / p["integral_gain"]),
        ("single_rod_pid", "integral", lambda p: -0.3 * p["spool_max"] / p["integral_gain"]),
        ("linear_mechanical", "integral", lambda p: 2.0),  # mechanical: held, acts on nothing
        (
            "boom_servo",
            "spool_velocity",
            lambda p: 0.2 * p["spool_frequency"] * p["spool_max"],
        ),
        ("position_servo", "supply_pressure", lambda p: 5.0e6),  # a pump's: 50 bar
        ("single_rod_pid", "supply_pressure", lambda p: 0.8 * p["supply_pressure"]),  # fixed
        ("crank_pump", "relief_opening", lambda p: 0.5 * p["relief_max_opening"]),
        ("rotary_joint", "supply_energy", lambda p: 3.0),
        ("position_servo", "compression_energy", lambda p: -1.5),
    ]


@pytest.mark.parametrize(("name", "state", "value"), _initial_cases())
def test_every_initial_state_runs_on_the_system_kernel(name, state, value):
    """[initial] states given apart from the parameters start the circuit's (the pid's
    ``initial_integral``, the valves' ``initial_spool_velocity``, the supply node or a fixed
    supply's source, the relief valve's ``initial_opening``, an energy's offset): the servo
    kernel's numbers to 1e-9 of each column's range, and the state's own column from that
    start (what the default start would not give)."""
    sc = scenario(name).replace(duration=0.05, derivative_gain=0.0)
    named = dict(zip((n for n, _, _ in PARAMETERS), sc.vector(), strict=True))
    v = float(value(named))
    assert v != sc.initial_state_default(state)
    sc = dataclasses.replace(sc, initial={**sc.initial, state: v})
    new, old = sc.run(), run_on_servo_kernel(sc)
    i = STATE_INDEX[state]
    assert old.states[0, i] == v == new.states[0, i]
    a = old.columns()
    for column, x in a.items():
        y = new.columns()[column]
        assert np.max(np.abs(x - y)) <= column_bound(sc, a, column), column
    for k in (i, STATE_INDEX["position"]):
        x, y = old.states[:, k], new.states[:, k]
        assert np.max(np.abs(x - y)) <= TOLERANCE * max(np.ptp(x), np.max(np.abs(x))), k
    e_old, e_new = old.energies(), new.energies()
    scale = abs(e_old["supply_energy_j"])
    for k in e_old:
        assert abs(e_old[k] - e_new[k]) <= TOLERANCE * scale, k


def test_a_relief_opening_without_a_relief_valve_is_refused_by_the_circuit():
    """The servo kernel holds such an opening (a constant leak where relief_max_opening is
    set): no circuit form, so run(), the batch path, the metrics and the stepper refuse it
    with one line naming the field, before any work (no other kernel runs it)."""
    sc = scenario("single_rod_pid").replace(derivative_gain=0.0, relief_max_opening=1e-8)
    sc = dataclasses.replace(sc, initial={"relief_opening": 5e-9})
    for work in (sc.run, lambda: run_servos([sc]), sc.metrics_vector, lambda: ServoStepper(sc)):
        with pytest.raises(HydroarmError, match="no relief valve") as e:
            work()
        assert e.value.field == "initial.relief_opening"


# a crank with piston and gearbox friction that sticks at the start and slides once the sine
# moves the lever (crank_pump's sine starts at 0.1 s)
CRANK_FRICTION = {
    "coulomb_friction": 5.0,
    "breakaway_friction": 10.0,
    "gearbox_friction_torque": 0.01,
    "gearbox_loss_at_stall": 0.2,
    "gearbox_loss_exponent": 1.5,
    "rated_load_pressure": 40.0e5,
}
DERIVATIVE = {  # electronic feedback with a derivative gain on crank_pump (mechanical there)
    "feedback_kind": 1.0,
    "proportional_gain": 0.2,
    "derivative_gain": 2.0e-4,
}
EXACT_FORMS = {
    # the PID's derivative from the sensor's rate: the rod's (a mass), an angle's (a rotary
    # load), a crank's rod (a slave node) and its joint
    "pid_mass": ("single_rod_pid", {}, "rk4"),
    "pid_rotary": ("rotary_joint", {"derivative_gain": 2.0e-5}, "rk4"),
    "pid_crank_rod": ("crank_pump", {**DERIVATIVE, "sense_actuator": 1.0}, "rk4"),
    "pid_crank_joint": ("crank_pump", {**DERIVATIVE, "sensor_gain": 7.5e-3}, "rk4"),
    # a crank's dry friction: the torque arm at the step's start in both kernels
    "friction_crank": ("crank_pump", CRANK_FRICTION, "rk4"),
    "friction_crank_euler": ("crank_pump", CRANK_FRICTION, "euler"),
    "friction_crank_paper_arm": (
        "crank_pump",
        {**CRANK_FRICTION, "kinematic_torque_arm": 0.0},
        "rk4",
    ),
    "friction_crank_pid": (
        "crank_pump",
        {**CRANK_FRICTION, **DERIVATIVE, "sense_actuator": 1.0},
        "rk4",
    ),
}


@pytest.mark.parametrize("case", sorted(EXACT_FORMS))
def test_a_pid_derivative_and_a_cranks_dry_friction_run_on_the_system_kernel(case):
    """A PID derivative gain (the circuit's ``pid`` takes the ``position_sensor``'s rate
    g·ẋ, the servo kernel's exact derivative on the measurement) and a crank's dry friction
    (the torque arm at the step's start, the drive force at its end, in both kernels):
    the servo kernel's numbers to 1e-9 of the range, as every other servo."""
    name, values, method = EXACT_FORMS[case]
    sc = dataclasses.replace(scenario(name).replace(**values), method=method)
    cols = agrees_with_the_servo_kernel(sc)
    if "friction" in case:  # the friction sticks and lets go: it acts
        v = cols["angular_velocity_deg_s"]
        assert np.sum(v == 0.0) > 10 and np.sum(v != 0.0) > 10
    if "pid" in case:  # the derivative acts: far above the tolerance
        plain = sc.replace(derivative_gain=0.0).run().columns()
        column = "position_m" if "position_m" in cols else "angle_deg"
        x = cols[column]
        assert np.max(np.abs(x - plain[column])) > 1e3 * TOLERANCE * np.ptp(x)


@pytest.mark.parametrize("name", ["crank_pump", "boom_servo"])
def test_a_displaced_spool_at_the_start_runs_on_the_system_kernel(name):
    """[initial] spool: the valves' ``initial_spool`` (a first-order spool in crank_pump, a
    second-order one in boom_servo), the servo kernel's numbers to 1e-9 of the range."""
    sc = scenario(name).replace(duration=0.05)
    sc = dataclasses.replace(sc, initial={**sc.initial, "spool": 0.4e-3})
    new, old = sc.run(), run_on_servo_kernel(sc)
    assert old.columns()["spool_m"][0] == 0.4e-3 == new.columns()["spool_m"][0]
    for column, x in old.columns().items():
        y = new.columns()[column]
        assert np.max(np.abs(x - y)) <= TOLERANCE * max(np.ptp(x), np.max(np.abs(x))), column


# ---------------------------------------------------------------- energy account ---
def energy_run(name, duration, reference=1.0e5, edit=None):
    path = SERVO_FILES[name][0]
    if edit is None:
        circuit = load_servo_circuit(path)
    else:
        doc = parse_toml(edit(path.read_text()), path.name)
        circuit = servo_circuit(doc, path.parent, path.stem)
    circuit = dataclasses.replace(circuit, duration=duration)
    return circuit, simulate(build(circuit, energy=True, energy_reference_pressure=reference))


PAPER_ARM = lambda text: text.replace('torque_arm = "kinematic"', 'torque_arm = "paper"')  # noqa: E731


@pytest.mark.parametrize("name", ["crank_pump", "rotary_joint", "crank_paper_arm"])
def test_energy_account_leaves_the_run_unchanged_and_closes(name):
    """``crank_paper_arm``: the crank carries the rod's force by r/n, not g', and makes or
    loses the difference, (g_f − g')·F_s·v_m, counted as its own (``crank.energy``)."""
    if name == "crank_paper_arm":
        circuit, res = energy_run("crank_pump", 0.1, edit=PAPER_ARM)
        assert res.energies()["crank.energy"] != 0.0
    else:
        circuit, res = energy_run(name, 0.1)
    plain = simulate(build(circuit))
    n = res.compiled.n_dynamic
    assert np.array_equal(plain.states, res.states[:, :n])  # bit for bit
    assert res.states.shape[1] == n + len(res.compiled.energy_states)
    e = res.energies()
    total = max(abs(v) for v in e.values())
    # Σ_c P_c = 0 at every evaluation (no node at the cavitation floor in these runs):
    # the balance is the round-off of adding terms of the largest one's size
    assert total > 0.0
    assert abs(e["balance"]) <= 1e-12 * total


def test_energy_terms_add_up_to_each_components_power():
    """Each component's terms add up to its absorbed power (port_quantities, the
    ``<component>_power_w`` column), whose trapezoid over the records (``energy()``) the
    integrated account matches to the trapezoid's error: O((record step)²·P''), bounded
    here by 1e-3 of the largest energy with records every 10 steps of 10 µs."""
    circuit, res = energy_run("position_servo", 0.05)
    res = simulate(
        build(
            dataclasses.replace(circuit, record_every=10),
            energy=True,
            energy_reference_pressure=0.0,  # absolute: the trapezoid's reference
        )
    )
    e = res.energies()
    trapezoid = res.component_energies()
    scale = max(abs(v) for v in trapezoid.values())
    for comp in (c.name for c in circuit.components):
        summed = sum(v for k, v in e.items() if k.split(".")[0] == comp)
        assert abs(summed - trapezoid[comp]) <= 1e-3 * scale, comp


def test_reference_pressure_moves_energy_between_terms_not_the_balance():
    """Absolute (p_ref = 0) and from the tank (1 bar): the tank absorbs p_ref·∫q in the
    first and nothing in the second; the pump's shaft work, a flow through it, is the same."""
    _, gauge = energy_run("crank_pump", 0.05, 1.0e5)
    _, absolute = energy_run("crank_pump", 0.05, 0.0)
    g, a = gauge.energies(), absolute.energies()
    assert g["tank.energy"] == 0.0 and a["tank.energy"] != 0.0
    assert math.isclose(g["pump.shaft"], a["pump.shaft"], rel_tol=1e-9)
    scale = abs(a["pump.shaft"])
    assert abs(a["balance"]) <= 1e-12 * max(scale, abs(a["tank.energy"]))


def test_energies_of_a_circuit_without_the_account_is_one_clear_error():
    circuit = dataclasses.replace(load_servo_circuit(SERVO_FILES["crank_pump"][0]), duration=0.01)
    res = simulate(build(circuit))
    with pytest.raises(HydroarmError) as err:
        res.energies()
    assert err.value.field == "energy" and "energy=True" in str(err.value)


def test_initial_states_take_every_path_of_the_run(tmp_path):
    """States given at the start, on every path that steps what run() steps: the batch
    (run_servos: its rows the single runs bit for bit), the piece-by-piece stepper (the run's
    final state bit for bit) and the on-the-fly metrics (the servo kernel's to 1e-9 of each
    quantity's scale, the energies of the supplied energy, as
    tests/test_circuit_observers.py holds them)."""
    sc = scenario("position_servo").replace(duration=0.02, record_every=50)
    P = dict(zip((n for n, _, _ in PARAMETERS), sc.vector(), strict=True))
    given = {
        "integral": 0.3 * P["spool_max"] / P["integral_gain"],
        "spool_velocity": 0.1 * P["spool_frequency"] * P["spool_max"],
        "supply_pressure": 5.0e6,
        "relief_opening": 0.2 * P["relief_max_opening"],
        "throttle_energy": 2.0,
    }
    sc = dataclasses.replace(sc, initial={**sc.initial, **given})
    single = sc.run()
    other = sc.replace(mass=2.0 * P["mass"])
    batch = run_servos([sc, other])
    assert np.array_equal(batch[0].states, single.states)
    assert np.array_equal(batch[1].states, other.run().states)
    st = ServoStepper(sc)
    st.advance_to(sc.duration)
    assert np.array_equal(st.servo_state(), single.states[-1])
    old, new = metrics_on_servo_kernel(sc), sc.metrics_vector()
    i = METRIC_INDEX
    supplied = abs(old[i["supply_energy"]])
    for name in ("supply_energy", "throttle_energy", "compression_energy", "actuator_work"):
        assert abs(old[i[name]] - new[i[name]]) <= TOLERANCE * supplied, name
    for name in ("peak_pressure", "final_pressure_a", "peak_supply_pressure"):
        assert abs(old[i[name]] - new[i[name]]) <= TOLERANCE * old[i["peak_pressure"]], name
    span = np.ptp(single.state("position"))
    assert span > 0.0
    assert abs(old[i["final_position"]] - new[i["final_position"]]) <= TOLERANCE * span


def test_simulate_runs_an_adaptive_servo_file_on_the_system_kernel(tmp_path, capsys):
    """``hydroarm simulate`` of a servo file with method = "adaptive": its circuit's Radau on
    the system kernel (what ServoScenario.run steps), the summary from the records."""
    text = SERVO_FILES["position_servo"][0].read_text()
    text = text.replace('duration = "3 s"', 'duration = "20 ms"')
    assert 'method = "rk4"' in text
    path = tmp_path / "adaptive_servo.toml"
    path.write_text(text.replace('method = "rk4"', 'method = "adaptive"'))
    assert main(["simulate", "--config", str(path), "--metrics"]) == 0
    got = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    sc = load_scenario(path)
    assert sc.method == "adaptive"
    want = sc.run().summary()
    assert got["final_position_m"] == want["final_position_m"]
    assert got["peak_pressure_bar"] == want["peak_pressure_bar"]
