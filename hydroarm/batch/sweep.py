"""Sweeps and tolerance studies: ``hydroarm sweep --config sweep.toml --out results.csv``.

A sweep file names a base scenario (the scenario-file format under ``[scenario]``; its input
must be a step, e.g. ``direction = "raise"``) and the parameters to vary, with units:

.. code-block:: toml

    [scenario.joint]
    parameter_set = "paper-calibrated"
    [scenario.load]
    builtin = 6
    [scenario.input]
    direction = "raise"
    [scenario.solver]
    duration = "1 s"

    [grid]                                   # cartesian product
    weight = ["15 N", "20 N", "25 N"]
    supply_pressure = { start = "25 bar", stop = "40 bar", num = 4 }

    [monte_carlo]                            # n draws per grid point, seeded
    n = 2000
    seed = 1
    flow_coefficient = { distribution = "normal", relative_sd = 0.1 }
    leakage_coefficient = { distribution = "uniform", relative = 0.1 }
    trapped_volume = { distribution = "normal", mean = "2.8 cm**3", sd = "0.2 cm**3" }

    [metrics]                                # optional: thresholds of the metrics
    middle = 0.8                             # (or [scenario.metrics], not both)

The sections are read by the readers of `hydroarm.io.sections`, shared with scenario and
arm files. Every row is validated as a scenario would be: grid points are built as
[`ServoJoint`][hydroarm.ServoJoint]/[`Load`][hydroarm.Load], and all rows,
Monte Carlo draws included, are checked vectorised by the rules of
`hydroarm.model.rules` (the first bad row is reported: ``monte_carlo.weight: row 17:
...``). The fixed step is checked for stability for the base scenario and for the rows that
need the smallest step by `rate_estimate` (a screen,
not a proof that every row is stable).

A ``[scenario]`` that is a servo built from components (it has ``[scenario.actuator]``)
makes a servo sweep (`hydroarm.batch.servo_sweep`), which shares the rows' reading and
drawing (`varied_rows`) and the running machinery below. A file whose ``[system]``
names a circuit file (``[system] file = "circuit.toml"``) makes a sweep of that circuit
(`hydroarm.batch.circuit_sweep`): any declared parameter, any statistic of any named
output.

Draws come from one seeded generator in the calling process, so results do not depend on
the number of threads or workers. The scenarios run in chunks; each finished chunk is kept in
``OUT.parts/`` so that an interrupted sweep resumes (``--resume``) to the same file.
"""

from __future__ import annotations

import array
import contextlib
import csv
import dataclasses
import hashlib
import itertools
import json
import logging
import math
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from numba import njit

from ..core.equations import holding_pressure, jack_position
from ..core.params import (
    J_AREA,
    J_BETA,
    J_CRANK,
    J_E_SAT,
    J_F_COULOMB,
    J_F_STATIC,
    J_FLOW_COEFF,
    J_GB_EXP,
    J_GB_LOSS,
    J_GB_T0,
    J_LEAK,
    J_RATIO,
    J_SUPPLY,
    J_VISCOUS,
    J_VOLUME,
    L_ARM,
    L_INERTIA,
    L_WEIGHT,
    joint_at,
    load_at,
)
from ..errors import HydroarmError, StabilityError
from ..files import (
    Interrupted,
    atomic_write_text,
    check_output_file,
    try_lock,
    unlock,
    write_error,
)
from ..integrators import registry
from ..integrators.stability import rate_estimate, stable_step_limit
from ..io.components import is_component_file
from ..io.progress import Throttle, notebook_bar
from ..io.schema import scenario_from_doc
from ..io.sections import (
    as_table,
    metric_options,
    optional_table,
    read_toml_file,
    reject_unknown_keys,
    whole_number,
    within,
)
from ..io.units import si_suffix
from ..metrics.step import unit_name
from ..model.rules import check_rows
from ..model.scenario import Scenario, format_time
from .circuit_sweep import CircuitSweep, is_circuit_study, parse_circuit_sweep
from .engine import METRICS, failure_reason, run_batch
from .rows import varied_rows
from .servo_sweep import ServoSweep, parse_servo_sweep
from .tables import EXPORT_SUFFIXES, SweepTable, check_export

