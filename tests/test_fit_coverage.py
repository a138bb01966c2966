"""Coverage of the fit's 95 % intervals (issue 16): over repeated noise seeds, the fraction
of intervals containing the truth must be what a 95 % interval promises, within the binomial
spread of a finite number of trials. Short traces on the batch engine keep it fast."""

import numpy as np
import pytest
from scipy import stats

import hydroarm as ha
from hydroarm.analysis.fit import FitProblem, Trace, model_samples, run_fit

SEEDS = 40
NOISE_MM = 0.05  # [mm] white noise on the jack position
TIMES = np.arange(0.005, 0.4, 0.005)  # [s] 79 samples of the first 0.4 s of each test
PARAMS = ("flow_coefficient", "leakage_coefficient")


def truth_joint():
    j = ha.shoulder_elevation()
    return j.replace(
        flow_coefficient=j.flow_coefficient * 1.1, leakage_coefficient=j.leakage_coefficient * 1.1
    )


@pytest.fixture(scope="module")
def coverage():
    tru = truth_joint()
    load = ha.paper_load(6)
    shapes = [
        Trace(t=TIMES, values=np.ones_like(TIMES), column="x_mm", load=load, direction=d)
        for d in ("raise", "lower")
    ]
    clean = [s[:, 1] * 1e3 for s in model_samples([tru], shapes)[0]]  # x [mm] at TIMES
    truth = np.array([getattr(tru, k) for k in PARAMS])
    inside = np.zeros((SEEDS, len(PARAMS)), bool)
    for seed in range(SEEDS):
        rng = np.random.default_rng(seed)
        traces = tuple(
            Trace(
                t=TIMES,
                values=c + rng.normal(0.0, NOISE_MM, len(TIMES)),
                column="x_mm",
                load=load,
                direction=s.direction,
                name=s.direction or "",
            )
            for c, s in zip(clean, shapes, strict=True)
        )
        res = run_fit(FitProblem(tru, PARAMS, traces))  # from the truth: fewer iterations
        inside[seed] = (res.ci95_low <= truth) & (truth <= res.ci95_high)
    return inside


def test_95_percent_intervals_cover_the_truth_at_their_rate(coverage):
    # Per parameter the 40 seeds are independent trials, each covering with probability 0.95
    # if the intervals are right: the count is Binomial(40, 0.95). The 99 % acceptance band
    # is its 0.5 % and 99.5 % quantiles, [34, 40]: a correct interval fails this test 1 % of
    # the time per parameter (fixed seeds: the outcome is reproducible, not flaky); too
    # narrow intervals (e.g. correlated noise or a wrong s²) give fewer than 34.
    lo, hi = stats.binom.ppf([0.005, 0.995], SEEDS, 0.95)
    counts = coverage.sum(axis=0)
    for k, n in zip(PARAMS, counts, strict=True):
        assert lo <= n <= hi, f"{k}: {n}/{SEEDS} intervals contain the truth, band [{lo}, {hi}]"
    # both parameters together (80 intervals; the two of a seed are correlated, +0.5, so this
    # is reported, not tested): the fraction
    print(f"coverage {coverage.mean():.3f} over {coverage.size} intervals; per parameter {counts}")
