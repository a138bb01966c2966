"""A mechanism's joints stepped by the system kernel together with circuits (issue 30).

The joints of a ``[mechanism]`` are mechanical nodes of the circuit; their accelerations come
from the tree's articulated-body algorithm (:mod:`hydroarm.core.tree`), and linkages (a
cylinder between two pivots, the paper's crank, a gear) carry actuator forces to them by
virtual work (:mod:`hydroarm.core.circuit.system`). Checked here against closed forms, an
independent integration of the tree's equations, the same joint as a plain inertia node, and
the energy account.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from hydroarm.core import tree as T
from hydroarm.core.circuit.components import TYPES
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import circuit_from_doc, load_circuit
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import build, simulate

DATA = Path(__file__).parent / "data" / "mechanism"


def _doc(name: str) -> dict:
    return parse_toml((DATA / name).read_text(), name)


def _crossings(t, y):
    """Times at which y changes sign (linear interpolation between records)."""
    i = np.nonzero(np.sign(y[1:-1]) * np.sign(y[2:]) < 0)[0] + 1
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def test_passive_pendulum_period_matches_the_elliptic_integral():
    """A pendulum released at rest swings with the period 4·√(I/(m·g·l))·K(sin²(α/2)),
    α the amplitude about the hanging pose (here 60°: released at 30°, hanging at 90°)."""
    r = simulate(load_circuit(DATA / "pendulum.toml"))
    assert r.bad_step == -1
    m, l, iyy = 2.0, 0.5, 1e-3
    inertia = iyy + m * l * l
    alpha = math.radians(60.0)
    period = (
        4 * math.sqrt(inertia / (m * T.STANDARD_GRAVITY * l)) * ellipk(math.sin(alpha / 2) ** 2)
    )
    w = r.output("swing_angular_velocity_rad_s")
    times = _crossings(r.t, w)
    measured = 2 * np.diff(times).mean()  # the velocity turns twice a period
    # RK4 at 0.2 ms has a phase error ~ (ωh)⁴ ≈ 1e-11; the crossings are interpolated
    # linearly between records 0.2 ms apart at the velocity's extremum slope: ≲ 1e-7 s
    assert measured == pytest.approx(period, rel=1e-6)
    angle = r.output("swing_angle_deg")
    assert angle.max() == pytest.approx(150.0, abs=1e-3)  # symmetric about the hanging 90°


def _double_pendulum_reference(cc, q0, t_end):
    tree = cc.mechanism.tree
    work = T.make_tree_work(2)
    fext = np.zeros((2, 6))

    def rhs(_t, y):
        qdd = np.zeros(2)
        T.forward_dynamics_crba(tree, y[:2].copy(), y[2:].copy(), np.zeros(2), fext, work, qdd)
        return np.concatenate([y[2:], qdd])

    return solve_ivp(rhs, (0, t_end), np.concatenate([q0, [0, 0]]), rtol=1e-11, atol=1e-12,
                     dense_output=True, method="DOP853")  # fmt: skip


def test_coupled_double_pendulum_matches_an_independent_integration():
    """Two joints push on each other: the kernel's run equals the tree's equations
    M(q)·q̈ = −C(q, q̇)·q̇ − g(q) (mass matrix and bias by CRBA/RNEA, not the ABA the kernel
    uses) integrated by scipy's DOP853 at tolerance 1e-11."""
    circuit = load_circuit(DATA / "double_pendulum.toml")
    cc = build(circuit)
    r = simulate(cc)
    q0 = np.radians([20.0, -40.0])
    ref = _double_pendulum_reference(cc, q0, r.t[-1])
    y = ref.sol(r.t)
    got = np.radians(np.column_stack([r.output("shoulder_angle_deg"), r.output("elbow_angle_deg")]))
    # RK4 at 0.1 ms over 1 s of a chaotic-ish motion: global error ~ C·h⁴ ≈ 1e-9 rad
    np.testing.assert_allclose(got, y[:2].T, atol=1e-7)
    # the elbow moves the shoulder: the same shoulder alone (elbow locked) moves differently
    locked = simulate(
        circuit_from_doc(_locked_elbow(_doc("double_pendulum.toml")), "locked", DATA)
    ).output("shoulder_angle_deg")
    assert np.max(np.abs(locked - np.degrees(got[:, 0]))) > 1.0


def _locked_elbow(doc):
    doc["mechanism"]["joint"][1]["type"] = "fixed"
    doc["mechanism"]["joint"][1]["rpy"] = ["0 deg", "-40 deg", "0 deg"]
    del doc["initial"]["elbow"]
    return doc


def test_passive_chain_conserves_energy():
    """No damping, no friction: T + V is constant to RK4's error; the energy account shows
    the mechanism absorbing nothing over the run."""
    circuit = load_circuit(DATA / "double_pendulum.toml")
    cc = build(circuit)
    r = simulate(cc)
    tree = cc.mechanism.tree
    work = T.make_tree_work(2)
    R = np.zeros((2, 3, 3))
    p = np.zeros((2, 3))
    e = []
    for row in r.states:
        q, qd = row[:2].copy(), row[2:4].copy()
        e.append(T.kinetic_energy(tree, q, qd, work) + T.potential_energy(tree, q, work, R, p))
    e = np.array(e)
    scale = 2.5 * T.STANDARD_GRAVITY * 0.5  # m·g·(a length of the chain) ≈ 12 J
    assert np.ptp(e) < 1e-8 * scale


