"""Honest fit intervals (issue 29; hydroarm/analysis/fit_intervals.py): the profile
likelihood on models whose answer is known (a linear model: the profile interval is the
Jacobian's exactly; a bound; a parameter the data do not see), the checks that say when a
Jacobian interval is not to be trusted, and a system fit with ``intervals = "profile"``
end to end (fit.csv, the plot, the report, the progress lines)."""

import csv
import math
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from hydroarm.analysis.fit import PENALTY, TRACE_TOL, fd_points, least_squares
from hydroarm.analysis.fit_intervals import (
    CONDITION_LIMIT,
    ProfileRun,
    interval_checks,
    linear_ends,
    profile_intervals,
)

ROOT = pathlib.Path(__file__).resolve().parent.parent


class Residuals:
    """A model as the fit sees it: residuals of scaled parameters z, their forward
    differences on the fit's own steps (:func:`fd_points`), the batch engine's flag."""

    engine = "batch"

    def __init__(self, f):
        self.f = f
        self.calls = 0

    def __call__(self, z):
        self.calls += 1
        return self.f(np.asarray(z, float))

    def jacobian(self, z, lo, hi, central=False, free=None):
        z = np.asarray(z, float)
        Z, derivative = fd_points(z, lo, hi, central, free)
        return derivative(self(z), np.array([self(x) for x in Z]))


def _fit(f, z0, lo, hi):
    """The fit's optimiser and statistics on ``f``: (run for profile_intervals, Jacobian
    interval low and high, the solution)."""
    model = Residuals(f)
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    sol = least_squares(model, np.asarray(z0, float), lambda z: model.jacobian(z, lo, hi),
                        lo, hi, TRACE_TOL)  # fmt: skip
    m, n = len(sol.fun), len(sol.x)
    s2 = float(sol.fun @ sol.fun) / (m - n)
    tq = float(stats.t.ppf(0.975, m - n))
    cov = np.linalg.pinv(sol.jac.T @ sol.jac) * s2
    se = np.sqrt(np.diag(cov))
    run = ProfileRun(
        model=model, least_squares=least_squares, z_hat=sol.x, cost_min=float(sol.fun @ sol.fun),
        cov_z=cov, delta=tq**2 * s2, quantile=tq, lo_z=lo, hi_z=hi, scale=np.ones(n),
        central=False, tol=TRACE_TOL, penalty=PENALTY, names=tuple(f"p{i}" for i in range(n)),
    )  # fmt: skip
    return run, sol.x - tq * se, sol.x + tq * se, sol


def _linear_data():
    rng = np.random.default_rng(3)
    x = np.linspace(0.0, 1.0, 40)
    A = np.column_stack([np.ones_like(x), x, x**2])
    y = A @ np.array([1.0, -2.0, 0.5]) + rng.normal(0, 0.05, x.size)
    return A, y


def test_a_linear_models_profile_interval_is_the_jacobians():
    """For residuals linear in the parameters the cost is exactly quadratic: the profile
    reaches Δ = t²·s² at estimate ± t·SE (module doc), and the interpolation in √q is exact,
    so the ends agree to the optimiser's tolerance."""
    A, y = _linear_data()
    run, low, high, sol = _fit(lambda z: A @ z - y, [0.5, 0.5, 0.5], [-np.inf] * 3, [np.inf] * 3)
    profiles = profile_intervals(run, budget=60)
    for i, p in enumerate(profiles):
        assert p.ends == "closed"
        width = high[i] - low[i]
        # 1e-6 of the width: the refits stop at ftol = xtol = 1e-10 of the cost and the
        # forward differences' error is ≈ 1e-4 × curvature, which a linear model has none of
        assert abs(p.low - low[i]) < 1e-6 * width and abs(p.high - high[i]) < 1e-6 * width
        assert p.refits <= 4  # one step to the Jacobian's end, at most a refinement a side


def _end_q(run, f):
    """The cost's rise over Δ at the linear theory's interval ends (run.py's end_costs on a
    plain function): parameter × low/high."""
    points, where = linear_ends(run.z_hat, run.cov_z, run.quantile, run.lo_z, run.hi_z)
    q = np.full((len(run.z_hat), 2), np.nan)
    for (i, side), z in zip(where, points, strict=True):
        r = f(z)
        q[i, side] = (r @ r - run.cost_min) / run.delta
    return q


