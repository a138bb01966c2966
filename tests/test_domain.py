"""Issue 20: valid input never gives silent nonsense.

Random valid scenarios (every physics option of ServoJoint, both fixed-step methods, steps
up to the accepted limit): a run either stays finite and within the physical bounds or
raises the one clear error; the suggested largest stable step is itself accepted; tiny
steps are never refused as too large; a swing past the crank's dead centre and a joint held
by friction are reported as such; failed sweep rows carry NaN metrics and stay out of the
summary.
"""

from __future__ import annotations

import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hydroarm as ha
from hydroarm.batch import sweep as sweep_mod
from hydroarm.batch.engine import METRICS, run_scenarios
from hydroarm.cli import main
from hydroarm.core.equations import crank_reach, pressure_bound
from hydroarm.integrators.stability import stable_step_limit
from hydroarm.metrics.step import unit_name

BASE = ha.parameter_set("paper-calibrated")
SETTINGS = settings(
    max_examples=30,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)


def make_scenario(d: dict) -> ha.Scenario:
    """A valid scenario from a dictionary of draws (factors on the paper's joint, a load,
    physics options, a motion); the step is set by the caller."""
    j = BASE.replace(
        piston_area=BASE.piston_area * d["area"],
        flow_coefficient=BASE.flow_coefficient * d["flow"],
        valve_saturation=BASE.valve_saturation * d["eo"],
        leakage_coefficient=BASE.leakage_coefficient * d["leak"],
        trapped_volume=BASE.trapped_volume * d["volume"],
        bulk_modulus=BASE.bulk_modulus * d["beta"],
        supply_pressure=BASE.supply_pressure * d["supply"],
        gear_ratio=d["ratio"],
        torque_arm=d["torque_arm"],
        valve_model=d["valve"],
        coulomb_friction=d["coulomb"],
        static_friction=d["coulomb"] * d["stiction"],
        viscous_friction=d["viscous"],
        gearbox_friction_torque=d["gb_t0"],
        gearbox_loss_at_stall=d["gb_loss"],
        gearbox_loss_exponent=d["gb_exp"],
        end_stop_angle=(d["stop"] * d["ratio"] * math.pi / 2) if d["stop"] else None,
    )
    reach = 0.8 * j.max_angle * (d["stop"] or 1.0)
    a0, a1 = d["a0"] * reach, d["a1"] * reach
    load = ha.Load(weight=d["weight"], arm=d["arm"], inertia=d["inertia"], name="random")
    return ha.Scenario(
        joint=j,
        load=load,
        lever=ha.step(j.jack_position(a0), j.jack_position(a1), 0.01),
        initial_angle=a0,
        duration=d["duration"],
        method=d["method"],
        step=1e-6,
    )


def _factor(lo, hi):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


DRAWS = st.fixed_dictionaries(
    {
        "area": _factor(0.5, 2),
        "flow": _factor(0.5, 2),
        "eo": _factor(0.5, 2),
        "leak": st.sampled_from([0.0, 1.0]) | _factor(0.1, 20),
        "volume": _factor(0.3, 3),
        "beta": _factor(0.3, 3),
        "supply": _factor(0.5, 2),
        "ratio": st.floats(1.0, 3.0),
        "torque_arm": st.sampled_from(["paper", "kinematic"]),
        "valve": st.sampled_from(["linear", "orifice"]),
        "coulomb": st.sampled_from([0.0]) | st.floats(0.0, 60.0),
        "stiction": st.floats(1.0, 2.0),
        "viscous": st.sampled_from([0.0]) | st.floats(0.0, 3000.0),
        "gb_t0": st.sampled_from([0.0]) | st.floats(0.0, 1.0),
        "gb_loss": st.sampled_from([0.0]) | st.floats(0.0, 0.5),
        "gb_exp": st.floats(0.5, 2.0),
        "stop": st.sampled_from([0.0, 0.9]),
        "weight": st.floats(0.0, 30.0),
        "arm": st.floats(0.0, 0.35),
        "inertia": _factor(2e-5, 0.3),
        "a0": st.floats(-1.0, 1.0),
        "a1": st.floats(-1.0, 1.0),
        "duration": st.floats(0.05, 0.3),
        "method": st.sampled_from(["euler", "rk4"]),
        "fraction": st.floats(0.05, 1.0),
    }
)


def _check_run(sc: ha.Scenario) -> None:
    """The run is finite and within the physical bounds, or raises the clear error."""
    try:
        r = ha.simulate(sc)
    except ha.StabilityError as e:
        assert "physical bounds" in str(e) or "dead centre" in str(e), str(e)
        return
    J, L = sc.params
    assert np.all(np.isfinite(r.theta)) and np.all(np.isfinite(r.p))
    assert np.all(np.abs(r.p) < pressure_bound(sc.start_pressure(), J, L))
    assert np.all(np.abs(r.theta) < crank_reach(J))