def _as_inertia_node(doc):
    """The boom with its joint as a plain rotational node: an ``inertia`` component with the
    link's inertia about the pivot and its gravity moment (issue 30: one joint alone is
    today's single joint)."""
    link = doc["mechanism"]["link"][1]
    m = float(link["mass"].split()[0])
    x = float(link["com"][0].split()[0])
    iyy = float(link["iyy"].split()[0])
    joint = doc["mechanism"]["joint"][0]
    del doc["mechanism"]
    doc["initial"].pop("lift")
    doc["component"].append(
        {
            "type": "inertia",
            "name": "boom",
            "ports": {"body": "lift"},
            "inertia": f"{iyy + m * x * x} kg*m**2",
            # axis −y: the torque of gravity about the axis is −m·g·x·cos θ
            "gravity_moment": f"{m * T.STANDARD_GRAVITY * x} N*m",
            "gravity_angle": "0 rad",
            "angle_min": joint["lower"],
            "angle_max": joint["upper"],
            "initial_angle": "0 deg",
        }
    )
    return doc


def test_one_joint_of_a_mechanism_is_the_plain_rotational_node():
    """The boom's joint in the tree, and the same joint as an ``inertia`` node: the same
    run. The ABA's single-joint arithmetic differs from F/M only by rounding: 1e-9."""
    tree_run = simulate(load_circuit(DATA / "boom.toml"))
    plain = simulate(circuit_from_doc(_as_inertia_node(_doc("boom.toml")), "plain", DATA))
    for name in ("lift_angle_deg", "A_pressure_bar", "B_pressure_bar", "rod_position_m"):
        a, b = tree_run.output(name), plain.output(name)
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9 * np.max(np.abs(b)), err_msg=name)
    assert np.ptp(tree_run.output("lift_angle_deg")) > 20.0  # it moved


def test_linkage_moves_the_rod_with_the_joint_and_the_energy_account_closes():
    r = simulate(load_circuit(DATA / "boom.toml"))
    df = r.to_pandas()
    th = np.radians(df["lift_angle_deg"].to_numpy()) + math.radians(60.0)
    a, b = 0.3, 0.5
    length = np.sqrt(a * a + b * b - 2 * a * b * np.cos(th))
    np.testing.assert_allclose(df["rod_position_m"], length - 0.27, rtol=0, atol=1e-12)
    np.testing.assert_allclose(df["lift_linkage_ratio"], a * b * np.sin(th) / length, atol=1e-12)
    # the joint's torque is the rod force through the moment arm, less the piston's (3 kg)
    # share of the rod's centripetal acceleration g''·θ̇² (virtual work)
    arm = a * b * np.sin(th) / length
    curvature = (a * b * np.cos(th) - arm * arm) / length
    omega = df["lift_angular_velocity_rad_s"].to_numpy()
    np.testing.assert_allclose(
        df["lift_torque_n_m"],
        arm * (df["lift_cylinder_force_n"] - 3.0 * curvature * omega**2),
        rtol=1e-9,
        atol=1e-6,
    )
    e = r.energy()
    # what the cylinder delivers is the mechanism's potential and kinetic energy
    assert e["mechanism_energy_j"] > 50.0
    # the powers sum to zero at every record; the trapezoid over records leaves round-off
    assert abs(e["closure_energy_j"]) < 1e-9 * e["supply_energy_j"] * -1


def test_equilibrium_start_holds_the_boom():
    r = simulate(load_circuit(DATA / "boom.toml").replace(duration=0.15))
    # the valve is shut until 0.2 s: the equilibrium start must not move (< 1e-6 of a degree)
    assert np.max(np.abs(r.output("lift_angle_deg"))) < 1e-6


