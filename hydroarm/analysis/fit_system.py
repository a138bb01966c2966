"""Fit any system named by file (issue 29; docs/fit.md "Any system").

A fit file names its system as design and evaluate do, ``[system] file = "rig.toml"``
(`hydroarm.io.system.system_of`: a circuit, a mechanism or a component servo; fields
beside ``file`` override the file's), the parameters by the names a study gives them
(``orifice.area``, ``feedback.proportional_gain``), and its traces by the system's named
outputs, the columns ``hydroarm simulate --out`` writes::

    [[trace]]
    csv = "measured.csv"
    columns = { t = ["time", "ms"], supply_pressure_bar = ["p", "psi"] }

Each measured column is converted once, here, into its output's unit (bar for a pressure,
L/min for a flow, degrees for an angle …). The runs of an evaluation (every point of a
Jacobian) go together through the system's batch engine
(`columns_many`, the path a design's
candidates take; each row the ``simulate`` run of that system), cut after the last sample;
the outputs are interpolated linearly at the measured times. This module reads the file's
system and traces, samples the model, and writes ``fitted.toml``; the fit itself is
`hydroarm.analysis.fit.run_fit`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import HydroarmError
from ..files import checked_path
from ..io.circuit import SYSTEM_REFERENCE_KEYS
from ..io.sections import (
    as_table,
    read_csv_columns,
    reject_unknown_keys,
    require_keys,
    require_table,
    text_value,
    time_value,
    unknown_name,
)
from ..io.servo_circuit import circuit_toml
from ..io.system import servo_with
from ..io.units import value_in
from ..model.circuit import Circuit
from ..model.servo import ServoScenario
from .systems import SystemRunner, study_system

SYSTEM_TRACE_KEYS = {"csv", "columns", "window", "weight", "delay", "name"}
MIN_SAMPLES = 3
# points of one measured trace: its residuals and Jacobian rows (points × parameters × 8 B:
# 10⁶ × 32 × 8 B = 256 MB), beyond any logger's record of one test
MAX_TRACE_POINTS = 10**6


@dataclass(frozen=True)
class SystemSource:
    """The system of a fit: ``runner`` (the system the fit runs, its duration cut after the
    last measured sample), ``system`` (as the fit file names it, its whole duration: what
    ``fitted.toml`` holds), ``path`` (the system file) and ``table`` (the fit file's
    ``[system]`` table)."""

    runner: SystemRunner
    system: Circuit | ServoScenario
    path: Path
    table: dict

    def with_values(self, values: dict[str, float]) -> Circuit | ServoScenario:
        """The system (whole duration) with fitted values (internal names, SI)."""
        if isinstance(self.system, Circuit):
            return self.system.with_values(values)
        return servo_with(self.system, values)


@dataclass(frozen=True)
class SystemTrace:
    """One measured run of a system: times ``t`` [s] and, per named output, its measured
    values in that output's unit (``units``: pint's syntax, as ``simulate --out`` writes
    the output)."""

    t: np.ndarray
    outputs: tuple[str, ...]
    values: tuple[np.ndarray, ...]
    units: tuple[str, ...]
    weight: float = 1.0
    name: str = "trace"
    delay: float | None = None
    fit_delay: bool = False
    group: str = ""

    def blocks(self) -> list[tuple[str, np.ndarray, float]]:
        """The measured columns fitted: (output, values, residual scale = their range)."""
        return [
            (o, v, max(float(np.ptp(v)), 1e-12))
            for o, v in zip(self.outputs, self.values, strict=True)
        ]


def check_trace(section: str, name: str, t: np.ndarray, delay: float | None) -> None:
    """A trace's size budget (`MAX_TRACE_POINTS`, naming ``<section>.csv``) and its
    fixed delay: a delay as long as the trace's time span leaves nothing of the model's
    response to compare (the fit would report its start unmoved, with an infinite error)."""
    if len(t) > MAX_TRACE_POINTS:
        raise HydroarmError(
            f"{section}.csv",
            f"{name}: {len(t)} samples are above the budget of {MAX_TRACE_POINTS} (a trace's "
            "residuals and Jacobian rows); keep every k-th row or give a window",
        )
    span = float(t[-1] - t[0])
    if delay is not None and abs(delay) >= span:
        raise HydroarmError(
            f"{section}.delay",
            f"{delay:g} s is not shorter than the trace ({name} spans {span:g} s): "
            "nothing of the response would be compared",
        )


def read_system(doc: dict, base_dir: Path) -> SystemSource:
    """The ``[system]`` of a fit file (every check of `system_of`)."""
    table = dict(require_table(doc, "system"))
    system, runner = study_system(doc, base_dir)
    path = checked_path("system.file", (base_dir / str(table["file"])).expanduser())
    return SystemSource(runner, system, path, table)


def cut_to(source: SystemSource, traces) -> SystemSource:
    """The source whose runner stops one record after the last measured sample (the same
    steps: a fixed-step run's start does not depend on its length); a sample beyond the
    system's run is refused."""
    s = source.system
    last = max(float(tr.t[-1]) for tr in traces)
    if last > s.duration * (1 + 1e-9):
        i = max(range(len(traces)), key=lambda k: float(traces[k].t[-1]))
        raise HydroarmError(
            f"trace[{i + 1}].csv",
            f"samples up to {last:.6g} s, beyond the system's run of {s.duration:.6g} s "
            "(give a longer system.duration)",
        )
    every = s.step * s.record_every
    duration = min(s.duration, (math.ceil(max(last, 0.0) / every) + 1) * every)
    return SystemSource(SystemRunner(s.replace(duration=duration)), s, source.path, source.table)


def column_spec(field: str, value) -> tuple[str, str]:
    """``"name_unit"`` (the unit after the last ``_``: ``p_bar``) or ``["name", "unit"]`` ->
    (column, unit): a measured trace's column, for every kind of fit."""
    if isinstance(value, list):
        if len(value) != 2 or not all(isinstance(v, str) and v.strip() for v in value):
            raise HydroarmError(field, 'must be a column name or [column, unit], e.g. ["t", "ms"]')
        return value[0].strip(), value[1].strip()
    col = text_value(field, value)
    if "_" not in col:
        raise HydroarmError(
            field,
            f'{col!r} carries no unit in its name: give [{col!r}, unit], e.g. [{col!r}, "bar"]',
        )
    return col, col.rsplit("_", 1)[1]


def read_system_trace(
    section: str, table: dict, base_dir: Path, runner: SystemRunner, delay_reader
) -> SystemTrace:
    """A ``[[trace]]`` of a system: ``csv``, ``columns`` (``t`` and at least one of the
    system's outputs, each mapped to a CSV column with its unit), ``window``, ``weight``,
    ``delay``, ``name`` (module doc). ``delay_reader(section, table)`` -> (delay, fit)."""
    reject_unknown_keys(section, table, SYSTEM_TRACE_KEYS)
    require_keys(section, table, ("csv",))
    field_csv = f"{section}.csv"
    f_cols = f"{section}.columns"
    if "columns" not in table:
        raise HydroarmError(
            f_cols,
            "is missing: map the outputs to fit to CSV columns, e.g. columns = "
            '{ t = "t_s", supply_pressure_bar = ["p", "psi"] }',
        )
    mapping = as_table(f_cols, table["columns"])
    known = runner.display_units
    for k in mapping:
        if k != "t" and k not in known:
            raise unknown_name(f_cols, f"output of {runner.name!r}", k, ("t", *known))
    outputs = tuple(k for k in mapping if k not in ("t", "t_s"))
    if not outputs:
        raise HydroarmError(f_cols, "names no output to fit (give at least one)")
    specs = {k: column_spec(f"{f_cols}.{k}", v) for k, v in mapping.items()}
    specs.setdefault("t", ("t_s", "s"))
    path = checked_path(field_csv, text_value(field_csv, table["csv"]), base_dir)
    if not path.is_file():
        raise HydroarmError(field_csv, f"{path.name}: no such file")
    header = read_csv_columns(field_csv, path)
    data = {}
    for k, (col, unit) in specs.items():
        if col not in header:
            raise HydroarmError(
                field_csv,
                f"{path.name} has no column {col!r} for {k} (columns: {', '.join(header)})",
            )
        target = "s" if k == "t" else known[k]
        f = f"{f_cols}.{k}"
        factor = value_in(f, f"1 {unit}", target) if target else _plain(f, unit)
        data[k] = header[col] * factor  # the output's own unit, once, here
        if not np.all(np.isfinite(data[k])):
            raise HydroarmError(field_csv, f"{path.name}: {col} values must be finite")
    t = data["t"]
    if np.any(np.diff(t) <= 0):
        raise HydroarmError(field_csv, f"{path.name}: times must be finite and increasing")
    keep = np.ones(len(t), bool)
    if "window" in table:
        w = table["window"]
        if not isinstance(w, list) or len(w) != 2:
            raise HydroarmError(f"{section}.window", 'must be [start, end], e.g. ["0 s", "1 s"]')
        a, b = (time_value(f"{section}.window", x) for x in w)
        if not a < b:
            raise HydroarmError(f"{section}.window", "start must be before end")
        keep = (t >= a) & (t <= b)
    if keep.sum() < MIN_SAMPLES:
        raise HydroarmError(
            field_csv, f"{path.name}: fewer than {MIN_SAMPLES} samples (in the window)"
        )
    if t[keep][0] < 0:
        raise HydroarmError(field_csv, f"{path.name}: times before 0 s (the run starts at 0 s)")
    values = tuple(data[o][keep] for o in outputs)
    for o, v in zip(outputs, values, strict=True):
        if np.ptp(v) == 0:
            raise HydroarmError(field_csv, f"{path.name}: {specs[o][0]} does not change")
    weight = table.get("weight", 1.0)
    if isinstance(weight, bool) or not isinstance(weight, int | float) or not weight > 0:
        raise HydroarmError(f"{section}.weight", f"must be a positive number, got {weight!r}")
    if not math.isfinite(weight):
        raise HydroarmError(f"{section}.weight", "must be finite")
    delay, fit_delay = delay_reader(section, table)
    check_trace(section, path.name, t[keep], delay)
    name = text_value(f"{section}.name", table.get("name", path.stem))
    return SystemTrace(
        t=t[keep],
        outputs=outputs,
        values=values,
        units=tuple(known[o] for o in outputs),
        weight=float(weight),
        name=name,
        delay=delay,
        fit_delay=fit_delay,
        group=name,
    )


def _plain(field: str, unit: str) -> float:
    """A signal's column (no unit of its own): only a plain number (``"1"``) is accepted."""
    if unit not in ("1", ""):
        raise HydroarmError(field, f"{unit!r}: this output is a signal, give its unit as '1'")
    return 1.0


def system_samples(
    runner: SystemRunner, keys, X: np.ndarray, traces, delays: np.ndarray, *, strict: bool
) -> list[list[np.ndarray]]:
    """The outputs of every trace at its times less its delay, for each row of values ``X``
    (SI, ``keys``' order), all rows run together on the system's batch engine:
    ``[row][trace] -> (len(t), outputs)``; a failed run raises (``strict``) or gets NaN."""
    X = np.atleast_2d(np.asarray(X, float))
    cols = runner.columns_many(list(keys), X)
    out = []
    for row, c in enumerate(cols):
        if c is None:
            if strict:
                raise HydroarmError(
                    "system",
                    f"the run of {runner.name!r} fails at "
                    + ", ".join(f"{k} = {v:.6g}" for k, v in zip(keys, X[row], strict=True))
                    + " (it leaves finite numbers, or its step is above the stable limit)",
                )
            out.append([np.full((len(tr.t), len(tr.outputs)), np.nan) for tr in traces])
            continue
        per = []
        for tr, d in zip(traces, delays[row], strict=True):
            q = tr.t - d
            per.append(np.column_stack([np.interp(q, c["t_s"], c[o]) for o in tr.outputs]))
        out.append(per)
    return out


def default_bounds(runner: SystemRunner, key: str, start: float) -> tuple[float, float]:
    """A parameter's bounds when the fit file gives none: its rule's."""
    rule = runner.rule(key)
    if rule == "positive":
        return (abs(start) * 1e-3 if start else 1e-12, math.inf)
    if rule == "nonnegative":
        return (0.0, math.inf)
    if rule.startswith("in ["):
        lo, hi = (float(v) for v in rule[4:].rstrip("]").split(","))
        return (lo, hi)
    return (-math.inf, math.inf)


def _toml_value(value: float, unit: str) -> str:
    return f'"{float(value)!r} {unit}"' if unit not in ("", "1") else repr(float(value))


def fitted_system_toml(
    source: SystemSource, values: dict[str, float], units: dict[str, str], header: str, out: Path
) -> str:
    """``fitted.toml``, a system file that loads back: a circuit written whole with the
    fitted values (`circuit_toml`); a mechanism or a
    component servo as a reference file, ``[system] file`` naming the fit's system file
    (relative to ``out``) with the fit file's overrides and the fitted values beside it
    (read by every study's ``[system] file``, `hydroarm.io.system.system_of`)."""
    fitted = source.with_values(values)
    if isinstance(fitted, Circuit) and fitted.mechanism is None:
        return circuit_toml(fitted, header)
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    lines += [
        "# a reference file: the system file below with the fitted values; name it in a study",
        '# as [system] file = "fitted.toml"',
        "[system]",
        f'file = "{Path(os.path.relpath(source.path, out.resolve())).as_posix()}"',
    ]
    for k, v in source.table.items():
        if k == "file" or k in values:
            continue
        if k in SYSTEM_REFERENCE_KEYS or not _is_fitted_alias(source, k, values):
            lines.append(f"{_key(k)} = {_raw(v)}")
    for k, v in values.items():
        lines.append(f"{_key(k)} = {_toml_value(v, units[k])}")
    return "\n".join(lines) + "\n"


def _is_fitted_alias(source: SystemSource, k: str, values) -> bool:
    """Whether an override of the fit file sets a parameter that was fitted (under another
    spelling, ``feedback.proportional_gain`` for ``proportional_gain``)."""
    try:
        return source.runner.key(k, k) in values
    except HydroarmError:
        return False


def _key(k: str) -> str:
    return k if k.replace("_", "").isalnum() else f'"{k}"'


def _raw(v) -> str:
    """A TOML value as the fit file gave it (a string, a number, a boolean)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(v)