# sweepable parameter -> (column of the batch table, dimension, must be positive)
PARAMETERS = {
    "piston_area": (J_AREA, "area", True),
    "flow_coefficient": (J_FLOW_COEFF, "flow_coefficient", True),
    "valve_saturation": (J_E_SAT, "length", True),
    "leakage_coefficient": (J_LEAK, "leakage", False),
    "trapped_volume": (J_VOLUME, "volume", True),
    "bulk_modulus": (J_BETA, "pressure", True),
    "supply_pressure": (J_SUPPLY, "pressure", True),
    "crank_radius": (J_CRANK, "length", True),
    "gear_ratio": (J_RATIO, "dimensionless", True),
    "weight": (L_WEIGHT, "force", False),
    "arm": (L_ARM, "length", False),
    "inertia": (L_INERTIA, "inertia", True),
    "coulomb_friction": (J_F_COULOMB, "force", False),
    "static_friction": (J_F_STATIC, "force", False),
    "viscous_friction": (J_VISCOUS, "viscous", False),
    "gearbox_friction_torque": (J_GB_T0, "torque", False),
    "gearbox_loss_at_stall": (J_GB_LOSS, "dimensionless", False),
    "gearbox_loss_exponent": (J_GB_EXP, "dimensionless", False),
}
DEFAULT_CHUNK = 256
SWEEP_SECTIONS = {"name", "description", "scenario", "grid", "monte_carlo", "metrics", "chunk"}
LOAD_FIELDS = ("weight", "arm", "inertia")
GOVERNING_ROWS = 10  # rows whose step stability is checked in full (besides the base)


@dataclass
class Sweep:
    """A parsed sweep: the base scenario and one parameter row per scenario."""

    base: Scenario
    names: list  # varied parameter names
    values: np.ndarray  # (n, len(names)) SI values
    params: np.ndarray  # (n, N_ROW) batch table: one row per scenario (model.joint.pack)
    digest: str  # identifies the sweep (for --resume)

    @property
    def size(self) -> int:
        return self.params.shape[0]

    def jobs(self):
        """``job(rows)`` -> (function, arguments) that computes the metrics of a slice of
        rows: the chunks of `run_sweep` (in this process or on a Dask worker)."""
        b = self.base
        method = registry.method(b.method).code
        th0, p0, y0, y1 = scenario_inputs(self)

        def job(s: slice):
            return run_chunk, (
                method,
                self.params[s],
                th0[s],
                p0[s],
                y0[s],
                y1[s],
                float(b.lever.times[0]),
                b.step,
                b.nsteps,
                b.metric_options,
            )

        return job

    def columns(self, metrics: np.ndarray) -> dict:
        """The results' columns: scenario, varied parameters, metrics."""
        return _columns(self, metrics)


def _check_grid_points(base, gnames, glists, combos, n_mc) -> None:
    """Build each grid point's joint and load: ServoJoint's and Load's own validation.

    Joints are built once per combination of the joint fields varied, loads once per
    combination of the load fields (a 100 × 100 pressure × weight grid: 200 builds)."""
    jnames = [k for k in gnames if k not in LOAD_FIELDS]
    lnames = [k for k in gnames if k in LOAD_FIELDS]
    for names, of in ((jnames, base.joint), (lnames, base.load)):
        if not names:
            continue
        idx = [gnames.index(k) for k in names]
        for sub in itertools.product(*(glists[i] for i in idx)):
            try:
                dataclasses.replace(of, **dict(zip(names, sub, strict=True)))
            except HydroarmError as exc:
                g = next(
                    g
                    for g, c in enumerate(combos)
                    if all(c[i] == v for i, v in zip(idx, sub, strict=True))
                )
                key = exc.field.rsplit(".", 1)[-1]
                field = f"grid.{key}" if key in gnames else "grid"
                raise HydroarmError(field, f"row {g * n_mc}: {exc.problem}") from None


def _columns_of(base, names, values) -> dict:
    """Field -> the base value (a float) or, for a varied field, one value per row."""
    j, load = base.joint, base.load
    cols = {k: getattr(j, k) for k in dataclasses.asdict(j) if not isinstance(getattr(j, k), str)}
    cols.update({k: getattr(load, k) for k in LOAD_FIELDS})
    cols["static_friction"] = j.breakaway_friction  # the kernels' breakaway force
    for i, k in enumerate(names):
        cols[k] = values[:, i]
    if "coulomb_friction" in names and "static_friction" not in names and j.static_friction is None:
        cols["static_friction"] = cols["coulomb_friction"]  # breakaway follows Coulomb
    return cols


