"""Batch engine and sweeps (issue 6): one physics with the single path, parsing, thread and
executor independence, interrupted sweeps resumed to the same file."""

import math

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.batch.engine import METRICS, run_scenarios
from hydroarm.batch.sweep import parameter_column, parse_sweep, run_sweep
from hydroarm.cli import main
from hydroarm.errors import HydroarmError
from hydroarm.integrators.fixed import EULER
from hydroarm.io.catalog import paper_load
from hydroarm.metrics.step import step_metrics, unit_name


def _single_metrics(sc):
    # the batch measures up to the target (or up to the stall when it stalls)
    r = ha.simulate(sc)
    kw = dict(
        valve_opening=sc.joint.valve_saturation,
        target=sc.target,
        t_start=0.0,
        full_opening_velocity=sc.joint.no_load_velocity,
    )
    stalled = step_metrics(r.t, r.x, **kw)["stalled"]
    return r, step_metrics(r.t, r.x, x_end=None if stalled else sc.target, **kw)


# every option of the physics issue on: such blocks run the general (not the paper) lanes
OPTIONS = dict(
    torque_arm="kinematic",
    valve_model="orifice",
    coulomb_friction=18.0,
    static_friction=25.0,
    viscous_friction=200.0,
    gearbox_friction_torque=0.05,
    gearbox_loss_at_stall=0.2,
    end_stop_angle=1.1,
)


@pytest.mark.parametrize("set_name", ["paper-calibrated", "ucl-arm-measured", "all-options"])
@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_batch_equals_single_path(set_name, method):
    import dataclasses

    if set_name == "all-options":
        j = dataclasses.replace(ha.parameter_set("paper-calibrated"), **OPTIONS)
    else:
        j = ha.parameter_set(set_name)
    scs = [
        ha.saturation_test(j, paper_load(k), d, method=method, duration=1.0)
        for k in (1, 6)
        for d in ("raise", "lower")
    ]
    for sc, mb in zip(scs, run_scenarios(scs), strict=True):
        r, ms = _single_metrics(sc)
        assert mb["final_x"] == pytest.approx(r.x[-1], rel=1e-12, abs=0)
        assert mb["peak_pressure"] == pytest.approx(np.max(np.abs(r.p)), rel=1e-12)
        assert mb["saturation_velocity"] == pytest.approx(ms["saturation_velocity"], rel=1e-12)
        # the 63 % crossing of a central-difference velocity: numpy.gradient's non-uniform
        # formula on t = k·h rounds differently in the last bits
        assert mb["time_constant_start"] == pytest.approx(ms["time_constant_start"], rel=1e-9)
        assert bool(mb["stalled"]) == ms["stalled"]


def _solo_rows(params, th0, p0, y0, y1, **kw):
    from hydroarm.batch.engine import run_batch

    return np.array(
        [
            run_batch(
                EULER,
                params[i : i + 1],
                th0[i : i + 1],
                p0[i : i + 1],
                y0[i : i + 1],
                y1[i : i + 1],
                **kw,
            )[0]
            for i in range(len(params))
        ]
    )


def test_lanes_independent_of_their_neighbours():
    # 21 scenarios: a full block of LANES = 16 and a short one; paper physics and options
    # mixed in one block, and one scenario whose state overflows. Each row must equal the
    # scenario run alone, bit for bit, and the overflow must not touch its neighbours.
    import dataclasses

    from hydroarm.batch.engine import LANES, run_batch
    from hydroarm.core.params import J_BETA, J_FLOW_COEFF

    base = ha.parameter_set("paper-calibrated")
    scs = []
    for i in range(21):
        j = dataclasses.replace(base, **OPTIONS) if i % 5 == 2 else base
        scs.append(
            ha.saturation_test(j, paper_load(1 + i % 8), ("raise", "lower")[i % 2], duration=0.25)
        )
    assert LANES < len(scs) < 2 * LANES
    params = np.array([sc.row for sc in scs])
    params[8, J_BETA] *= 1e8  # far beyond the Euler step's stability limit: overflows
    params[8, J_FLOW_COEFF] *= 10
    th0 = np.array([sc.initial_angle for sc in scs])
    p0 = np.array([sc.start_pressure() for sc in scs])
    y0 = np.array([float(sc.lever.positions[0]) for sc in scs])
    y1 = np.array([sc.target for sc in scs])
    kw = dict(t_step=0.0, h=scs[0].step, nsteps=scs[0].nsteps)
    together = run_batch(EULER, params, th0, p0, y0, y1, **kw)
    alone = _solo_rows(params, th0, p0, y0, y1, **kw)
    np.testing.assert_array_equal(together, alone)
    failed = together[:, METRICS.index("failed")]
    # the overflow is caught as it leaves the physical bounds (code 2, out_of_bounds)
    assert failed[8] == 2.0 and np.count_nonzero(failed) == 1


def test_batch_stalled_motion_velocity_up_to_stall():
    j = ha.parameter_set("ucl-arm-measured")
    load = ha.Load(weight=30.0, arm=0.3, inertia=0.3)  # beyond the arm's stall at horizontal
    sc = ha.saturation_test(j, load, "raise", duration=1.5)
    mb = run_scenarios([sc])[0]
    r = ha.simulate(sc)
    ms = r.metrics(t_start=0.0)
    assert mb["stalled"] == 1.0 and ms["stalled"]
    assert mb["saturation_velocity"] == pytest.approx(ms["saturation_velocity_m_s"], rel=1e-9)


