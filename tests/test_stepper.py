"""The steppers (hydroarm/model/stepper.py, hydroarm/arm/stepper.py,
hydroarm/model/servo_stepper.py): a joint, the whole arm or a component servo advanced piece
by piece gives the whole run's trajectory bit for bit, whatever the pieces (the servo: its
circuit on the system kernel, as its run).

Bit for bit, not to a tolerance: the steppers call the same step kernels with the same
floating-point operations in the same order (a held lever is a one-point lever table; the
arm's, the input of its lever source on the system kernel)."""

import math
import pathlib

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm.config import load_arm
from hydroarm.arm.expand import arm_circuit, simulate_arm
from hydroarm.arm.stepper import ArmStepper
from hydroarm.errors import HydroarmError
from hydroarm.integrators.fixed import RK4, integrate
from hydroarm.model.circuit import build, simulate
from hydroarm.model.lever import LeverInput
from hydroarm.model.servo_stepper import ServoStepper
from hydroarm.model.stepper import OUTPUTS, JointStepper

DURATION = 0.07  # [s] of the raise test: 7000 steps of 10 us (the motion under way)


def raise_test(method):
    return ha.saturation_test(
        ha.shoulder_elevation(), ha.paper_load(6), "raise", method=method, duration=DURATION
    )


def drive(stepper, sc, chunk_steps, n_chunks):
    """Advance a stepper chunk by chunk, the lever set to the scenario's at each chunk start;
    the states (θ₂, ω, p) at the chunk ends, the start included."""
    out = [(stepper.outputs()["theta"], stepper.outputs()["omega"], stepper.outputs()["p"])]
    for _ in range(n_chunks):
        stepper.lever = float(sc.lever(stepper.t)[0])
        stepper.advance(chunk_steps * sc.step)
        o = stepper.outputs()
        out.append((o["theta"], o["omega"], o["p"]))
    return np.array(out)


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("chunk", [7, 100])  # 70 us (not a divisor of the run) and 1 ms
def test_joint_stepper_is_simulate_bit_for_bit(method, chunk):
    sc = raise_test(method)
    n = sc.nsteps // chunk
    ref = ha.simulate(sc.replace(record_every=chunk))
    got = drive(JointStepper.from_scenario(sc), sc, chunk, n)
    want = np.c_[ref.theta, ref.omega, ref.p][: n + 1]
    assert np.array_equal(got, want)


def test_joint_stepper_carries_the_remainder():
    # communication steps of 2.5 internal steps: every second call takes 3 steps, the other
    # 2, and the states at whole multiples of 5 steps are simulate's
    sc = raise_test("rk4")
    ref = ha.simulate(sc.replace(record_every=5))
    st = JointStepper.from_scenario(sc)
    got = []
    for _ in range(40):
        st.advance(2.5 * sc.step)
        got.append(st.outputs()["theta"])
    assert st.steps == 100
    assert np.array_equal(np.array(got[1::2]), ref.theta[1:21])


def test_joint_stepper_outputs_follow_the_state():
    sc = raise_test("rk4")
    st = JointStepper.from_scenario(sc)
    st.advance(0.02)
    o = st.outputs()
    assert list(o) == [name for name, _, _ in OUTPUTS]
    j = sc.joint
    assert o["x"] == pytest.approx(j.jack_position(o["theta"]), rel=1e-12)  # one formula
    # eq. (3): actuator torque A·p·r/n (the paper's torque arm)
    assert o["torque"] == pytest.approx(
        j.piston_area * o["p"] * j.crank_radius / j.gear_ratio, rel=1e-12
    )
    # the valve wide open early in the raise: the supply flow is the saturated K_q·e_o
    assert o["supply_flow"] == pytest.approx(j.flow_gain * j.valve_saturation, rel=1e-12)


