"""The four-bar linkage (issue 30: actuation through linkages, an excavator's H-link).

Its position law (Freudenstein's equation by the half-angle tangent) against an independent
construction, the intersection of the coupler's and the output link's circles; its ratio g'
and curvature g'' against the coupler's rigidity differentiated once and twice (closed form,
no differences) and against central differences of g; a mechanism turned through it and a
pivot linkage on its rocker, its energy account closing; its dead centres refused before a
run as one line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hydroarm.core.circuit.components import TYPES
from hydroarm.errors import HydroarmError
from hydroarm.io.circuit import circuit_from_doc, load_circuit
from hydroarm.io.sections import parse_toml
from hydroarm.model.circuit import build, simulate

DATA = Path(__file__).parent / "data" / "mechanism"
FOUR_BAR = TYPES["four_bar_linkage"]
PIVOT = TYPES["pivot_linkage"]
OPEN, CROSSED = 0, 1

# (d, a, b, c): a Grashof crank-rocker (the input turns fully), a Grashof double-crank
# (drag link: the shortest link is the ground) and a non-Grashof triple rocker (the input
# turns over part of a turn only), in the same units
GEOMETRIES = {
    "crank_rocker": (0.5, 0.2, 0.45, 0.3),
    "double_crank": (0.2, 0.5, 0.45, 0.4),
    "triple_rocker": (0.5, 0.4, 0.3, 0.45),
}
PHI2, PHI4 = 0.3, -0.7  # the angle offsets: q = 0 is not the four-bar's own zero


def _params(d, a, b, c, branch, phi2=PHI2, phi4=PHI4):
    return np.array([d, a, b, c, phi2, phi4, branch], float)


def _wrap(x):
    """x into (−π, π]."""
    return x - 2 * math.pi * math.ceil((x - math.pi) / (2 * math.pi))


def _circle_construction(d, a, b, c, t2, branch):
    """The pin B, where the circle of radius b about A (the input link's end) meets the
    circle of radius c about O₄: the point at x along A→O₄ and h off it (h > 0: to the
    left, the open branch). None where the circles do not meet."""
    pa = np.array([a * math.cos(t2), a * math.sin(t2)])
    o4 = np.array([d, 0.0])
    v = o4 - pa
    dist = math.hypot(*v)
    x = (dist * dist + b * b - c * c) / (2 * dist)
    if b * b - x * x < 0.0:
        return None
    h = math.sqrt(b * b - x * x)
    u = v / dist
    left = np.array([-u[1], u[0]])
    return pa + x * u + (h if branch == OPEN else -h) * left


def _samples(geometry, branch):
    """(q, out) at 2001 master angles over a whole turn where the four-bar assembles."""
    d, a, b, c = GEOMETRIES[geometry]
    P = _params(d, a, b, c, branch)
    rows = []
    for q in np.linspace(-math.pi, math.pi, 2001):
        out = np.zeros(4)
        FOUR_BAR.transmit(P, 0, float(q), out)
        rows.append((float(q), out))
    return P, rows


@pytest.mark.parametrize("branch", [OPEN, CROSSED])
@pytest.mark.parametrize("geometry", sorted(GEOMETRIES))
def test_position_matches_the_circle_construction(geometry, branch):
    """g(q) = θ₄ − φ₄ against the pin B found by intersecting two circles (no Freudenstein):
    both are a few dozen operations on lengths ~0.5 and angles ~π, so they agree to round-off
    (measured: 2e-15 rad for the crank-rocker, 6e-14 for the drag link, whose Freudenstein
    coefficients K₁ = d/a, K₂ = d/c are small against K₃; 1e-12 allowed); where the circles
    do not meet, g is NaN."""
    d, a, b, c = GEOMETRIES[geometry]
    _, rows = _samples(geometry, branch)
    assembled = 0
    worst = 0.0
    for q, out in rows:
        pin = _circle_construction(d, a, b, c, q + PHI2, branch)
        if pin is None:
            assert np.isnan(out).all(), q
            continue
        assembled += 1
        expected = _wrap(math.atan2(pin[1], pin[0] - d) - PHI4)
        err = abs(_wrap(out[0] - expected))
        worst = max(worst, err)
        assert -math.pi < out[0] <= math.pi
    assert worst < 1e-12, worst
    if geometry == "triple_rocker":
        assert 0 < assembled < len(rows)  # the input cannot turn all the way round
    else:
        assert assembled == len(rows)  # Grashof with the input a crank: every angle


@pytest.mark.parametrize("branch", [OPEN, CROSSED])
@pytest.mark.parametrize("geometry", sorted(GEOMETRIES))
def test_loop_closes_and_the_coupler_stays_rigid(geometry, branch):
    """The coupler's length |B − A| is b at the position g gives (loop closure); its time
    derivatives vanish at the velocity g'·q̇ and acceleration g'' q̇² g gives (q̇ = 1, q̈ = 0):

        (v_B − v_A)·(B − A) = 0,   (a_B − a_A)·(B − A) + |v_B − v_A|² = 0

    with v_A = a·e⊥(θ₂), a_A = −a·e(θ₂), v_B = c·g'·e⊥(θ₄), a_B = c·(g''·e⊥(θ₄) − g'²·e(θ₄)).
    Checked relative to b and to the terms' size a·c·(1 + g'² + |g''|), which grow near the
    toggles (measured: the length to 6e-14 of b, the rates to 8e-15; 1e-13 allowed)."""
    d, a, b, c = GEOMETRIES[geometry]
    _, rows = _samples(geometry, branch)
    worst = np.zeros(3)
    for q, out in rows:
        if np.isnan(out[0]):
            continue
        t2, t4 = q + PHI2, out[0] + PHI4
        e2, p2 = np.array([math.cos(t2), math.sin(t2)]), np.array([-math.sin(t2), math.cos(t2)])
        e4, p4 = np.array([math.cos(t4), math.sin(t4)]), np.array([-math.sin(t4), math.cos(t4)])
        pa, pb = a * e2, np.array([d, 0.0]) + c * e4
        rel = pb - pa
        va, vb = a * p2, c * out[1] * p4
        aa, ab = -a * e2, c * (out[2] * p4 - out[1] ** 2 * e4)
        scale = a * c * (1 + out[1] ** 2 + abs(out[2]))
        worst = np.maximum(
            worst,
            [
                abs(math.hypot(*rel) - b) / b,
                abs((vb - va) @ rel) / scale,
                abs((ab - aa) @ rel + (vb - va) @ (vb - va)) / scale,
            ],
        )
        assert out[3] == out[1]  # the force lever is g' (virtual work)
    assert worst[0] < 1e-13 and worst[1] < 1e-13 and worst[2] < 1e-13, worst


@pytest.mark.parametrize("branch", [OPEN, CROSSED])
@pytest.mark.parametrize("geometry", sorted(GEOMETRIES))
def test_derivatives_match_central_differences(geometry, branch):
    """g' and g'' against central differences of g and g' (h = 1e-5: truncation ~h²·g''' ≈
    1e-10, round-off ~1e-16/h ≈ 1e-11, both relative to the derivatives' size), at angles
    away from the toggles (transmission angle above 20°: there g''' stays moderate)."""
    d, a, b, c = GEOMETRIES[geometry]
    P = _params(d, a, b, c, branch)
    out, hi, lo = np.zeros(4), np.zeros(4), np.zeros(4)
    h = 1e-5
    checked = 0
    for q in np.linspace(-math.pi, math.pi, 181):
        FOUR_BAR.transmit(P, 0, q, out)
        FOUR_BAR.transmit(P, 0, q + h, hi)
        FOUR_BAR.transmit(P, 0, q - h, lo)
        if not np.isfinite([out[0], hi[0], lo[0]]).all():
            continue
        pin = _circle_construction(d, a, b, c, q + PHI2, branch)
        pa = np.array([a * math.cos(q + PHI2), a * math.sin(q + PHI2)])
        t4 = out[0] + PHI4
        u = (pin - pa) / b  # the coupler's direction; sin μ = |u × e(θ₄)|
        sin_mu = abs(u[0] * math.sin(t4) - u[1] * math.cos(t4))
        if sin_mu < math.sin(math.radians(20.0)):
            continue
        scale = 1 + abs(out[1]) + abs(out[2])
        assert abs(out[1] - _wrap(hi[0] - lo[0]) / (2 * h)) < 1e-8 * scale, q
        assert abs(out[2] - (hi[1] - lo[1]) / (2 * h)) < 1e-6 * scale, q
        checked += 1
    assert checked > 60


def _doc():
    return parse_toml((DATA / "four_bar.toml").read_text(), "four_bar.toml")


def _component(doc, name):
    return next(c for c in doc["component"] if c["name"] == name)


def test_mechanism_through_the_four_bar_closes_its_energy_account():
    """A boom on a revolute joint, its cylinder on the four-bar's rocker through a pivot
    linkage (tests/data/mechanism/four_bar.toml): the rocker and the rod follow the chain of
    laws at every record, the joint's ratio is the product, and the energy the supply gives
    is what the valve, the cylinder and the mechanism take (the powers sum to zero at every
    record; the trapezoid over the records leaves round-off: 1e-9 of the supply's energy)."""
    r = simulate(load_circuit(DATA / "four_bar.toml"))
    assert r.bad_step == -1
    df = r.to_pandas()
    q = np.radians(df["lift_angle_deg"].to_numpy())
    assert np.ptp(q) > math.radians(20.0)  # it moved
    P = _params(0.5, 0.2, 0.45, 0.3, OPEN, math.radians(90.0), 0.0)
    pp = np.array([0.3, 0.25, math.radians(-22.0), 0.27])
    out, o2 = np.zeros(4), np.zeros(4)
    rocker, rod, ratio = [], [], []
    for qi in q:
        FOUR_BAR.transmit(P, 0, float(qi), out)
        PIVOT.transmit(pp, 0, out[0], o2)
        rocker.append(out[0])
        rod.append(o2[0])
        ratio.append(out[1])
    np.testing.assert_allclose(np.radians(df["rocker_angle_deg"]), rocker, rtol=0, atol=1e-12)
    np.testing.assert_allclose(df["rod_position_m"], rod, rtol=0, atol=1e-12)
    np.testing.assert_allclose(df["h_link_ratio"], ratio, rtol=0, atol=1e-12)
    e = r.energy()
    assert e["mechanism_energy_j"] > 50.0
    assert e["h_link_energy_j"] == 0.0  # lossless
    assert abs(e["closure_energy_j"]) < 1e-9 * -e["supply_energy_j"]


def test_hydroarm_arm_runs_the_four_bar_file(tmp_path):
    import pandas as pd

    from hydroarm.cli import main

    out = tmp_path / "fb"
    argv = ["arm", "--config", str(DATA / "four_bar.toml"), "--out", str(out), "--no-animation"]
    assert main(argv) == 0
    df = pd.read_csv(out / "joints.csv")
    assert "lift_angle_deg" in df and "rocker_angle_deg" in df
    assert (out / "energy.csv").stat().st_size > 0


@pytest.mark.parametrize(
    ("edit", "field", "words"),
    [
        # the input link and the coupler in line at lift ≈ 117 deg: the rocker turns back
        (
            lambda d: d["mechanism"]["joint"][0].__setitem__("upper", "120 deg"),
            "component.h_link",
            "passes its dead centre (ratio 0) at lift = 11",
        ),
        # a coupler too short: no assembly beyond lift ≈ 33 deg (the toggle)
        (
            lambda d: _component(d, "h_link").__setitem__("coupler_length", "0.33 m"),
            "component.h_link",
            "cannot be assembled",
        ),
        # the pivot linkage on the rocker: its pivots and axis in line inside the rocker's
        # swing as the joint moves in its limits (a chain's inner linkage)
        (
            lambda d: _component(d, "lift_linkage").__setitem__("angle_offset", "60 deg"),
            "component.lift_linkage",
            "passes its dead centre (ratio 0) at lift = ",
        ),
        # the rocker's zero at -70 deg: its angle, taken in ±180 deg about it, would jump
        # by a turn where θ₄ = 110 deg, at lift ≈ 12 deg
        (
            lambda d: _component(d, "h_link").__setitem__("output_angle_offset", "-70 deg"),
            "component.h_link",
            "the slave rocker passes 180 deg from its zero (its angle would jump by a turn) "
            "at lift = 1",
        ),
    ],
)
def test_dead_centres_are_refused_before_a_run(edit, field, words):
    doc = _doc()
    edit(doc)
    with pytest.raises(HydroarmError) as e:
        build(circuit_from_doc(doc, "bad", DATA))
    assert e.value.field == field, str(e.value)
    assert words in str(e.value), str(e.value)
    assert "\n" not in str(e.value)


def test_dead_centre_is_one_line_from_the_command_line(tmp_path, capsys):
    from hydroarm.cli import main

    text = (DATA / "four_bar.toml").read_text().replace('upper = "60 deg"', 'upper = "120 deg"')
    cfg = tmp_path / "bad.toml"
    cfg.write_text(text)
    assert main(["arm", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("hydroarm: error: component.h_link: the linkage passes its dead")
    assert not (tmp_path / "o").exists()


def test_a_large_gear_ratio_is_not_taken_for_a_jump():
    """The jump check compares a rotational slave's motion between two points of the grid
    with g'·Δq: a motor behind a 400:1 gearbox on a joint without limits turns 400 turns
    over the joint's one (2.8 rad between grid points), and is no jump."""
    doc = parse_toml((DATA / "pendulum.toml").read_text(), "pendulum.toml")
    doc.setdefault("component", []).extend(
        [
            {
                "type": "gear_drive",
                "name": "gearbox",
                "ports": {"joint": "swing", "drive": "motor"},
                "ratio": "400 rad/rad",
            },
            {
                "type": "inertia",
                "name": "rotor",
                "ports": {"body": "motor"},
                "inertia": "1e-5 kg*m**2",
            },
        ]
    )
    compiled = build(circuit_from_doc(doc, "geared", DATA))
    assert len(compiled.slaves) == 1