def test_the_curvature_check_is_silent_on_a_linear_model_and_speaks_on_a_curved_one():
    """Without a profile, the cost at the Jacobian interval's ends as the linear theory
    places them: exactly Δ (q = 1) for a linear model; for y = a·exp(−k·x) with noise of
    30 % of its peak, k's cost rises 4.6 Δ at its lower end (q > 1.5²), 0.59 Δ at its upper:
    the profile too says so (its ends 0.80 and 4.07 against the Jacobian's 0.37 and 3.08)."""
    A, y = _linear_data()
    f = lambda z: A @ z - y  # noqa: E731
    run, low, high, sol = _fit(f, [0.5, 0.5, 0.5], [-np.inf] * 3, [np.inf] * 3)
    q = _end_q(run, f)
    assert np.allclose(q, 1.0, atol=1e-6)  # the optimiser's tolerance, 1e-10 of the cost
    checks = interval_checks(run.names, sol.jac, sol.x, low, high, (run.lo_z, run.hi_z), end_q=q)
    assert checks.warnings == []
    x = np.linspace(0.0, 3.0, 30)
    rng = np.random.default_rng(2)
    y2 = 1.0 * np.exp(-2.0 * x) + rng.normal(0, 0.3, x.size)  # noise 30 % of the peak
    g = lambda z: z[0] * np.exp(-z[1] * x) - y2  # noqa: E731
    run, low, high, sol = _fit(g, [1.0, 2.0], [0.01, 0.01], [np.inf, np.inf])
    q = _end_q(run, g)
    assert q[1, 0] > 1.5**2  # k's lower end: the cost rises 4.6 Δ (the interval too wide)
    checks = interval_checks(run.names, sol.jac, sol.x, low, high, (run.lo_z, run.hi_z), end_q=q)
    assert checks.flags[1] == ["nonlinear"] and checks.flag(0) == "none"  # a: q 1.32, 0.88
    profiles = profile_intervals(run, budget=40)
    ratio_high = (profiles[1].high - sol.x[1]) / (high[1] - sol.x[1])
    assert ratio_high > 1.5  # the profile's upper side 1.7 times the Jacobian's
    with_profile = interval_checks(run.names, sol.jac, sol.x, low, high,
                                   (run.lo_z, run.hi_z), profiles=profiles)  # fmt: skip
    assert with_profile.flags[1] == ["nonlinear"]


def test_a_bound_inside_the_interval_leaves_that_side_open():
    """p1 ≥ −2.05 where its estimate is near −2 and its Jacobian interval reaches below
    −2.05: the bound is the profile's lower end."""
    A, y = _linear_data()
    lo, hi = np.array([-np.inf, -2.05, -np.inf]), np.array([np.inf] * 3)
    run, low, high, sol = _fit(lambda z: A @ z - y, [1.0, -1.0, 0.5], lo, hi)
    pf = profile_intervals(run, budget=60)[1]
    assert low[1] < lo[1]  # the Jacobian's interval reaches past the bound
    assert pf.low == pytest.approx(-2.05) and pf.low_open == "bound" and pf.ends == "open_low"
    checks = interval_checks(
        run.names, sol.jac, sol.x, low, high, (lo, hi), profiles=[None, pf, None]
    )
    assert "at_bound" in checks.flags[1] and checks.flag(0) == "none"
    assert any("p1" in w and "bound" in w for w in checks.warnings)


def test_a_parameter_the_data_do_not_see_is_open_within_its_budget():
    """y = a·(1 − exp(−k·x)) sampled where exp(−k·x) ≈ 0 (x from 5 with k ≈ 3): k raises
    the cost hardly at all above its estimate (the curve is already flat), so the upper
    side of k's profile does not reach the threshold within its refits."""
    x = np.linspace(5.0, 6.0, 30)
    y = 2.0 * (1 - np.exp(-3.0 * x)) + np.random.default_rng(1).normal(0, 0.01, x.size)
    run, low, high, sol = _fit(lambda z: z[0] * (1 - np.exp(-z[1] * x)) - y, [2.0, 3.0],
                               [0.0, 0.0], [np.inf, np.inf])  # fmt: skip
    profiles = profile_intervals(run, budget=16)  # 4 refits a side
    k = profiles[1]
    assert k.high_open == "budget" and k.refits <= 8
    assert k.high > sol.x[1]  # the furthest value profiled, reported as where it got to


def test_a_bound_reached_through_a_correlation_is_flagged_too():
    """b is 1.5 SE above its bound 0, a correlated +0.9 with it: at the lower end of a's
    interval (a − 1.96 SE) the linear profile trace moves b by 0.9·1.96 SE, past 0, so a's
    interval cannot be reached either; with no correlation only b's own interval counts."""
    se, est = np.array([1.0, 1.0]), np.array([10.0, 1.5])
    low, high = est - 1.96 * se, est + 1.96 * se
    bounds = (np.array([-np.inf, 0.0]), np.array([np.inf, np.inf]))
    cov = np.array([[1.0, 0.9], [0.9, 1.0]])
    checks = interval_checks(("a", "b"), np.eye(2), est, low, high, bounds, cov=cov)
    assert checks.flags == [["at_bound"], ["at_bound"]]
    assert "puts b at" in checks.warnings[0]
    plain = interval_checks(("a", "b"), np.eye(2), est, low, high, bounds, cov=np.eye(2))
    assert plain.flags == [[], ["at_bound"]]


