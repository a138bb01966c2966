"""Sweeps and tolerance studies of servos built from components (docs/batch.md "Component
servos"): ``hydroarm sweep --config study.toml --out results.csv`` where ``[scenario]``
holds a component servo file's sections (it has ``[scenario.actuator]``).

.. code-block:: toml

    [scenario.actuator]      # … the sections of a component servo file (docs/components.md)
    [scenario.valve]
    …
    [grid]                   # servo parameters by their names (hydroarm.core.servo), units
    mass = ["50 kg", "100 kg", "200 kg"]
    [monte_carlo]
    n = 300
    seed = 1
    overlap = { distribution = "normal", relative_sd = 0.1 }      # the four lap_*
    bulk_modulus = { distribution = "uniform", relative = 0.2 }
    [metrics]
    settling_band = 0.02     # settling time: within ±2 % of the last step's size

The names and their dimensions are `hydroarm.io.components.SWEEP_PARAMETERS` plus the
convenience names of `SWEEP_ALIASES` (``overlap``,
``piston_area``, ``dead_volume``, ``external_leakage``, ``flow_coefficient``). The grid and
the draws are those of the joint's sweeps (`hydroarm.batch.rows.varied_rows`); the
chunks, ``--resume``, the Dask executor and the output file are its machinery too
(`hydroarm.batch.sweep.run_sweep`). A chunk's rows run on
`hydroarm.model.servo_observers.servo_metrics_many`: the servo's circuit observed on the system
kernel (`hydroarm.integrators.observers.observe_many`, the rows sharing one net together);
a row's metrics are those of the same servo run alone
([`metrics`][hydroarm.ServoResult.metrics]), bit for bit.
"""

from __future__ import annotations

import array
import csv
import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from ..core.servo import (
    LOAD_CRANK,
    LOAD_MASS,
    P_P_SUPPLY,
    P_P_TANK,
    PARAMETER_INDEX,
    S_PA,
    S_PB,
    S_PS,
    SUPPLY_FIXED,
    default_parameters,
)
from ..errors import HydroarmError
from ..integrators import registry
from ..io.components import (
    check_sweep_name,
    servo_from_doc,
    sweep_dimension,
    sweep_names,
    sweep_rule,
    sweep_targets,
    sweep_value,
)
from ..io.sections import (
    as_table,
    number_or_quantity,
    optional_table,
    reject_unknown_keys,
    within,
)
from ..io.units import si_suffix
from ..metrics.servo import DEFAULT_BAND, metric_columns
from ..model.servo import ServoScenario
from ..model.servo_observers import servo_metrics_many
from .rows import varied_rows

GOVERNING_ROWS = 10  # rows (besides the base) whose step is checked: the extremes
METRICS_KEYS = {"settling_band"}


@dataclass
class ServoSweep:
    """A parsed servo sweep: the base servo and one parameter vector per scenario."""

    base: ServoScenario
    names: list  # varied names as written (convenience names included)
    values: np.ndarray  # (n, len(names)) SI values
    table: np.ndarray  # (n, N_PARAMETERS) the kernel's parameter vectors
    initial: np.ndarray  # (n, N_STATES) initial states
    band: float  # settling band, a fraction of the step's size
    digest: str  # identifies the sweep (for --resume)

    @property
    def size(self) -> int:
        return self.table.shape[0]

    def scenario(self, row: int) -> ServoScenario:
        """Row ``row`` as a single [`ServoScenario`][hydroarm.ServoScenario] (for checks and
        re-runs)."""
        params = dict(self.base.parameters)
        for i, k in enumerate(self.names):
            for target in sweep_targets(k):
                params[target] = float(self.values[row, i])
        return self.base.replace(parameters=params)

    def jobs(self):
        """``job(rows)`` -> (function, arguments): the metrics of a slice of rows."""

        def job(s: slice):
            return run_servo_chunk, (self, s.start, min(s.stop, self.size))

        return job

    def columns(self, metrics: np.ndarray) -> dict:
        """scenario, the varied names (SI, the unit in each name: ``mass_kg``), then the
        metrics (`metric_columns`)."""
        cols: dict = {"scenario": np.arange(self.size)}
        for i, k in enumerate(self.names):
            suffix = si_suffix(sweep_dimension(k, self.base.parameters))
            cols[f"{k}_{suffix}" if suffix else k] = self.values[:, i]
        cols.update(metric_columns(metrics, self.base_linear))
        return cols

    @property
    def base_linear(self) -> bool:
        return self.base.parameters.get("load_kind", LOAD_MASS) == LOAD_MASS