def _row_text(names, values, row) -> str:
    return ", ".join(f"{k} = {values[row, i]:.4g}" for i, k in enumerate(names))


def check_sweep_step(base, names, values, params, cols) -> None:
    """Refuse a fixed step that is unstable for the base or a governing row.

    The governing rows are the ``GOVERNING_ROWS`` rows with the highest
    `rate_estimate` (stiffest oil column, lightest
    inertia, most leakage); each gets the same check as a single scenario. A screen, not a
    proof: a row outside them could in principle still be unstable (the engine then reports
    it as ``failed``).
    """
    with within("scenario"):
        base.check_step()
    n = params.shape[0]
    if not names or n == 0:
        return
    rate = np.broadcast_to(
        rate_estimate(
            cols["piston_area"],
            cols["trapped_volume"],
            cols["bulk_modulus"],
            cols["crank_radius"],
            cols["gear_ratio"],
            cols["inertia"],
            cols["leakage_coefficient"],
            cols["viscous_friction"],
        ),
        (n,),
    )
    k = min(GOVERNING_ROWS, n)
    rows = np.argpartition(-rate, k - 1)[:k] if k < n else np.arange(n)
    rows = rows[np.argsort(-rate[rows], kind="stable")]
    th0, th1 = base.initial_angle, base.target_angle()
    for row in rows:
        h = stable_step_limit(
            base.method, base.step, th0, th1, joint_at(params, row), load_at(params, row)
        )
        if h is None:
            continue
        raise StabilityError(
            "scenario.solver.step",
            f"{format_time(base.step)} is too large to be stable with method '{base.method}' "
            f"for row {int(row)} ({_row_text(names, values, int(row))}); the largest stable "
            f"step for that row is {format_time(h)}",
            h,
        )


def parse_sweep(
    doc: dict, base_dir: Path = Path("."), source: str = "sweep"
) -> Sweep | ServoSweep | CircuitSweep:
    """A sweep of the paper's joint (`Sweep`), or of a servo built from components
    when ``[scenario]`` has an ``[actuator]`` (`ServoSweep`)."""
    if is_circuit_study(doc):  # any circuit, by its system file
        return parse_circuit_sweep(doc, base_dir, source)
    reject_unknown_keys("", doc, SWEEP_SECTIONS)
    if "chunk" in doc:
        whole_number("chunk", doc["chunk"])
    sc_doc = optional_table(doc, "scenario")
    if is_component_file(sc_doc):  # a servo built from components
        return parse_servo_sweep(doc, sc_doc, base_dir, source)
    with within("scenario"):
        base = scenario_from_doc(sc_doc, base_dir, source, records=False)
        if base.lever.description != "step":
            raise HydroarmError("input.type", "a sweep needs a step input")
        if not registry.method(base.method).fixed_step:
            raise HydroarmError(
                "solver.method", f"a sweep runs {' or '.join(registry.fixed_step_methods())}"
            )
    if "metrics" in doc:
        if "metrics" in sc_doc:
            raise HydroarmError("metrics", "give [metrics] or [scenario.metrics], not both")
        base = base.replace(
            metric_options=metric_options("metrics", as_table("metrics", doc["metrics"]))
        )
    P0 = base.row
    grid = optional_table(doc, "grid")
    mc = dict(optional_table(doc, "monte_carlo"))
    v = varied_rows(
        grid,
        mc,
        PARAMETERS,
        "sweep parameter",
        read=lambda k: None,
        dimension=lambda k: None,
        base_value=lambda k: P0[PARAMETERS[k][0]],
        check_grid=lambda gnames, glists, combos, n_mc: _check_grid_points(
            base, gnames, glists, combos, n_mc
        ),
    )
    names, values = v.names, v.values
    n = values.shape[0]
    cols = _columns_of(base, names, values)
    check_rows(cols, {k: v.field(k) for k in names})
    params = np.repeat(P0[None, :], n, axis=0)
    for i, k in enumerate(names):
        params[:, PARAMETERS[k][0]] = values[:, i]
    if (
        "coulomb_friction" in names
        and "static_friction" not in names
        and base.joint.static_friction is None
    ):
        params[:, J_F_STATIC] = params[:, J_F_COULOMB]  # breakaway follows Coulomb
    check_sweep_step(base, names, values, params, cols)
    h = hashlib.sha256()
    h.update(json.dumps(doc, sort_keys=True, default=str).encode())
    h.update(params.tobytes())
    return Sweep(base=base, names=names, values=values, params=params, digest=h.hexdigest()[:16])


