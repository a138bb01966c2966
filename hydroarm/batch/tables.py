"""Sweep and sensitivity results as xarray datasets (NetCDF) and MATLAB files (issue 33).

A sweep's rows (`SweepTable`: one value of every column per scenario, the columns of
its CSV, each name with its SI unit) and a sensitivity study's samples and indices
([`hydroarm.analysis.sensitivity.SensitivityResult.to_xarray`][hydroarm.SensitivityResult.to_xarray])
become one `xarray.Dataset` each, written as NetCDF (``.to_netcdf``), and the same arrays as a
MATLAB ``.mat`` file (`scipy.io.savemat`: one variable per column, strings as cell
arrays, true/false as logicals). The values are the run's doubles, not the CSV's 10
significant digits.

xarray is optional (``pip install 'hydroarm[xarray]'``): without it `require_xarray`
refuses with one line; ``.mat`` needs only scipy.
"""

from __future__ import annotations

import contextlib
import csv
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import HydroarmError
from ..files import write_error

#: ``--export`` formats and the suffix of the file each writes
EXPORT_SUFFIXES = {"netcdf": ".nc", "mat": ".mat"}
UNITS_NOTE = "each variable's name ends with its SI unit (docs/model.md 'Units in names')"
_MAT_NAME = re.compile(r"[^A-Za-z0-9_]")
MAT_NAME_LENGTH = 63  # MATLAB's namelengthmax


def require_xarray(field_name: str = "--export"):
    """The xarray module, or one line saying how to install it (xarray and its NetCDF writer,
    h5netcdf on h5py: h5netcdf installs without h5py, and xarray then fails at the write)."""
    try:
        import xarray
    except ImportError:
        raise HydroarmError(
            field_name, "netcdf needs xarray (pip install 'hydroarm[xarray]')"
        ) from None
    for module in ("h5netcdf", "h5py"):
        try:
            __import__(module)
        except ImportError:
            raise HydroarmError(
                field_name, f"netcdf needs {module} (pip install 'hydroarm[xarray]')"
            ) from None
    return xarray


def check_export(formats, field_name: str = "--export") -> tuple[str, ...]:
    """The export formats asked for (``netcdf``, ``mat``), checked before any work."""
    out = tuple(dict.fromkeys(formats or ()))
    for f in out:
        if f not in EXPORT_SUFFIXES:
            raise HydroarmError(field_name, f"must be netcdf or mat, got {f!r}")
    if "netcdf" in out:
        require_xarray(field_name)
    return out


def mat_name(name: str) -> str:
    """A column's name as a MATLAB variable name: letters, digits and ``_``, starting with
    a letter, at most 63 characters (``position.max`` → ``position_max``)."""
    text = _MAT_NAME.sub("_", name)
    if not text[:1].isalpha():
        text = "v_" + text
    return text[:MAT_NAME_LENGTH]


def _replace_into(path: Path, write) -> None:
    """``write(tmp)`` then rename onto ``path``: a reader never sees half a file."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{path.suffix}")
    try:
        write(tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        raise write_error(path, exc) from exc
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def write_mat(path, variables: dict, header: str = "") -> Path:
    """``variables`` (name → array or text) as a MATLAB 5 file: 1-D arrays as columns, text
    arrays as cell arrays, names made valid (`mat_name`; two names that become one
    are refused)."""
    from scipy.io import savemat

    out: dict = {}
    for k, v in variables.items():
        name = mat_name(k)
        if name in out:
            raise HydroarmError("--export", f"mat: {k!r} and another name both become {name!r}")
        a = np.asarray(v)
        out[name] = a.astype(object) if a.dtype.kind in "UO" else a
    if header:
        out["description"] = header
    path = Path(path)
    _replace_into(path, lambda tmp: savemat(tmp, out, oned_as="column", do_compression=True))
    return path


def write_netcdf(path, dataset) -> Path:
    """An xarray dataset written as NetCDF (xarray's default engine), atomically."""
    path = Path(path)
    _replace_into(path, lambda tmp: dataset.to_netcdf(tmp))
    return path


@dataclass
class SweepTable:
    """A finished sweep's rows: ``columns`` (name → one value per scenario: the columns of
    its CSV, SI values, each name with its unit), in the CSV's order."""

    columns: dict
    name: str = "sweep"
    attrs: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    @classmethod
    def read(cls, path) -> SweepTable:
        """A sweep's results file: CSV (each column read back as the sweep wrote it: whole
        numbers, numbers with empty cells as NaN, True/False, text) or Parquet."""
        path = Path(path)
        if path.suffix.lower() == ".parquet":
            import pandas as pd

            df = pd.read_parquet(path)
            return cls({k: df[k].to_numpy() for k in df.columns}, name=path.stem)
        try:
            with open(path, newline="") as f:
                rows = list(csv.reader(f))
        except OSError as exc:
            raise HydroarmError("sweep", f"cannot read {path}: {exc.strerror or exc}") from None
        if not rows:
            raise HydroarmError("sweep", f"{path} is empty")
        header, body = rows[0], rows[1:]
        cols = {k: _column(k, [r[i] for r in body]) for i, k in enumerate(header)}
        return cls(cols, name=path.stem)

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self.columns)

    def to_xarray(self):
        """One dataset along ``scenario`` (the scenario numbers as its coordinate), every
        other column a variable."""
        xr = require_xarray("to_xarray")
        n = len(self)
        index = np.asarray(self.columns.get("scenario", np.arange(n)))
        data = {
            k: ("scenario", _netcdf_values(v)) for k, v in self.columns.items() if k != "scenario"
        }
        attrs = {"title": self.name, "units": UNITS_NOTE, **self.attrs}
        return xr.Dataset(data, coords={"scenario": index}, attrs=attrs)

    def to_netcdf(self, path) -> Path:
        return write_netcdf(path, self.to_xarray())

    def to_mat(self, path) -> Path:
        """One MATLAB variable per column (`write_mat`)."""
        return write_mat(path, self.columns, header=f"{self.name}: {UNITS_NOTE}")

    def export(self, out, formats) -> list[Path]:
        """Write each format of ``formats`` beside ``out`` (``out`` with ``.nc``, ``.mat``)."""
        written = []
        for f in formats:
            path = Path(out).with_suffix(EXPORT_SUFFIXES[f])
            written.append(self.to_netcdf(path) if f == "netcdf" else self.to_mat(path))
        return written


def _netcdf_values(v) -> np.ndarray:
    a = np.asarray(v)
    return a.astype(str) if a.dtype.kind == "O" else a


def _column(name: str, cells: list[str]) -> np.ndarray:
    """A CSV column as the sweep wrote it: the scenario numbers, True/False, numbers (an
    empty cell: NaN), else text."""
    if name == "scenario":
        return np.array([int(c) for c in cells], dtype=np.int64)
    if cells and all(c in ("True", "False") for c in cells):
        return np.array([c == "True" for c in cells])
    try:
        return np.array([float(c) if c else np.nan for c in cells])
    except ValueError:
        return np.array(cells, dtype=object)