@pytest.mark.slow
@SETTINGS
@given(DRAWS)
def test_random_scenarios_accepted_step_is_stable(d):
    sc = make_scenario(d)
    h = sc.largest_stable_step()
    # the suggested step is accepted
    assert stable_step_limit(sc.method, h, sc.initial_angle, sc.target_angle(), *sc.params) is None
    step = min(h * d["fraction"], sc.duration / 10)
    step = max(step, sc.duration / 200_000)  # keep the run short (CI budget)
    sc = sc.replace(step=step)
    if step <= h:
        sc.check_step()  # accepted
        _check_run(sc)
    else:  # the CI floor on the step lifted it above the limit
        _check_run_unchecked(sc)
    # the same scenario through the batch engine: failed rows carry NaN metrics
    (m,) = run_scenarios([sc])
    if m["failed"]:
        assert m["failure"] in ("unstable", "out_of_bounds", "past_dead_centre")
        assert all(math.isnan(m[k]) for k in METRICS if k not in ("failed", "stalled"))
    else:
        assert m["failure"] is None
        assert m["peak_pressure"] < pressure_bound(sc.start_pressure(), *sc.params)


@pytest.mark.slow
@SETTINGS
@given(DRAWS)
def test_above_the_limit_never_silent(d):
    """A step far above the limit, run without the check: the clear error, or a sane run."""
    sc = make_scenario(d)
    h = sc.largest_stable_step()
    step = min(h * (2 + 20 * d["fraction"]), sc.duration / 10)
    _check_run_unchecked(sc.replace(step=step))


def _check_run_unchecked(sc):
    try:
        r = ha.simulate(sc, check_stability=False)
    except ha.StabilityError as e:
        assert "physical bounds" in str(e) or "dead centre" in str(e), str(e)
        return
    J, L = sc.params
    assert np.all(np.isfinite(r.p)) and np.all(np.isfinite(r.theta))
    assert np.all(np.abs(r.p) < pressure_bound(sc.start_pressure(), J, L))
    assert np.all(np.abs(r.theta) < crank_reach(J))


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_tiny_steps_are_never_too_large(method):
    sc = ha.saturation_test(BASE, ha.paper_load(6), "raise", method=method, duration=1e-4)
    for step in (1e-12, 1e-10, 1e-8, 1e-7):
        sc.replace(step=step).check_step()  # no refusal
    r = ha.simulate(sc.replace(step=1e-8))
    assert np.all(np.isfinite(r.p))


def test_too_small_a_step_says_so():
    sc = ha.saturation_test(BASE, ha.paper_load(6), "raise", duration=1.5, step=1e-12)
    with pytest.raises(ha.HydroarmError, match="too small"):
        ha.simulate(sc)


def test_suggested_step_accepted_and_refusal_names_it():
    sc = ha.saturation_test(BASE, ha.paper_load(6), "raise", duration=0.2)
    for method in ("euler", "rk4"):
        h = sc.largest_stable_step(method)
        sc.replace(method=method, step=h).check_step()
        with pytest.raises(ha.StabilityError, match="too large") as e:
            sc.replace(method=method, step=min(1.5 * h, 0.1)).check_step()
        assert e.value.largest_stable_step == pytest.approx(h)


def _past_dead_centre():
    """A heavy load beyond the top on a weak supply: it falls on past the dead centre."""
    j = BASE.replace(supply_pressure=0.2 * BASE.supply_pressure, torque_arm="kinematic")
    load = ha.Load(weight=30.0, arm=0.35, inertia=0.15, name="heavy")
    a0 = 0.85 * j.max_angle
    return ha.Scenario(
        joint=j,
        load=load,
        lever=ha.step(j.jack_position(a0), j.jack_position(0.9 * j.max_angle), 0.0),
        initial_angle=a0,
        duration=0.3,
        step=2e-6,
    )


def test_past_dead_centre_is_flagged():
    sc = _past_dead_centre()
    with pytest.raises(ha.StabilityError, match="dead centre"):
        ha.simulate(sc)
    (m,) = run_scenarios([sc])
    assert m["failed"] and m["failure"] == "past_dead_centre"
    assert math.isnan(m["saturation_velocity"]) and not m["stalled"]


NO_LEAKAGE = """
[joint]
parameter_set = "paper-calibrated"
leakage_coefficient = "0 mm**5/s/N"
[load]
builtin = 6
[input]
direction = "DIRECTION"
"""