def test_an_ill_conditioned_jacobian_is_flagged_with_the_parameters_it_concerns():
    """Two columns equal to 1 part in 10⁵ (condition index ≈ 10⁵ > 10³): both parameters
    flagged, the third (orthogonal) not."""
    rng = np.random.default_rng(0)
    a, c = rng.normal(size=50), rng.normal(size=50)
    J = np.column_stack([a, a + 1e-5 * rng.normal(size=50), c])
    est, inf = np.zeros(3), np.full(3, np.inf)
    checks = interval_checks(("a", "b", "c"), J, est, est - 1, est + 1, (-inf, inf))
    assert checks.flags == [["ill_conditioned"], ["ill_conditioned"], []]
    assert f"{CONDITION_LIMIT:.0e}" in checks.warnings[0]
    # the same columns far apart: nothing to say
    J[:, 1] = rng.normal(size=50)
    assert interval_checks(("a", "b", "c"), J, est, est - 1, est + 1, (-inf, inf)).warnings == []
    # a column of zeros (a parameter the residuals do not see, as a friction at 0 can be):
    # that parameter flagged, the others judged among themselves
    J[:, 1] = 0.0
    zero = interval_checks(("a", "b", "c"), J, est, est - 1, est + 1, (-inf, inf))
    assert zero.flags == [[], ["ill_conditioned"], []] and "zero column" in zero.warnings[0]


def test_starts_that_end_apart_at_the_same_cost_are_called_multimodal():
    est, inf = np.array([1.0, 2.0]), np.full(2, np.inf)
    starts = [
        {"estimate": est, "cost": 1.00},
        {"estimate": np.array([1.05, 5.0]), "cost": 1.02},  # within Δ, b outside: flagged
        {"estimate": np.array([9.0, 9.0]), "cost": 3.0},  # far worse: a poor local minimum
    ]
    checks = interval_checks(("a", "b"), np.eye(2), est, est - 0.1, est + 0.1, (-inf, inf),
                             starts=starts, delta=0.1)  # fmt: skip
    assert checks.flags == [[], ["multimodal"]]
    assert "start 2" in checks.warnings[0]


RIG = (ROOT / "examples" / "orifice_rig.toml").as_posix()
FIT = f"""[system]
file = "{RIG}"
duration = "0.15 s"
[fit]
parameters = ["orifice.area", "hose.bulk_modulus"]
intervals = "profile"
profile_refits = 24
[fit.initial]
"orifice.area" = "3 mm**2"
[[trace]]
csv = "{(ROOT / "examples" / "fit_circuit_measured.csv").as_posix()}"
columns = {{ t = ["time", "ms"], supply_pressure_bar = ["pressure", "psi"] }}
window = ["0 s", "0.15 s"]
"""