def run_servo_chunk(sweep: ServoSweep, start: int, stop: int, threads=None) -> np.ndarray:
    """Metrics of the rows ``start`` … ``stop - 1`` of a servo sweep
    (`servo_metrics_many`); ``threads`` limits numba's threads (1 inside a Dask worker)."""
    if threads is not None:
        most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
        numba.set_num_threads(max(1, min(threads, most)))
    rows = [sweep.scenario(i) for i in range(start, stop)]
    return servo_metrics_many(rows, sweep.band)


def _base_value(field: str, name: str, parameters: dict) -> float:
    """The base servo's value of a sweep name (a convenience name's entries must agree)."""
    vals = {parameters.get(t, _default(t)) for t in sweep_targets(name)}
    if len(vals) != 1:
        raise HydroarmError(
            field,
            f"sets {', '.join(sweep_targets(name))}, which differ in the base servo: "
            "vary them by name",
        )
    return float(vals.pop())


def _default(name: str) -> float:
    return float(default_parameters()[PARAMETER_INDEX[name]])


@dataclass
class _Changed:
    """One set of parameter changes as the rows of a sweep (`check_servo_changes`)."""

    names: list
    values: np.ndarray  # (1, len(names))

    def field(self, name: str) -> str:
        return name


def check_servo_changes(base: ServoScenario, changes: dict) -> None:
    """Refuse parameter changes of a servo (sweep names, SI values) with the rules of a
    sweep's rows (sign rules, the component readers' cross rules), naming the parameter:
    ``mass: must be positive, got -1``. The FMU's parameters (`hydroarm.fmu`)."""
    if not changes:
        return
    names = list(changes)
    values = np.array([[float(changes[k]) for k in names]])
    params = dict(base.parameters)
    for k in names:
        for target in sweep_targets(k):
            params[target] = float(changes[k])
    table = base.replace(parameters=params).vector()[None, :]
    _check_values(_Changed(names, values), table, base, rows=False)