def load_sweep(path) -> Sweep | ServoSweep | CircuitSweep:
    """Read a sweep TOML file (see the module doc)."""
    doc, path = read_toml_file(path)
    return parse_sweep(doc, path.parent, path.name)


# ------------------------------------------------------------------ running ---
def scenario_inputs(sw: Sweep):
    """Per-scenario start angle, start pressure and lever step (y0 → y1) [rad, Pa, m]."""
    b = sw.base
    n = sw.size
    th0 = np.full(n, b.initial_angle)
    p_start = math.nan if b.initial_pressure is None else float(b.initial_pressure)
    p0, y0, y1 = _step_inputs(sw.params, b.initial_angle, b.target_angle(), p_start)
    return th0, p0, y0, y1


@njit(cache=True, nogil=True, error_model="numpy")
def _step_inputs(table, a0, a1, p_start):
    """Start pressure (``p_start``, or NaN: the holding pressure) and lever step of each row:
    the test is defined by its angles a0 → a1, the lever follows the crank geometry."""
    n = table.shape[0]
    p0 = np.empty(n)
    y0 = np.empty(n)
    y1 = np.empty(n)
    for i in range(n):
        J, L = joint_at(table, i), load_at(table, i)
        y0[i] = jack_position(a0, J)
        y1[i] = jack_position(a1, J)
        p0[i] = holding_pressure(a0, J, L) if math.isnan(p_start) else p_start
    return p0, y0, y1


def run_chunk(
    method, params, th0, p0, y0, y1, t_step, h, nsteps, metric_options=None, threads=None
):
    """Metrics of one chunk; ``threads`` limits numba's threads (1 inside a Dask worker)."""
    if threads is not None:
        most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
        numba.set_num_threads(max(1, min(threads, most)))
    return run_batch(
        method,
        params,
        th0,
        p0,
        y0,
        y1,
        t_step=t_step,
        h=h,
        nsteps=nsteps,
        metric_options=metric_options,
    )


class _Bar:
    """A sweep's progress: a bar redrawn on a terminal; off a terminal a line every
    `hydroarm.io.progress.interval` seconds at most; in a notebook a ``tqdm.auto`` bar."""

    def __init__(self, total, stream=None):
        self.stream = stream or sys.stderr
        self.on = self.stream.isatty()
        self.throttle = Throttle(self.on)
        self.total = total
        self.t0 = time.perf_counter()
        # a notebook: a tqdm.auto bar of chunks (hydroarm.io.progress.notebook_bar)
        self.bar = notebook_bar(total, "sweep") if stream is None else None

    def __call__(self, done, steps_done):
        final = done == self.total
        if self.bar is not None:
            rate = steps_done / max(time.perf_counter() - self.t0, 1e-9)
            self.bar.set_postfix_str(f"{rate:.3g} scenario-steps/s", refresh=False)
            self.bar.update(done - self.bar.n)
            if final:
                self.bar.close()
            return
        if not self.throttle():
            return
        rate = steps_done / max(time.perf_counter() - self.t0, 1e-9)
        if not self.on:
            self.stream.write(
                f"sweep: {done}/{self.total} chunks, {rate:.3g} scenario-steps/s "
                f"({time.perf_counter() - self.t0:.0f} s)\n"
            )
            self.stream.flush()
            return
        w = 30
        f = done / self.total if self.total else 1
        self.stream.write(
            f"\r[{'#' * int(w * f):<{w}}] {done}/{self.total} chunks, {rate:.3g} scenario-steps/s"
        )
        if final:
            self.stream.write("\n")
        self.stream.flush()