@pytest.mark.parametrize("direction", ["raise", "lower"])
def test_no_leakage_unstable_loop_is_named(direction, tmp_path, capsys):
    """Issue 13: with L = 0 the paper's loop is unstable (nothing damps the oil column); the run
    stops with one line naming the cause, not blaming a step that is stable."""
    path = tmp_path / "l0.toml"
    path.write_text(NO_LEAKAGE.replace("DIRECTION", direction))
    assert main(["simulate", "--config", str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("hydroarm: error: joint.leakage_coefficient: the servo loop is unstable")
    assert "diverged" in line and "with no leakage nothing damps the oil column" in line
    assert "the step, 10 us, is not the cause" in line and "reduce the step" not in line
    # the Python API: the same error, the oscillation's growth rate > 0
    sc = ha.saturation_test(BASE.replace(leakage_coefficient=0.0), ha.paper_load(6), direction)
    with pytest.raises(ha.StabilityError, match=r"oscillation grows at 16\.7/s") as e:
        ha.simulate(sc)
    assert e.value.field == "joint.leakage_coefficient"


def test_friction_held_stall_is_a_stall():
    j = BASE.replace(coulomb_friction=5000.0)
    sc = ha.saturation_test(j, ha.paper_load(6), "raise", duration=0.2)
    r = ha.simulate(sc)
    m = r.metrics()
    assert m["stalled"] is True
    assert math.isnan(m["saturation_velocity_m_s"]) and math.isnan(m["time_constant_start_s"])
    assert "does not move" in m["stall_reason"]
    s = r.summary()
    assert s["stalled"] is True and s["saturation_velocity_mm_s"] is None
    with pytest.raises(ha.HydroarmError, match="does not move"):  # no target: still an error
        ha.step_metrics(r.t, np.full_like(r.t, r.x[0]))


def test_failed_sweep_rows_excluded_from_summary(tmp_path):
    good = ha.saturation_test(BASE, ha.paper_load(6), "raise", duration=1.0, step=1e-4)
    bad = _past_dead_centre()
    rows = run_scenarios([good.replace(lever=ha.step(good.lever.positions[0], good.target, 0.0))])
    rows += run_scenarios([bad])
    metrics = np.array([[r[k] for k in METRICS] for r in rows], float)
    assert metrics[1, METRICS.index("failed")] == 3.0
    assert np.all(np.isnan(metrics[1, :3]))
    path = tmp_path / "s.csv"
    head = ",".join(["scenario", *(unit_name(k) for k in METRICS)])  # as a sweep writes it
    lines = [head]
    for i, row in enumerate(metrics):
        fields = [str(i)]
        for k, v in zip(METRICS, row, strict=True):
            fields.append(str(v > 0.5) if k in ("stalled", "failed") else sweep_mod._csv_field(v))
        lines.append(",".join(fields))
    # an old file's failed row with garbage metrics
    lines.append(lines[-1].replace(",,", ",7.99e198,", 1))
    path.write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        s = sweep_mod.summary(path)
    assert s["scenarios"] == 3 and s["failed"] == 2 and s["measured"] == 1
    assert s["saturation_velocity_mm_s_mean"] == pytest.approx(1e3 * metrics[0, 0])
    assert math.isnan(s["saturation_velocity_mm_s_sd"])


def test_cli_friction_held_stall(tmp_path, capsys):
    """`hydroarm simulate` on a joint its friction holds: a table and a stall, exit 0."""
    cfg = tmp_path / "held.toml"
    cfg.write_text(
        '[joint]\nparameter_set = "paper-calibrated"\n[physics]\ncoulomb_friction = "5000 N"\n'
        '[load]\nbuiltin = 6\n[input]\ndirection = "raise"\n[solver]\nduration = "0.2 s"\n'
    )
    assert main(["simulate", "--config", str(cfg)]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert "no motion to measure" in last and "[stalled]" in last


def test_sweep_file_names_why_rows_failed(tmp_path):
    """A sweep file gains a `failure` column when some row failed (only then: files of sweeps
    without failures keep their columns)."""
    metrics = np.zeros((3, len(METRICS)))
    metrics[1, METRICS.index("failed")] = 2.0
    metrics[1, :3] = np.nan
    sw = SimpleNamespace(size=3, names=["weight"], values=np.array([[10.0], [20.0], [30.0]]))
    sw.columns = lambda m: sweep_mod._columns(sw, m)  # the joint sweep's columns
    out = tmp_path / "r.csv"
    sweep_mod._write(out, sw, metrics)
    rows = out.read_text().splitlines()
    assert rows[0].split(",")[-1] == "failure"
    assert [r.split(",")[-1] for r in rows[1:]] == ["", "out_of_bounds", ""]
    sweep_mod._write(out, sw, np.zeros((3, len(METRICS))))
    assert "failure" not in out.read_text().splitlines()[0]