def _check_values(v, table: np.ndarray, base: ServoScenario, rows: bool = True) -> None:
    """Every row, draws included, checked vectorised: sign rules and the cross rules of the
    component readers (first bad row named: ``monte_carlo.mass: row 17: ...``; ``rows``
    false: no row named)."""

    def at(row: int) -> str:
        return f"row {row}: " if rows else ""

    for i, k in enumerate(v.names):
        vals = v.values[:, i]
        rule = sweep_rule(k)
        bad = ~np.isfinite(vals)
        if rule == "positive":
            bad |= ~(vals > 0.0)
            words = "must be positive"
        elif rule == "nonnegative":
            bad |= ~(vals >= 0.0)
            words = "must not be negative"
        else:
            words = "must be finite"
        if np.any(bad):
            row = int(np.argmax(bad))
            raise HydroarmError(v.field(k), f"{at(row)}{words}, got {vals[row]:.6g}")

    def col(name):
        return table[:, PARAMETER_INDEX[name]]

    def refuse(names, bad, words):
        row = int(np.argmax(bad))
        varied = [k for k in v.names if set(sweep_targets(k)) & set(names)]
        field = v.field(varied[0]) if varied else "scenario"
        raise HydroarmError(field, f"{at(row)}{words}")

    varied = {t for k in v.names for t in sweep_targets(k)}
    rules = [
        (("stroke_min", "stroke_max"), col("stroke_max") > col("stroke_min"),
         "stroke_max must be above stroke_min"),
        (("position_min", "position_max"), col("position_max") > col("position_min"),
         "position_max must be above position_min"),
        (("output_min", "output_max"), col("output_max") > col("output_min"),
         "output_max must be above output_min"),
        (("air_fraction",), col("air_fraction") < 1.0, "air_fraction must be below 1"),
        (("gearbox_loss_at_stall",), col("gearbox_loss_at_stall") < 1.0,
         "gearbox_loss_at_stall must be below 1"),
    ]  # fmt: skip
    if base.parameters.get("supply_kind") == SUPPLY_FIXED:
        rules.append(
            (("supply_pressure", "tank_pressure"), col("supply_pressure") > col("tank_pressure"),
             "the supply pressure must be above the tank pressure (absolute)")
        )  # fmt: skip
    if base.parameters.get("load_kind") != LOAD_CRANK:  # the stops of a load driven directly
        lo = np.maximum(col("position_min"), col("stroke_min"))
        hi = np.minimum(col("position_max"), col("stroke_max"))
    else:
        lo, hi = col("position_min"), col("position_max")
    q0 = base.initial.get("position", 0.0)
    rules.append(
        (("stroke_min", "stroke_max", "position_min", "position_max"), (lo <= q0) & (q0 <= hi),
         "the initial position is outside the stroke and end stops")
    )  # fmt: skip
    for names, ok, words in rules:
        if varied & set(names) and not np.all(ok):
            refuse(names, ~ok, words)


def _initial_states(base: ServoScenario, table: np.ndarray, varied: set) -> np.ndarray:
    """Each row's initial state as
    [`ServoScenario.initial_state`][hydroarm.ServoScenario.initial_state] builds it: chamber
    pressures at the row's tank pressure, the supply at its ``supply_pressure`` (unless the base
    gives them)."""
    s0 = base.initial_state()
    S0 = np.repeat(s0[None, :], table.shape[0], axis=0)
    if "tank_pressure" in varied:
        for k, i in (("pressure_a", S_PA), ("pressure_b", S_PB)):
            if k not in base.initial:
                S0[:, i] = table[:, P_P_TANK]
        if "supply_pressure" not in base.parameters and "supply_pressure" not in varied:
            S0[:, S_PS] = table[:, P_P_TANK]
    if "supply_pressure" in varied:
        S0[:, S_PS] = table[:, P_P_SUPPLY]
    return S0


def _check_step(base: ServoScenario, sw_names, values, table, initial) -> None:
    """The base's step check ([`ServoScenario.check_step`][hydroarm.ServoScenario.check_step]), then
    the same check for the rows at the extremes of each varied value (at most ``GOVERNING_ROWS``): a
    screen, not a proof (a row outside them that is unstable reports ``failed``)."""
    with within("scenario"):
        base.check_step()
    if not sw_names or table.shape[0] == 0:
        return
    rows: list[int] = []
    for i in range(values.shape[1]):
        for r in (int(np.argmin(values[:, i])), int(np.argmax(values[:, i]))):
            if r not in rows:
                rows.append(r)
    m = base.method
    for r in rows[:GOVERNING_ROWS]:
        params = dict(base.parameters)
        for i, k in enumerate(sw_names):
            for target in sweep_targets(k):
                params[target] = float(values[r, i])
        with within("scenario"):  # the row's circuit (`ServoScenario.step_limit`)
            limit = base.replace(parameters=params).step_limit()
        if limit is None:
            continue
        shown = ", ".join(f"{k} = {values[r, i]:.4g}" for i, k in enumerate(sw_names))
        raise HydroarmError(
            "scenario.solver.step",
            f"{base.step:.3g} s is above the stable limit {limit:.3g} s of '{m}' for row {r} "
            f"({shown}); use a smaller step",
        )