def run_sweep(
    sw: Sweep | ServoSweep | CircuitSweep,
    out,
    *,
    chunk: int = DEFAULT_CHUNK,
    resume: bool = False,
    executor: str = "local",
    scheduler: str | None = None,
    progress=None,
    stop_after: int | None = None,
    export=(),
) -> Path:
    """Run a sweep and write one row per scenario (parameters and metrics) to ``out``;
    ``export`` (``"netcdf"``, ``"mat"``): the same rows also beside it, as ``out`` with
    ``.nc`` (an xarray dataset, NetCDF; needs xarray) and ``.mat`` (MATLAB)
    (`hydroarm.batch.tables.SweepTable`)."""
    out = Path(out)
    formats = check_export(export)
    suffix = out.suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise HydroarmError("--out", "must end in .csv or .parquet")
    if suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise HydroarmError(
                "--out", "parquet needs pyarrow (pip install 'hydroarm[parquet]')"
            ) from None
    if executor not in ("local", "dask"):
        raise HydroarmError("--executor", f"must be local or dask, got {executor!r}")
    if not (isinstance(chunk, int) and chunk >= 1):
        raise HydroarmError("--chunk", f"must be a whole number ≥ 1, got {chunk!r}")
    check_output_file("--out", out)
    for f in formats:
        if out.with_suffix(EXPORT_SUFFIXES[f]) == out:
            raise HydroarmError("--export", f"{f} would overwrite --out {out}")
        check_output_file("--export", out.with_suffix(EXPORT_SUFFIXES[f]))
    if scheduler and executor != "dask":
        raise HydroarmError("--scheduler", "needs --executor dask")
    if scheduler:
        check_scheduler_address(scheduler)
    parts = out.with_name(out.name + ".parts")
    lock, created = _open_parts(parts, sw, chunk, resume)
    try:
        return _run_locked(
            sw, out, parts, created, chunk, executor, scheduler, progress, stop_after, formats
        )
    finally:
        unlock(lock)


def _open_parts(parts: Path, sw: Sweep | ServoSweep | CircuitSweep, chunk: int, resume: bool):
    """Lock the parts folder (made if missing) and check its manifest: (lock, created).

    A manifest that is missing, empty or unreadable (a crash or a full disk while it was
    written) holds no usable work: the folder starts afresh."""
    manifest = {"digest": sw.digest, "chunk": chunk, "n": sw.size}
    created = False
    try:
        parts.mkdir()
        created = True
    except FileExistsError:
        if not parts.is_dir():
            raise HydroarmError("--out", f"{parts} exists and is not a folder") from None
    except OSError as exc:
        raise write_error(parts, exc) from exc
    lock = try_lock(parts)
    if lock is None:
        raise HydroarmError(
            "--out",
            f"{parts} is in use by another running hydroarm sweep; wait for it to finish",
        )
    try:
        old = None if created else _read_manifest(parts)
        if old is None:
            for f in parts.glob("*chunk_*.npy"):
                f.unlink()
            atomic_write_text(parts / "manifest.json", json.dumps(manifest))
        elif not resume:
            raise HydroarmError(
                "--out",
                f"{parts} holds an unfinished sweep: use --resume to continue it, or delete it",
            )
        elif old != manifest:
            raise HydroarmError(
                "--resume",
                f"{parts} belongs to a different sweep or chunk size; delete it to start again",
            )
    except BaseException:
        if created:
            shutil.rmtree(parts, ignore_errors=True)
        unlock(lock)
        raise
    return lock, created