@pytest.mark.parametrize(
    "name", ["crank_linkage", "pivot_linkage", "gear_drive", "four_bar_linkage"]
)
def test_linkage_derivatives_are_consistent(name):
    """g' and g'' of every linkage against central differences of g (h = 1e-5: truncation
    ~h²·g''' ≈ 1e-10, round-off ~1e-16/h ≈ 1e-11)."""
    module = TYPES[name]
    decl = module.DECLARATION
    values = {
        "crank_radius": 0.05, "gear_ratio": 3.0, "rod_position_at_zero": 0.01,
        "base_radius": 0.3, "link_radius": 0.5, "angle_offset": 1.0, "retracted_length": 0.27,
        "ratio": 0.2, "offset": 0.1,
        "ground_length": 0.5, "input_length": 0.2, "coupler_length": 0.45, "output_length": 0.3,
        "input_angle_offset": 1.0, "output_angle_offset": 0.5,
    }  # fmt: skip
    P = np.array([values.get(p.name, 0.0 if p.choices else p.default) for p in decl.parameters])
    out = np.zeros(4)
    hi, lo = np.zeros(4), np.zeros(4)
    for q in (-0.4, 0.1, 0.7):
        h = 1e-5
        module.transmit(P, 0, q, out)
        module.transmit(P, 0, q + h, hi)
        module.transmit(P, 0, q - h, lo)
        assert out[1] == pytest.approx((hi[0] - lo[0]) / (2 * h), rel=1e-8, abs=1e-12)
        assert out[2] == pytest.approx((hi[1] - lo[1]) / (2 * h), rel=1e-6, abs=1e-10)
        assert out[3] == out[1]  # the force lever is g' (by virtual work) unless told


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d["initial"].__setitem__("lift", "80 deg"), "initial.lift"),
        (lambda d: d["initial"].__setitem__("nope", "1 deg"), "initial.nope"),
        # θ + φ reaches 180° at θ = 120°: the pivots and the axis in line inside the limits
        (
            lambda d: d["mechanism"]["joint"][0].__setitem__("upper", "130 deg"),
            "component.lift_linkage",
        ),
        (
            lambda d: d["component"][-1]["ports"].__setitem__("rod", "lift"),
            "component.lift_linkage.ports.rod",
        ),
        (
            lambda d: d["component"][-1]["ports"].__setitem__("joint", "rod"),
            "component.lift_linkage.ports.joint",
        ),
    ],
)
def test_bad_mechanism_circuits_are_one_line_errors(edit, field):
    doc = _doc("boom.toml")
    edit(doc)
    with pytest.raises(HydroarmError) as e:
        build(circuit_from_doc(doc, "bad", DATA))
    assert e.value.field == field, str(e.value)


def test_sweep_over_mechanism_designs(tmp_path):
    """examples/boom_study.toml on the batch engine: a bigger bore needs less pressure to
    hold and lift the same boom (p ≈ τ/(A·g')), at every pivot radius; a row equals the
    same design run alone."""
    import pandas as pd

    from hydroarm.cli import main

    out = tmp_path / "s.csv"
    examples = Path(__file__).resolve().parents[1] / "examples"
    rc = main(["sweep", "--config", str(examples / "boom_study.toml"), "--out", str(out)])
    assert rc == 0
    df = pd.read_csv(out)
    assert not df["failed"].any()
    for _, rows in df.groupby("lift_linkage.base_radius_m"):
        rows = rows.sort_values("lift_cylinder.area_a_m2")
        assert np.all(np.diff(rows["peak_cap_pressure_bar"]) < 0)
    alone = simulate(
        load_circuit(examples / "boom.toml")
        .replace(duration=1.0, record_every=1)  # the study observes every step
        .with_values({"lift_linkage.base_radius": 0.25, "lift_cylinder.area_a": 15e-4})
    )
    assert df["top_deg"].iloc[0] == pytest.approx(alone.output("lift_angle_deg").max(), rel=1e-9)


def test_hydroarm_arm_runs_any_mechanism_file(tmp_path, capsys):
    """`hydroarm arm` on a mechanism file: per-joint columns named as in the file, the
    driving cylinder's pressures under the joint's name, the plots; a passive file runs from
    its [initial] angles."""
    import pandas as pd

    from hydroarm.cli import main

    examples = Path(__file__).resolve().parents[1] / "examples"
    out = tmp_path / "boom"
    assert main(["arm", "--config", str(examples / "boom.toml"), "--out", str(out)]) == 0
    df = pd.read_csv(out / "joints.csv")
    for col in ("lift_angle_deg", "lift_angular_velocity_rad_s", "lift_torque_n_m",
                "lift_pressure_a_bar", "lift_pressure_b_bar"):  # fmt: skip
        assert col in df, col
    np.testing.assert_array_equal(df["lift_pressure_a_bar"], df["A_pressure_bar"])
    for name in ("energy.csv", "joints.png", "frames.png", "mechanism.gif"):
        assert (out / name).stat().st_size > 0
    passive = tmp_path / "dp"
    argv = ["arm", "--config", str(DATA / "double_pendulum.toml"), "--out", str(passive)]
    assert main([*argv, "--no-animation"]) == 0
    df = pd.read_csv(passive / "joints.csv")
    assert df["shoulder_angle_deg"].iloc[0] == pytest.approx(20.0)
    assert df["elbow_angle_deg"].iloc[0] == pytest.approx(-40.0)
    assert "elbow" in capsys.readouterr().out


def test_hydroarm_arm_bad_mechanism_is_one_line(tmp_path, capsys):
    doc = (
        (DATA / "double_pendulum.toml").read_text().replace('parent = "upper"', 'parent = "lower"')
    )
    bad = tmp_path / "bad.toml"
    bad.write_text(doc)
    rc = main_cli(["arm", "--config", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("hydroarm: error: mechanism."), err
    assert not (tmp_path / "o").exists()


def main_cli(argv):
    from hydroarm.cli import main

    try:
        return main(argv)
    except SystemExit as e:
        return e.code