@pytest.fixture(scope="module")
def profiled(tmp_path_factory):
    """``hydroarm fit`` of the orifice rig's example data (0.15 s of the hose pressure)
    with ``intervals = "profile"``, from the command line, progress lines off a terminal."""
    d = tmp_path_factory.mktemp("profile")
    (d / "f.toml").write_text(FIT)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HYDROARM_PROGRESS_INTERVAL": "0",
           "NUMBA_NUM_THREADS": "1"}  # fmt: skip
    p = subprocess.run(
        [sys.executable, "-m", "hydroarm.cli", "fit", "--config", "f.toml", "--out", "out"],
        cwd=d, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    return d / "out", p


def test_a_system_fits_profile_intervals_are_written_plotted_and_reported(profiled):
    out, p = profiled
    rows = {r["parameter"]: r for r in csv.DictReader(open(out / "fit.csv"))}
    assert list(next(iter(rows.values()))) == [
        "parameter", "initial", "estimate", "std_error", "ci95_low", "ci95_high",
        "profile_low", "profile_high", "profile_ends", "jacobian_warning", "unit",
    ]  # fmt: skip
    truth = {"orifice.area": 2.6e-6, "hose.bulk_modulus": 1.5e9}  # fit_circuit_data.py
    for k, r in rows.items():
        lo, hi = float(r["profile_low"]), float(r["profile_high"])
        jl, jh = float(r["ci95_low"]), float(r["ci95_high"])
        assert r["profile_ends"] == "closed" and lo < float(r["estimate"]) < hi
        # this rig is nearly linear in its two parameters over their intervals: each side
        # of the profile within the warning's factor 1.5 of the Jacobian's (no flag)
        assert r["jacobian_warning"] == "none", r
        assert 1 / 1.5 < (hi - lo) / (jh - jl) < 1.5
        # the example's one noise draw (seed 29) lies inside both (as in test_fit_system)
        assert lo <= truth[k] <= hi
    assert (out / "profile.png").stat().st_size > 10_000
    report = (out / "fit_report.md").read_text()
    assert "Profile likelihood" in report and "profile.png" in report
    assert "profile 95 %" in p.stdout
    assert "profile:" in p.stderr and "refits" in p.stderr  # the progress lines


def test_the_profile_keeps_within_its_budget(profiled):
    out, p = profiled
    line = [ln for ln in p.stderr.splitlines() if "profile:" in ln and "failed" in ln][-1]
    refits = int(line.split("profile: ")[1].split(" refits")[0])
    assert 4 <= refits <= 24, line
    assert math.isfinite(float(next(csv.DictReader(open(out / "fit.csv")))["profile_low"]))


def test_the_profile_example_flags_the_friction_and_its_profiles_hold_the_truth(tmp_path):
    """examples/fit_boom_servo_profile.toml as the docs run it (``hydroarm fit --config …``
    is this call): the measured lift's truth (boom_servo_measured.csv's header: the file's
    values, viscous_friction 4200 N·s/m) inside the three profile intervals; the friction,
    which 0.6 s of lift barely sees, flagged: its Jacobian interval reaches below 0, and so,
    through their correlation with it, do the other two's ends."""
    import numba

    from hydroarm.analysis.fit import fit

    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # the rows are independent: the numbers do not change
    try:
        res = fit(str(ROOT / "examples" / "fit_boom_servo_profile.toml"), tmp_path / "out")
    finally:
        numba.set_num_threads(threads)
    truth = {"flow_coefficient": res.problem.system.runner.current("flow_coefficient"),
             "viscous_friction": 4200.0, "internal_leakage": 2e-12}  # fmt: skip
    rows = {r["parameter"]: r for r in csv.DictReader(open(tmp_path / "out" / "fit.csv"))}
    for p in res.profiles:
        # one noise draw (seed 7): each interval could miss 5 % of the time; this one holds
        assert p.low <= truth[p.parameter] <= p.high, p.describe()
    friction = rows["viscous_friction"]
    assert "at_bound" in friction["jacobian_warning"] and float(friction["ci95_low"]) < 0
    assert friction["profile_ends"] == "open_low" and float(friction["profile_low"]) == 0.0
    # the valve and the leakage are correlated with the friction (+0.89, −0.82): at their
    # Jacobian intervals' ends the linear theory puts the friction below 0, so those ends
    # cannot be reached either (their profiles, which keep the friction ≥ 0, are the ones)
    for k in ("flow_coefficient", "internal_leakage"):
        assert rows[k]["jacobian_warning"] == "at_bound", rows[k]
        assert any(w.startswith(f"{k}:") and "puts viscous_friction at" in w for w in res.warnings)
    assert (tmp_path / "out" / "profile.png").is_file()
    assert sum(p.refits for p in res.profiles) <= 48  # the file's profile_refits


def test_the_joints_fit_takes_the_same_profile():
    """The paper joint's fit (hydroarm/analysis/fit.py's own path, not a system's): K and L
    from 0.4 s of a raise and a lower test (tests/test_fit_coverage.py's set-up, one noise
    draw), profiled; the model is close to linear in them over their intervals, so each
    profile end lies within the warning's factor of the Jacobian's and nothing is flagged."""
    import hydroarm as ha
    from hydroarm.analysis.fit import FitProblem, Trace, model_samples, run_fit

    j = ha.shoulder_elevation()
    truth = j.replace(flow_coefficient=j.flow_coefficient * 1.1)
    times = np.arange(0.005, 0.4, 0.005)
    load = ha.paper_load(6)
    shapes = [Trace(t=times, values=times, column="x_mm", load=load, direction=d)
              for d in ("raise", "lower")]  # fmt: skip
    rng = np.random.default_rng(5)
    traces = tuple(
        Trace(t=times, values=s[:, 1] * 1e3 + rng.normal(0, 0.05, times.size), column="x_mm",
              load=load, direction=sh.direction, name=sh.direction or "")
        for s, sh in zip(model_samples([truth], shapes)[0], shapes, strict=True)
    )  # fmt: skip
    params = ("flow_coefficient", "leakage_coefficient")
    res = run_fit(FitProblem(truth, params, traces, intervals=("jacobian", "profile")))
    assert [p.parameter for p in res.profiles] == list(params)
    for i, p in enumerate(res.profiles):
        half = 0.5 * (res.ci95_high[i] - res.ci95_low[i])
        assert p.ends == "closed"
        for side in (res.estimate[i] - p.low, p.high - res.estimate[i]):
            assert 1 / 1.5 < side / half < 1.5
    assert [res.checks.flag(i) for i in range(2)] == ["none", "none"]