def _run_locked(
    sw, out, parts, created, chunk, executor, scheduler, progress, stop_after, formats=()
):
    b = sw.base
    job = sw.jobs()
    starts = list(range(0, sw.size, chunk))
    todo = [k for k, s in enumerate(starts) if not (parts / f"chunk_{k:06d}.npy").exists()]
    tick = progress or _Bar(len(starts))
    done = len(starts) - len(todo)
    nsteps = b.nsteps

    def args(k):
        return job(slice(starts[k], starts[k] + chunk))

    def keep(k, res):
        nonlocal done
        tmp = parts / f".chunk_{k:06d}.tmp.npy"
        try:
            np.save(tmp, res)
            os.replace(tmp, parts / f"chunk_{k:06d}.npy")
        except OSError as exc:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise write_error(parts / f"chunk_{k:06d}.npy", exc) from exc
        done += 1
        tick(done, done * chunk * nsteps)

    def kept() -> str:
        return f"{done} of {len(starts)} chunks kept in {parts}; run again with --resume to finish"

    tick(done, 0)
    finished = 0
    try:
        if executor == "local":
            for k in todo:
                fn, fn_args = args(k)
                keep(k, fn(*fn_args))
                finished += 1
                if stop_after is not None and finished >= stop_after:
                    raise _StopAfter
        else:
            _run_dask(todo, args, keep, scheduler, stop_after)
        metrics = np.vstack([np.load(parts / f"chunk_{k:06d}.npy") for k in range(len(starts))])
        _write(out, sw, metrics)
        if formats:  # the same rows (the run's doubles) beside out
            SweepTable(sw.columns(metrics), name=out.stem).export(out, formats)
    except _StopAfter:  # the tests' interruption
        raise HydroarmError("interrupted", kept()) from None
    except KeyboardInterrupt:
        if done == 0 and created:  # nothing finished: leave no trace
            shutil.rmtree(parts, ignore_errors=True)
            raise Interrupted("no chunk had finished; nothing kept") from None
        raise Interrupted(kept()) from None
    except BaseException as exc:
        if done == 0 and created:  # nothing worth keeping: leave no trace
            shutil.rmtree(parts, ignore_errors=True)
        elif isinstance(exc, HydroarmError) and done:
            raise HydroarmError(exc.field, f"{exc.problem} ({kept()})") from exc
        raise
    shutil.rmtree(parts, ignore_errors=True)
    return out


class _StopAfter(Exception):
    pass


SCHEDULER_TIMEOUT_S = 5
_ADDRESS = re.compile(r"^(?:(tcp|tls|ws|wss|ucx|inproc)://)?(\[[0-9a-fA-F:]+\]|[\w.-]+):(\d{1,5})$")


def check_scheduler_address(address: str) -> None:
    """Refuse at once a ``--scheduler`` that is not an address (``tcp://host:port``)."""
    m = _ADDRESS.match(address.strip())
    if not m or not 0 < int(m.group(3)) < 65536:
        raise HydroarmError(
            "--scheduler", f"{address!r} is not a scheduler address (e.g. tcp://host:8786)"
        )


def _run_dask(todo, args, keep, scheduler, stop_after):
    # no worker or nanny warnings on stderr when a sweep is interrupted or closes: in this
    # process and the worker processes it starts (they read the environment)
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "critical")
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise HydroarmError(
            "--executor", "dask is not installed (pip install 'hydroarm[dask]')"
        ) from None
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    cluster = None
    if scheduler:
        address = scheduler if "://" in scheduler else f"tcp://{scheduler}"
        try:
            client = Client(address, timeout=SCHEDULER_TIMEOUT_S)
        except (OSError, TimeoutError) as exc:
            raise HydroarmError(
                "--scheduler",
                f"cannot reach {address} (no answer within {SCHEDULER_TIMEOUT_S} s)",
            ) from exc
    else:
        # one numba thread per task and one task per worker thread: no over-subscription
        cluster = LocalCluster(
            n_workers=min(2, os.cpu_count() or 1),
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        )
        client = Client(cluster)
    try:
        futs = {client.submit(args(k)[0], *args(k)[1], threads=1, pure=False): k for k in todo}
        finished = 0
        for fut in as_completed(futs):
            keep(futs[fut], fut.result())
            finished += 1
            if stop_after is not None and finished >= stop_after:
                raise _StopAfter
    finally:
        with contextlib.suppress(Exception):
            client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()


def _read_manifest(parts: Path):
    try:
        m = json.loads((parts / "manifest.json").read_text())
    except (OSError, ValueError):
        return None
    return m if isinstance(m, dict) and m else None


_BOOL_COLUMNS = ("stalled", "failed")
_VELOCITY = unit_name("saturation_velocity")  # the column summary() reads
_CSV_BLOCK = 4096  # rows formatted at a time


def parameter_column(name: str) -> str:
    """A varied parameter's column: its name with its SI unit (``weight_n``,
    ``trapped_volume_m3``; ``gear_ratio`` as it is)."""
    suffix = si_suffix(PARAMETERS[name][1])
    return f"{name}_{suffix}" if suffix else name