def parse_servo_sweep(doc: dict, sc_doc: dict, base_dir: Path, source: str) -> ServoSweep:
    """A `ServoSweep` from a parsed sweep file whose ``[scenario]`` is a servo built
    from components (module doc)."""
    with within("scenario"):
        base = servo_from_doc(sc_doc, base_dir, source)
        if not registry.method(base.method).fixed_step:
            raise HydroarmError(
                "solver.method", f"a sweep runs {' or '.join(registry.fixed_step_methods())}"
            )
    band = DEFAULT_BAND
    if "metrics" in doc:
        mt = as_table("metrics", doc["metrics"])
        reject_unknown_keys("metrics", mt, METRICS_KEYS)
        if "settling_band" in mt:
            band = number_or_quantity(
                "metrics.settling_band", mt["settling_band"], "dimensionless", positive=True
            )
    params = base.parameters
    grid = optional_table(doc, "grid")
    mc = dict(optional_table(doc, "monte_carlo"))
    known = sweep_names()
    for sec, section in (("grid", grid), ("monte_carlo", mc)):
        for k in section:
            if k in known:
                check_sweep_name(f"{sec}.{k}", k, params)

    def read(k):
        return lambda field, value: sweep_value(field, k, value, params)

    v = varied_rows(
        grid,
        mc,
        known,
        "servo sweep parameter",
        read=read,
        dimension=lambda k: sweep_dimension(k, params),
        base_value=lambda k: _base_value(f"monte_carlo.{k}", k, params),
    )
    n = v.values.shape[0]
    table = np.repeat(base.vector()[None, :], n, axis=0)
    varied: set = set()
    for i, k in enumerate(v.names):
        for target in sweep_targets(k):
            table[:, PARAMETER_INDEX[target]] = v.values[:, i]
            varied.add(target)
    _check_values(v, table, base)
    initial = _initial_states(base, table, varied)
    _check_step(base, v.names, v.values, table, initial)
    h = hashlib.sha256()
    h.update(json.dumps(doc, sort_keys=True, default=str).encode())
    h.update(table.tobytes())
    h.update(initial.tobytes())
    return ServoSweep(
        base=base,
        names=v.names,
        values=v.values,
        table=table,
        initial=initial,
        band=band,
        digest=h.hexdigest()[:16],
    )


def servo_summary(path) -> dict:
    """Quick statistics of a finished servo sweep file (for the CLI): rows, failed rows,
    rows that settled, and the mean and spread of the settling time and the peak chamber
    pressure over the rows that did not fail."""
    path = Path(path)
    names = ("settling_time_s", "peak_pressure_bar")
    if path.suffix.lower() == ".csv":
        vals = {k: array.array("d") for k in names}
        failed = 0
        with open(path, newline="") as f:
            rows = csv.reader(f)
            header = next(rows)
            idx = {k: header.index(k) for k in names}
            i_f = header.index("failed")
            for row in rows:
                bad = row[i_f] == "True"
                failed += bad
                for k in names:
                    x = row[idx[k]]
                    vals[k].append(float(x) if x and not bad else math.nan)
        cols = {k: np.frombuffer(vals[k], dtype=float) for k in names}
    else:
        import pandas as pd

        df = pd.read_parquet(path)
        bad_rows = df["failed"].to_numpy(bool)
        failed = int(bad_rows.sum())
        cols = {k: np.where(bad_rows, math.nan, df[k].to_numpy(float)) for k in names}
    n = len(cols[names[0]])
    out: dict = {"scenarios": n, "failed": failed}
    for k in names:
        x = cols[k][np.isfinite(cols[k])]
        out[f"{k}_rows"] = len(x)
        out[f"{k}_mean"] = float(np.mean(x)) if len(x) else math.nan
        out[f"{k}_sd"] = float(np.std(x, ddof=1)) if len(x) > 1 else math.nan
    return out