SWEEP = {
    "scenario": {
        "joint": {"parameter_set": "paper-calibrated"},
        "load": {"builtin": 6},
        "input": {"direction": "raise"},
        "solver": {"duration": "0.3 s", "step": "20 us"},
    },
    "grid": {
        "weight": ["15 N", "20 N"],
        "supply_pressure": {"start": "25 bar", "stop": "35 bar", "num": 3},
    },
    "monte_carlo": {
        "n": 5,
        "seed": 7,
        "flow_coefficient": {"distribution": "normal", "relative_sd": 0.1},
        "leakage_coefficient": {"distribution": "uniform", "relative": 0.2},
    },
}


def _sweep(**changes):
    import copy

    doc = copy.deepcopy(SWEEP)
    for k, v in changes.items():
        sec, key = k.split("__")
        if v is None:
            doc[sec].pop(key)
        else:
            doc[sec][key] = v
    return parse_sweep(doc)


def test_sweep_parsed():
    sw = _sweep()
    assert sw.size == 2 * 3 * 5
    assert sw.names == ["weight", "supply_pressure", "flow_coefficient", "leakage_coefficient"]
    assert set(np.round(sw.values[:, 1] / 1e5, 6)) == {25.0, 30.0, 35.0}
    # the same seed gives the same draws
    assert np.array_equal(_sweep().values, sw.values)
    assert not np.array_equal(_sweep(monte_carlo__seed=8).values, sw.values)


@pytest.mark.parametrize(
    "change, field",
    [
        ({"grid__gravity": ["1 N"]}, "grid.gravity"),
        ({"grid__weight": ["15 bar"]}, "grid.weight"),
        ({"grid__weight": []}, "grid.weight"),
        ({"grid__supply_pressure": {"start": "25 bar", "num": 3}}, "grid.supply_pressure.stop"),
        ({"monte_carlo__seed": None}, "monte_carlo.seed"),
        ({"monte_carlo__n": 0}, "monte_carlo.n"),
        (
            {"monte_carlo__flow_coefficient": {"distribution": "cauchy"}},
            "monte_carlo.flow_coefficient.distribution",
        ),
        (
            {"monte_carlo__flow_coefficient": {"distribution": "normal", "relative_sd": 5.0}},
            "monte_carlo.flow_coefficient",
        ),
        (
            {"monte_carlo__leakage_coefficient": {"distribution": "uniform", "low": "2 N"}},
            "monte_carlo.leakage_coefficient",
        ),
    ],
)
def test_sweep_errors(change, field):
    with pytest.raises(HydroarmError, match=field.replace(".", r"\.")):
        _sweep(**change)


def test_results_independent_of_threads(tmp_path):
    import numba

    sw = _sweep()
    n0 = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        run_sweep(sw, tmp_path / "one.csv", chunk=7)
        numba.set_num_threads(n0)
        run_sweep(sw, tmp_path / "all.csv", chunk=30)
    finally:
        numba.set_num_threads(n0)
    assert (tmp_path / "one.csv").read_bytes() == (tmp_path / "all.csv").read_bytes()


def test_interrupted_sweep_resumes_to_the_same_file(tmp_path):
    sw = _sweep()
    run_sweep(sw, tmp_path / "full.csv", chunk=4)
    with pytest.raises(HydroarmError, match="--resume"):
        run_sweep(sw, tmp_path / "cut.csv", chunk=4, stop_after=3)
    assert not (tmp_path / "cut.csv").exists()
    kept = sorted((tmp_path / "cut.csv.parts").glob("chunk_*.npy"))
    assert len(kept) == 3
    with pytest.raises(HydroarmError, match="--resume"):  # refuses to overwrite silently
        run_sweep(sw, tmp_path / "cut.csv", chunk=4)
    with pytest.raises(HydroarmError, match="different sweep"):
        run_sweep(sw, tmp_path / "cut.csv", chunk=5, resume=True)
    run_sweep(sw, tmp_path / "cut.csv", chunk=4, resume=True)
    assert (tmp_path / "cut.csv").read_bytes() == (tmp_path / "full.csv").read_bytes()
    assert not (tmp_path / "cut.csv.parts").exists()


def test_parquet_output(tmp_path):
    pd = pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    sw = _sweep()
    run_sweep(sw, tmp_path / "r.parquet", chunk=16)
    df = pd.read_parquet(tmp_path / "r.parquet")
    assert list(df.columns) == [
        "scenario",
        *map(parameter_column, sw.names),
        *map(unit_name, METRICS),
    ]
    assert len(df) == sw.size and not df["failed"].any()


@pytest.mark.slow
def test_dask_local_cluster_matches_local(tmp_path):
    pytest.importorskip("dask.distributed")
    sw = _sweep()
    run_sweep(sw, tmp_path / "local.csv", chunk=8)
    run_sweep(sw, tmp_path / "dask.csv", chunk=8, executor="dask")  # LocalCluster, 2 workers
    assert (tmp_path / "dask.csv").read_bytes() == (tmp_path / "local.csv").read_bytes()


def test_sweep_cli(tmp_path, capsys):
    cfg = tmp_path / "s.toml"
    cfg.write_text("""
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "lower"
[scenario.solver]
duration = "0.3 s"
[grid]
weight = { start = "10 N", stop = "20 N", num = 4 }
""")
    assert main(["sweep", "--config", str(cfg), "--out", str(tmp_path / "r.csv")]) == 0
    rows = (tmp_path / "r.csv").read_text().splitlines()
    assert rows[0].startswith("scenario,weight_n,saturation_velocity_m_s") and len(rows) == 5
    v = [float(r.split(",")[2]) for r in rows[1:]]
    assert all(math.isfinite(x) for x in v) and v == sorted(v)  # heavier falls faster
    assert main(["sweep", "--config", str(cfg), "--out", str(tmp_path / "r.txt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("hydroarm: error: --out")