def _columns(sw: Sweep, metrics: np.ndarray) -> dict:
    """scenario, the varied parameters, the metrics: SI values, each name with its unit
    (``weight_n``, ``saturation_velocity_m_s``, ``peak_pressure_pa``; docs/model.md "Units in
    names")."""
    cols: dict[str, np.ndarray] = {"scenario": np.arange(sw.size)}
    for i, k in enumerate(sw.names):
        cols[parameter_column(k)] = sw.values[:, i]
    for i, k in enumerate(METRICS):
        cols[unit_name(k)] = metrics[:, i] > 0.5 if k in _BOOL_COLUMNS else metrics[:, i]
    codes = metrics[:, METRICS.index("failed")]
    if np.any(codes > 0.5):  # why each failed row failed (only then: files stay as they were)
        cols["failure"] = np.array([failure_reason(c) or "" for c in codes], dtype=object)
    return cols


def _csv_field(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "True" if v else "False"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, str):
        return v
    return "" if math.isnan(v) else f"{v:.10g}"  # empty for NaN, as pandas writes it


def _write(out: Path, sw: Sweep | ServoSweep | CircuitSweep, metrics: np.ndarray) -> None:
    """One row per scenario; CSV written directly (no pandas import on the sweep path),
    Parquet through pandas/pyarrow. Written to a temporary file, then renamed."""
    cols = sw.columns(metrics)
    tmp = out.with_name(f".{out.name}.tmp")
    try:
        _write_file(tmp, out, sw, cols)
        os.chmod(tmp, 0o644)
        os.replace(tmp, out)
    except OSError as exc:
        raise write_error(out, exc) from exc
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _write_file(tmp: Path, out: Path, sw: Sweep | ServoSweep | CircuitSweep, cols: dict) -> None:
    if out.suffix.lower() == ".csv":
        names = list(cols)
        with open(tmp, "w", newline="") as f:
            f.write(",".join(names) + "\n")
            for lo in range(0, sw.size, _CSV_BLOCK):  # in blocks: memory stays flat
                block = (cols[k][lo : lo + _CSV_BLOCK].tolist() for k in names)
                f.writelines(
                    ",".join(_csv_field(v) for v in row) + "\n" for row in zip(*block, strict=True)
                )
    else:
        import pandas as pd

        pd.DataFrame(cols).to_parquet(tmp, index=False)


def summary(path) -> dict:
    """Quick statistics of a finished sweep file (for the CLI).

    Failed rows (``failed``: the run left the physical bounds) are counted and left out of
    the statistics, whatever their file holds; ``measured`` is the number of rows with a
    finite saturation velocity that the mean and standard deviation are taken over. A file
    written before the columns carried their units (``saturation_velocity``) is read too."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        vals = array.array("d")  # streamed: memory stays flat for 10⁶ rows
        failed = stalled = 0
        with open(path, newline="") as f:
            rows = csv.reader(f)
            header = next(rows)
            velocity = _VELOCITY if _VELOCITY in header else "saturation_velocity"
            iv, i_f, i_s = (header.index(k) for k in (velocity, "failed", "stalled"))
            for row in rows:
                bad = row[i_f] == "True"
                vals.append(float(row[iv]) if row[iv] and not bad else math.nan)
                failed += bad
                stalled += row[i_s] == "True"
        v = np.frombuffer(vals, dtype=float)
        n = len(v)
    else:
        import pandas as pd

        df = pd.read_parquet(path)
        bad_rows = df["failed"].to_numpy(bool)
        velocity = _VELOCITY if _VELOCITY in df.columns else "saturation_velocity"
        v = np.where(bad_rows, math.nan, df[velocity].to_numpy(float))
        failed, stalled = int(bad_rows.sum()), int(df["stalled"].sum())
        n = len(v)
    v = v[np.isfinite(v)] * 1e3
    return {
        "scenarios": n,
        "failed": failed,
        "stalled": stalled,
        "measured": len(v),
        "saturation_velocity_mm_s_mean": float(np.mean(v)) if len(v) else math.nan,
        "saturation_velocity_mm_s_sd": float(np.std(v, ddof=1)) if len(v) > 1 else math.nan,
    }