def test_joint_stepper_inputs_supply_and_torque():
    sc = raise_test("rk4")
    # a lower supply pressure through the stepper is the same joint with that supply (the
    # paper joint: no physics reads the rated supply)
    low = 0.8 * sc.joint.supply_pressure
    st = JointStepper.from_scenario(sc)
    st.supply_pressure = low
    got = drive(st, sc, 100, sc.nsteps // 100)
    ref = ha.simulate(sc.replace(joint=sc.joint.replace(supply_pressure=low), record_every=100))
    assert np.array_equal(got[:, 0], ref.theta)
    # an external torque is the load record's torque T of the one step kernel
    st = JointStepper.from_scenario(sc)
    st.external_torque = 2.0
    got = drive(st, sc, 100, sc.nsteps // 100)
    J, L = sc.params
    lev = sc.lever
    t, th, *_ = integrate(
        RK4, sc.initial_angle, 0.0, sc.start_pressure(), 0.0, sc.step, sc.nsteps, 100,
        lev.times, lev.positions, lev.sine, J, L._replace(torque=2.0),
    )  # fmt: skip
    assert np.array_equal(got[:, 0], th)
    assert not np.array_equal(th, ref.theta)


def test_joint_stepper_state_round_trip():
    sc = raise_test("rk4")
    st = JointStepper.from_scenario(sc)
    st.advance(0.012303)  # 1230 whole steps, a remainder of 0.3 steps carried in the state
    saved = st.get_state()
    st.advance(0.03)
    first = st.outputs()
    st.lever = 0.0
    st.advance(0.01)  # move on with another lever, then roll back
    st.set_state(saved)
    assert st.steps == 1230
    assert st.remainder == pytest.approx(0.3 * sc.step, rel=1e-6)  # the sum's rounding
    st.advance(0.03)
    assert st.outputs() == first


def test_joint_stepper_refuses_bad_input():
    sc = raise_test("rk4")
    with pytest.raises(HydroarmError, match="solver.method"):
        JointStepper(sc.joint, sc.load, method="adaptive")
    st = JointStepper.from_scenario(sc)
    for field, value in (("lever", math.nan), ("supply_pressure", -1.0)):
        with pytest.raises(HydroarmError, match=field):
            setattr(st, field, value)
    with pytest.raises(HydroarmError, match="duration"):
        st.advance(-1e-3)


# ---------------------------------------------------------------------------- the arm ---
ARM_DURATION = 0.6  # [s]: the levers start moving at 0.3 s (examples/block_stacking.csv)


@pytest.fixture(scope="module")
def arm():
    return load_arm("examples/ucl-arm.toml")


def whole_run(sc):
    """The arm's circuit run whole on the system kernel: its states and its ArmResult-like
    traces (simulate_arm's reading of the same run)."""
    res = simulate(build(arm_circuit(sc)))
    assert res.bad_step < 0
    return res


def drive_arm(st, chunk_s, n, levers=None):
    """Advance an ArmStepper n pieces of chunk_s, levers (a function of the piece's index)
    set before each piece; the circuit's states and the stepper's outputs at the ends."""
    states, outs = [st.circuit._s.copy()], [st.outputs()]
    for i in range(n):
        if levers is not None:
            st.levers = levers(i)
        st.advance(chunk_s)
        states.append(st.circuit._s.copy())
        outs.append(st.outputs())
    return np.array(states), outs


@pytest.mark.parametrize(("method", "step", "chunk"), [("euler", 20e-6, 257), ("rk4", 0.5e-3, 7)])
def test_arm_stepper_is_the_circuit_run_with_the_files_levers(arm, method, step, chunk):
    # the file's block-stacking levers (a table against time) never set: the stepper steps
    # the arm's circuit as its whole run does, in pieces that divide neither the run nor the
    # lever table's instants (5.14 ms, 3.5 ms), bit for bit, and reads its outputs as
    # simulate_arm reads the whole run's columns
    sc = arm.replace(method=method, step=step, duration=ARM_DURATION, record_every=chunk)
    res = whole_run(sc)
    n = res.states.shape[0] - 1
    got, outs = drive_arm(ArmStepper(sc), chunk * step, n)
    assert np.array_equal(got, res.states)
    traces = simulate_arm(sc)
    names = [name for name, _ in build(arm_circuit(sc)).state_names]
    for j, aj in enumerate(sc.joints):
        name = aj.name
        theta = np.array([o[name]["theta"] for o in outs])
        q = res.states[:, names.index(f"{name}.angle")]
        assert np.array_equal(theta, q - aj.angle_offset), name
        p = np.array([o[name]["p"] for o in outs])
        assert np.array_equal(p, traces.p[:, j]), name
    ps = np.array([o["supply_pressure"] for o in outs])
    assert np.array_equal(ps, traces.supply_pressure)
    assert np.ptp(traces.theta[:, 0]) > 0.1  # the shoulder moved (0.3 s of a 35° lever ramp)


def step_levers(sc):
    """The arm with every lever stepped at t = 0 to its block-stacking pick position."""
    return sc.replace(
        inputs={
            name: LeverInput([0.0, 0.0], [lv(0.0)[0], lv(1.0)[0]]) for name, lv in sc.inputs.items()
        }
    )


@pytest.mark.parametrize("method", ["euler", "rk4"])
@pytest.mark.parametrize("chunk", [3, 20])
def test_arm_stepper_levers_set_at_the_start_are_the_step_levers_run(arm, method, chunk):
    # the levers set before the first step and held (what the explorer's arm page and the
    # arm FMU do) give the whole run of the same step levers written into the file, bit for
    # bit: the set lever is the file's lever at every stage of every step
    sc = step_levers(arm).replace(method=method, step=0.5e-3, duration=0.3, record_every=chunk)
    res = whole_run(sc)
    n = res.states.shape[0] - 1
    st = ArmStepper(arm.replace(method=method, step=0.5e-3))
    st.levers = {name: float(lv(1.0)[0]) for name, lv in arm.inputs.items()}
    got, outs = drive_arm(st, chunk * sc.step, n)
    assert np.array_equal(got, res.states)
    assert outs[-1]["elbow_reach"]["theta"] - outs[0]["elbow_reach"]["theta"] > 0.5  # it moved


def test_arm_stepper_levers_held_over_pieces_are_the_replay_with_euler(arm):
    # levers set at 5 ms communication points against the whole run of the same levers as
    # steps at those points (what a master gives the arm FMU): Euler reads a lever at the
    # step's start only, so every state is the replay's bit for bit but one: the elbow's
    # spool, algebraic (recorded, not integrated), which the step's projection records from
    # the lever at the step's end, where the file's step has already changed (module doc)
    chunk_s, step = 5e-3, 20e-6
    tb = np.arange(int(round(ARM_DURATION / chunk_s)) + 1) * chunk_s
    held = {}
    for name, lv in arm.inputs.items():
        v = lv(tb)
        held[name] = LeverInput(np.repeat(tb, 2)[1:-1], np.repeat(v[:-1], 2))
    sc = arm.replace(inputs=held, method="euler", step=step, duration=ARM_DURATION)
    res = whole_run(sc.replace(record_every=int(round(chunk_s / step))))
    st = ArmStepper(sc)
    got, _ = drive_arm(
        st, chunk_s, len(tb) - 1, lambda i: {k: float(lv(tb[i])[0]) for k, lv in arm.inputs.items()}
    )
    names = [name for name, _ in st.circuit.compiled.state_names]
    spool = names.index("elbow_reach_valve.spool")
    differ = np.flatnonzero(np.any(got != res.states, axis=0)).tolist()
    assert differ == [spool]
    assert np.ptp(res.states[:, names.index("shoulder_elevation.angle")]) > 0.1  # it moved


def test_arm_stepper_levers_are_the_files_until_set(arm):
    st = ArmStepper(arm.replace(step=0.5e-3))
    st.advance(0.4)  # the block-stacking levers under way (they move from 0.3 s)
    for n, lv in arm.inputs.items():
        # the lever source's table against the lever input's: one linear interpolation
        # each, rounding apart (1e-12 relative)
        assert st.levers[n] == pytest.approx(float(lv(st.t)[0]), rel=1e-12, abs=1e-15), n
    st.set_lever("elbow_reach", 0.004)
    st.advance(0.1)
    assert st.levers["elbow_reach"] == 0.004
    assert st.levers["shoulder_elevation"] == pytest.approx(
        float(arm.inputs["shoulder_elevation"](st.t)[0]), rel=1e-12
    )


def test_arm_stepper_state_round_trip(arm):
    sc = step_levers(arm).replace(step=0.5e-3, duration=0.3)
    st = ArmStepper(sc)
    st.advance(0.0505)  # half a step carried
    saved = st.get_state()
    st.advance(0.1)
    first = st.outputs()
    st.levers = {"elbow_reach": 0.0}
    st.advance(0.05)
    st.set_state(saved)
    st.advance(0.1)
    assert st.outputs() == first
    assert first["pump_flow"] == pytest.approx(arm.power_pack.pump_flow, rel=1e-15)


def test_arm_stepper_refuses_bad_input(arm):
    st = ArmStepper(arm)
    with pytest.raises(HydroarmError, match="no joint 'knee'"):
        st.levers = {"knee": 0.0}
    with pytest.raises(HydroarmError, match="state"):
        st.set_state(np.zeros(3))
    # a state of the arm's own kernel (before issue 28: step count, requested time, supply
    # pressure, failed; 9 numbers a joint; the component joints' states) is refused in one line
    old = np.zeros(4 + 9 * 4 + 4 * 14)
    old = np.resize(old, st.state_size)  # even one of this stepper's length
    with pytest.raises(HydroarmError, match="state: must be .* beginning -28") as exc:
        st.set_state(old)
    assert "\n" not in str(exc.value)
    for bad in (-0.01, math.nan, "1 kg"):
        with pytest.raises(HydroarmError, match="arm.hand_mass"):
            st.hand_mass = bad
    assert st.hand_mass == arm.geometry.hand_mass  # refused values change nothing
    st.hand_mass = 0.25
    assert st.hand_mass == 0.25
    with pytest.raises(HydroarmError, match="arm.hand_mass: must be positive"):
        st.hand_mass = 0.0  # the wrist rotation turns the hand alone (arm_circuit's rule)
    with pytest.raises(HydroarmError, match="theta.elbow_reach"):
        st.stop_joints([0.0, 0.0, math.inf, 0.0], [2])
    with pytest.raises(HydroarmError, match="solver.method"):
        ArmStepper(arm, method="heun")


# ------------------------------------------------------------ the component servo ---
SERVO_FILE = "examples/position_servo.toml"


@pytest.fixture(scope="module")
def servo():
    sc = ha.load_scenario(pathlib.Path(__file__).parent.parent / SERVO_FILE)
    # 0.05 s of 10 us RK4, the reference stepped at 0.02 s so that the stepper crosses it
    ref = LeverInput(np.array([0.0, 0.02, 0.02]), np.array([0.2, 0.2, 0.7]), description="steps")
    return sc.replace(reference=ref, duration=0.05, record_every=100)


@pytest.mark.parametrize("chunk", [7, 100])
def test_servo_stepper_is_run_bit_for_bit(servo, chunk):
    # the stepper steps what the single run steps: the servo's circuit on the system kernel
    res = servo.run()
    st = ServoStepper(servo)
    assert st.circuit is not None
    got = [st.outputs()]
    for k in range(1, servo.nsteps + 1):
        if k % chunk == 0 or k % servo.record_every == 0:  # pieces cut at the records too
            st.advance_to(k * servo.step)
        if k % servo.record_every == 0:
            assert st.steps == k
            got.append(st.outputs())
    cols = res.columns()
    for name in got[0]:
        assert np.array_equal([g[name] for g in got], cols[name]), name


def test_servo_stepper_steps_a_pid_derivative_and_crank_friction_on_the_circuit():
    """A crank with piston and gearbox friction under electronic feedback with a derivative
    gain (once servo-kernel cases): the stepper steps the circuit, run()'s trajectory bit
    for bit in pieces of 7 steps."""
    path = pathlib.Path(__file__).parent / "data" / "servo_circuit" / "crank_pump.toml"
    sc = ha.load_scenario(path).replace(
        duration=0.01,
        record_every=50,
        coulomb_friction=5.0,
        gearbox_friction_torque=0.01,
        feedback_kind=1.0,
        sense_actuator=1.0,
        proportional_gain=0.2,
        derivative_gain=2.0e-4,
    )
    st = ServoStepper(sc)
    assert st.circuit is not None
    res = sc.run()
    for k in range(1, sc.nsteps + 1):
        if k % 7 == 0 or k % sc.record_every == 0:
            st.advance_to(k * sc.step)
        if k % sc.record_every == 0:
            assert np.array_equal(st.servo_state(), res.states[k // sc.record_every])


def test_servo_stepper_steps_air_at_another_atmosphere_on_the_circuit():
    """Air at a non-standard atmosphere (once a servo-kernel case): the stepper steps the
    circuit, run()'s trajectory bit for bit, its state in the servo kernel's layout, and the
    external force acts as the file's (a constant force written into the scenario, bit for
    bit)."""
    path = pathlib.Path(__file__).parent / "data" / "servo_circuit" / "crank_pump.toml"
    sc = ha.load_scenario(path).replace(duration=0.01, atmospheric_pressure=9.0e4, record_every=50)
    st = ServoStepper(sc)
    res = sc.run()
    for k in range(1, sc.nsteps // sc.record_every + 1):
        st.advance(sc.record_every * sc.step)
        assert np.array_equal(st.servo_state(), res.states[k])
    pushed = sc.replace(external_force=3.0)
    st = ServoStepper(sc)
    st.external_force = 3.0
    st.advance_to(sc.duration)
    assert np.array_equal(st.servo_state(), pushed.run().states[-1])


def test_servo_stepper_inputs_and_state_round_trip(servo):
    st = ServoStepper(servo)
    assert st.reference == 0.2 and not st.reference_set and st.external_force == 0.0
    st.reference = 0.5
    st.external_force = -100.0
    st.advance(0.01)
    saved = st.get_state()
    st.advance(0.01)
    after = st.outputs()
    st.reference = 0.3
    st.advance(0.005)
    st.set_state(saved)
    assert st.reference == 0.5 and st.reference_set and st.external_force == -100.0
    st.advance(0.01)
    assert st.outputs() == after
    # the held reference is a constant reference in the scenario, bit for bit
    const = servo.replace(
        reference=LeverInput(np.array([0.0]), np.array([0.5]), description="steps"),
        external_force=-100.0,
        duration=0.02,
        record_every=2000,
    )
    assert np.array_equal(const.run().states[-1], st.servo_state())


def test_servo_stepper_refuses_bad_input(servo):
    st = ServoStepper(servo)
    for name, value in (("reference", math.nan), ("external_force", "1 N")):
        with pytest.raises(HydroarmError, match=name):
            setattr(st, name, value)
    with pytest.raises(HydroarmError, match="solver.method"):
        ServoStepper(servo, method="adaptive")
    with pytest.raises(HydroarmError, match="stable limit"):
        ServoStepper(servo, method="euler")
    with pytest.raises(HydroarmError, match="state"):
        st.set_state([1.0, 2.0])


@pytest.mark.parametrize(("method", "step", "chunk"), [("euler", 20e-6, 257), ("rk4", 1e-3, 7)])
def test_arm_stepper_with_a_joint_on_a_bench_is_the_circuit_run(method, step, chunk):
    # the elbow on a test bench (a fixed load: an inertia off the arm's tree, on its own
    # node): the stepper steps the arm's circuit as its whole run does, bit for bit, and
    # reads each joint's angle where simulate_arm reads it (the bench joint: its load's node)
    sc = load_arm(pathlib.Path(__file__).parent / "data" / "arm" / "elbow-bench.toml")
    sc = sc.replace(method=method, step=step, duration=1.3, record_every=chunk)
    res = whole_run(sc)
    n = res.states.shape[0] - 1
    st = ArmStepper(sc)
    got, outs = drive_arm(st, chunk * step, n)
    assert np.array_equal(got, res.states)
    names = [name for name, _ in st.circuit.compiled.state_names]
    for aj in sc.joints:
        theta = np.array([o[aj.name]["theta"] for o in outs])
        q = res.states[:, names.index(f"{aj.name}.angle")]
        assert np.array_equal(theta, q - aj.angle_offset), aj.name
    bench = [aj.name for aj in sc.joints].index("elbow_reach")
    traces = simulate_arm(sc)  # the bench joint moved (its lever from 1 s)
    assert np.ptp(traces.theta[:, bench]) > 0.1
    # its torque, the actuator's through the crank (as a tree joint's, friction aside), holds
    # the bench load's gravity torque W·X·cos(θ − θ_h) when it rests, to within the friction
    # that may hold it: the gearbox's load-dependent loss, up to 0.348 of that torque at
    # stall (the file's gearbox_loss_at_stall, exponent 1); measured 0.19 and 0.24
    st2 = ArmStepper(sc.replace(method="rk4", step=1e-3))
    load, servo = sc.joint("elbow_reach").fixed_load, sc.joint("elbow_reach").servo
    rests = []
    for _ in range(8):
        st2.advance(0.25)
        o = st2.outputs()["elbow_reach"]
        if o["omega"] == 0.0:
            gravity = load.weight * load.arm * math.cos(o["theta"] - servo.horizontal_angle)
            rests.append((o["theta"], o["torque"], gravity))
    assert max(t for t, _, _ in rests) - min(t for t, _, _ in rests) > 0.5  # before and after
    for _, torque, gravity in rests:
        assert abs(torque - gravity) <= 0.36 * abs(torque), (torque, gravity)
    # an inelastic stop of the bench joint (the explorer's contacts): its node at rest there
    st.stop_joints(np.full(len(sc.joints), 0.3), [bench])
    assert st.servo_angles()[bench] == pytest.approx(0.3, abs=1e-15)
    assert st.outputs()["elbow_reach"]["omega"] == 0.0
