"""Sweep and sensitivity results as xarray datasets (NetCDF) and MATLAB files (issue 33):
``--export netcdf`` / ``--export mat`` write the same rows as the CSV, at full precision.

"Exactly" below: a value read back from the NetCDF or .mat file, formatted as the CSV
writer formats it (10 significant digits for a sweep, 9 for samples.csv, 6 for the index
table), is the CSV's text character for character; NetCDF and .mat hold the same doubles
bit for bit."""

import csv
import sys

import numpy as np
import pytest

from hydroarm.analysis.sensitivity import _num
from hydroarm.batch.sweep import _csv_field
from hydroarm.batch.tables import SweepTable, mat_name
from hydroarm.cli import main

xr = pytest.importorskip("xarray")
loadmat = pytest.importorskip("scipy.io").loadmat

# four rows; the smallest leakage leaves the oil column undamped: those runs fail (the CSV
# then has a text column, ``failure``)
SWEEP = """
[scenario.joint]
parameter_set = "paper-calibrated"
[scenario.load]
builtin = 6
[scenario.input]
direction = "raise"
[scenario.solver]
duration = "1 s"
[grid]
weight = ["15 N", "25 N"]
leakage_coefficient = ["0.5e-13 m**3/s/Pa", "4.878e-13 m**3/s/Pa"]
"""

SENSITIVITY = """
load = 6
direction = "raise"
[joint]
parameter_set = "paper-calibrated"
[sensitivity]
method = "morris"
samples = 3
seed = 2
[sensitivity.parameters]
flow_coefficient = { distribution = "uniform", relative = 0.1 }
leakage_coefficient = { distribution = "uniform", relative = 0.1 }
[sensitivity.solver]
duration = "0.5 s"
"""


def _csv_columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {k: [r[i] for r in rows[1:]] for i, k in enumerate(rows[0])}


def _mat(path):
    m = loadmat(path)
    return {k: v for k, v in m.items() if not k.startswith("__")}


def _mat_text(cells) -> list[str]:
    """A cell array of strings as loadmat reads it back (an empty string: an empty cell)."""
    return [str(c[0]) if c.size else "" for c in np.asarray(cells).ravel()]


def test_sweep_rows_round_trip_through_netcdf_and_mat(tmp_path, capsys):
    cfg = tmp_path / "s.toml"
    cfg.write_text(SWEEP)
    out = tmp_path / "r.csv"
    args = ["sweep", "--config", str(cfg), "--out", str(out)]
    assert main([*args, "--export", "netcdf", "--export", "mat"]) == 0
    assert f"also written to {tmp_path / 'r.nc'}" in capsys.readouterr().out
    text = _csv_columns(out)
    assert "failure" in text and "True" in text["failed"] and "False" in text["failed"]
    ds = xr.load_dataset(tmp_path / "r.nc")
    mat = _mat(tmp_path / "r.mat")
    assert list(ds.scenario.values) == [int(v) for v in text["scenario"]]
    assert list(ds.data_vars) == [k for k in text if k != "scenario"]
    for k, cells in text.items():
        nc = ds[k].values
        m = mat[mat_name(k)]
        if k == "failure":
            assert list(nc) == cells and _mat_text(m) == cells
            continue
        assert [_csv_field(v) for v in nc.tolist()] == cells, k
        m = m.ravel().astype(nc.dtype)  # a MATLAB logical is read back as uint8
        assert np.array_equal(m, nc, equal_nan=True), k  # the same doubles
    # and the CSV read back holds the NetCDF's values to the CSV's 10 digits
    table = SweepTable.read(out)
    v = ds["saturation_velocity_m_s"].values
    assert np.allclose(table.columns["saturation_velocity_m_s"], v, rtol=1e-9, equal_nan=True)
    assert table.to_xarray()["failed"].dtype == bool


def test_sensitivity_samples_and_indices_round_trip(tmp_path, capsys):
    cfg = tmp_path / "s.toml"
    cfg.write_text(SENSITIVITY)
    out = tmp_path / "o"
    args = ["sensitivity", "--config", str(cfg), "--out", str(out)]
    assert main([*args, "--export", "netcdf", "--export", "mat"]) == 0
    assert "sensitivity.nc, sensitivity.mat)" in capsys.readouterr().out
    ds = xr.load_dataset(out / "sensitivity.nc")
    mat = _mat(out / "sensitivity.mat")
    samples = _csv_columns(out / "samples.csv")
    assert len(samples["run"]) == 3 * 3  # 3 trajectories × (D + 1)
    for k, cells in samples.items():
        if k == "run":
            assert [str(v) for v in ds.run.values] == cells
            continue
        if ds[k].dtype.kind in "UO":  # why a run failed ("" when it did not)
            assert list(ds[k].values) == cells and _mat_text(mat[mat_name(k)]) == cells
            continue
        assert [_num(v) for v in ds[k].values] == cells, k
        assert np.array_equal(mat[mat_name(k)].ravel(), ds[k].values, equal_nan=True)
    with open(out / "morris.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert _mat_text(mat["parameter"]) == list(ds.parameter.values)
    for r in rows:
        at = {"metric": r["metric"], "parameter": r["parameter"]}
        for c in ("mu_star", "mu_star_conf", "sigma"):
            assert f"{float(ds[c].sel(at)):.6g}" == r[c], (r, c)
        i = list(ds.metric.values).index(r["metric"])
        j = list(ds.parameter.values).index(r["parameter"])
        assert np.array_equal(mat["mu_star"][i, j], ds["mu_star"].values[i, j])
    assert ds.attrs["method"] == "morris"


def test_netcdf_without_xarray_is_one_line(tmp_path, capsys, monkeypatch):
    cfg = tmp_path / "s.toml"
    cfg.write_text(SWEEP)
    monkeypatch.setitem(sys.modules, "xarray", None)  # import xarray: ImportError
    out = tmp_path / "r.csv"
    args = ["sweep", "--config", str(cfg), "--out", str(out), "--export", "netcdf"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    need = "netcdf needs xarray (pip install 'hydroarm[xarray]')"
    assert err == [f"hydroarm: error: --export: {need}"]
    assert not out.exists()  # refused before any work
    # .mat needs scipy only
    assert main([*args[:-1], "mat"]) == 0
    assert (tmp_path / "r.mat").exists() and not (tmp_path / "r.nc").exists()


def test_parquet_rows_and_mat_hold_the_same_doubles(tmp_path):
    pytest.importorskip("pyarrow")
    from hydroarm.batch.sweep import parse_sweep, run_sweep
    from hydroarm.io.sections import parse_toml

    sweep = parse_sweep(parse_toml(SWEEP, "s.toml"))
    out = run_sweep(sweep, tmp_path / "r.parquet", export=("mat",))
    table = SweepTable.read(out)
    mat = _mat(tmp_path / "r.mat")
    assert len(table) == 4
    for k, v in table.columns.items():
        if k == "failure":
            assert _mat_text(mat[k]) == list(v)
            continue
        m = mat[mat_name(k)].ravel().astype(np.asarray(v).dtype)
        assert np.array_equal(m, v, equal_nan=True), k
