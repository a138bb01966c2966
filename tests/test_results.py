"""One result shape: the column specification behind table(), to_csv() and to_pandas(),
plain-float metrics, and ArmResult.plot()."""

import csv
import math
from pathlib import Path

import numpy as np
import pytest

import hydroarm as ha
from hydroarm.arm import load_arm, simulate_arm
from hydroarm.errors import HydroarmError
from hydroarm.io.catalog import paper_load
from hydroarm.model.result import COLUMNS, DEFAULT_COLUMNS
from hydroarm.model.scenario import saturation_test, simulate

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "ucl-arm.toml"


@pytest.fixture(scope="module")
def res():
    return simulate(saturation_test(ha.parameter_set("paper-calibrated"), paper_load(6), "raise"))


@pytest.fixture(scope="module")
def arm_res():
    sc = load_arm(EXAMPLE)
    return simulate_arm(sc.replace(duration=0.4, record_every=50))


def read_csv(path):
    with open(path) as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], float)


def test_column_spec_is_complete():
    names = [c.name for c in COLUMNS]
    assert len(names) == len(set(names))
    assert set(DEFAULT_COLUMNS) <= set(names)
    for c in COLUMNS:
        assert c.unit and c.description and callable(c.accessor)


def test_table_csv_pandas_agree(res, tmp_path):
    df = res.to_pandas()
    assert list(df.columns) == [c.name for c in COLUMNS]  # to_pandas: every column
    tab = res.table()
    assert tab.shape == (res.t.size, len(DEFAULT_COLUMNS))
    np.testing.assert_array_equal(tab, df[list(DEFAULT_COLUMNS)].to_numpy())
    res.to_csv(tmp_path / "r.csv")
    head, data = read_csv(tmp_path / "r.csv")
    assert head == list(DEFAULT_COLUMNS)
    np.testing.assert_allclose(data, tab, rtol=1e-8, atol=1e-12)  # 9 significant figures
    # the same subset through columns= in all three
    cols = ["t_s", "e_mm", "omega_rad_s", "y_mm"]
    res.to_csv(tmp_path / "s.csv", columns=cols)
    head, data = read_csv(tmp_path / "s.csv")
    assert head == cols
    np.testing.assert_array_equal(res.table(cols), res.to_pandas(cols).to_numpy())
    np.testing.assert_allclose(data, res.table(cols), rtol=1e-8, atol=1e-12)


def test_columns_are_the_documented_quantities(res):
    df = res.to_pandas()
    np.testing.assert_array_equal(df["t_s"], res.t)
    np.testing.assert_array_equal(df["x_mm"], res.x * 1e3)
    np.testing.assert_array_equal(df["theta_deg"], np.degrees(res.theta))
    np.testing.assert_array_equal(df["p_bar"], res.p * 1e-5)
    np.testing.assert_array_equal(df["xdot_mm_s"], res.xdot * 1e3)


def test_unknown_column_is_an_error(res, tmp_path):
    with pytest.raises(HydroarmError, match="columns"):
        res.table(["t_s", "nope"])
    with pytest.raises(HydroarmError, match="columns"):
        res.to_csv(tmp_path / "x.csv", columns=[])
    assert not (tmp_path / "x.csv").exists()


def _check_plain(m):
    for k, v in m.items():
        if isinstance(v, tuple):
            _check_plain(dict(enumerate(v)))
        elif v is not None:
            assert type(v) in (float, int, bool), (k, type(v))


def test_metrics_are_plain_python_numbers(res):
    m = res.metrics()
    assert type(m["saturation_velocity_m_s"]) is float
    assert type(m["time_constant_start_s"]) is float and type(m["travel_m"]) is float
    assert type(m["direction"]) is int and type(m["stalled"]) is bool
    _check_plain(m)


def test_arm_result_columns_agree(arm_res, tmp_path):
    df = arm_res.to_pandas()
    spec = arm_res.column_spec()
    assert list(df.columns) == list(spec)
    for n in arm_res.names:
        for suffix in ("deg", "rate_deg_s", "pressure_bar", "lever_mm"):
            assert f"{n}_{suffix}" in spec and spec[f"{n}_{suffix}"].unit
    np.testing.assert_array_equal(arm_res.table(), df.to_numpy())
    arm_res.to_csv(tmp_path / "j.csv", tmp_path / "h.csv")
    head, data = read_csv(tmp_path / "j.csv")
    assert head == list(spec)
    np.testing.assert_allclose(data, arm_res.table(), rtol=1e-5, atol=1e-9)  # 6 s.f.
    head, data = read_csv(tmp_path / "h.csv")
    assert head[0] == "t_s" and head[-1] == "hand_z_m" and len(head) == 10
    np.testing.assert_allclose(data[:, 7:], arm_res.points()[:, 2, :], rtol=1e-5, atol=1e-9)
    n = arm_res.names[0]
    np.testing.assert_array_equal(df[f"{n}_deg"], np.degrees(arm_res.angle(n)))
    cols = ["t_s", f"{n}_pressure_bar"]
    np.testing.assert_array_equal(arm_res.to_pandas(cols).to_numpy(), arm_res.table(cols))


def test_arm_joint_metrics_are_plain(arm_res):
    moving = [n for n in arm_res.names if np.ptp(arm_res.angle(n)) > math.radians(5)]
    assert moving
    m = arm_res.joint_metrics(moving[0])
    assert type(m["saturation_velocity_rad_s"]) is float
    _check_plain(m)


def test_arm_result_plot_returns_a_figure(arm_res):
    figure = pytest.importorskip("matplotlib.figure").Figure
    plt = pytest.importorskip("matplotlib.pyplot")
    fig = arm_res.plot()
    assert isinstance(fig, figure) and fig.axes
    assert isinstance(arm_res.plot("frames", n=4), figure)
    with pytest.raises(HydroarmError, match="kind"):
        arm_res.plot("nope")
    plt.close("all")


def test_no_backend_is_selected_by_the_package():
    pkg = Path(ha.__file__).parent
    for path in pkg.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "matplotlib.use(" not in text and "mpl.use(" not in text, path
