"""The rows of a sweep: ``[grid]`` × ``[monte_carlo]`` read with units and drawn from one
seeded generator, shared by the joint's sweeps (`hydroarm.batch.sweep`) and the
component servos' (`hydroarm.batch.servo_sweep`)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import HydroarmError
from ..io.sections import (
    FIELD_DIMENSIONS,
    as_table,
    field_value,
    reject_unknown_keys,
    require_keys,
    unknown_name,
    whole_number,
)
from ..io.sections import (
    number_or_quantity as _number_or_quantity,
)

MAX_SCENARIOS = 10**6  # rows of one sweep


def _grid_values(name, spec, read=None) -> list:
    """A grid's values in SI; ``read(field, value)`` reads one (default: the joint or load
    field ``name`` with its dimension and sign rule)."""
    field = f"grid.{name}"
    if read is None:

        def read(f, v):
            return field_value(f, name, v)

    if isinstance(spec, list):
        if not spec:
            raise HydroarmError(field, "is an empty list")
        return [read(field, v) for v in spec]
    if isinstance(spec, dict):
        reject_unknown_keys(field, spec, {"start", "stop", "num"})
        require_keys(field, spec, ("start", "stop", "num"))
        num = whole_number(f"{field}.num", spec["num"])
        if num > MAX_SCENARIOS:
            raise HydroarmError(f"{field}.num", f"must be at most {MAX_SCENARIOS:.0e}, got {num}")
        return list(
            np.linspace(
                read(f"{field}.start", spec["start"]),
                read(f"{field}.stop", spec["stop"]),
                num,
            )
        )
    raise HydroarmError(field, "must be a list of values or {start, stop, num}")


def _draw(name, spec, base_value, n, rng, dim=None) -> np.ndarray:
    field = f"monte_carlo.{name}"
    dim = FIELD_DIMENSIONS[name] if dim is None else dim
    if callable(dim):  # a reader (field, value) -> SI: the sign rules are checked here
        reader = dim

        def number_or_quantity(f, value, _dim, *, nonnegative=False):
            if _dim == "dimensionless":  # relative spreads are plain numbers
                return _number_or_quantity(f, value, _dim, nonnegative=nonnegative)
            v = reader(f, value)
            if nonnegative and not v >= 0:
                raise HydroarmError(f, f"must not be negative, got {value!r}")
            return v

    else:
        number_or_quantity = _number_or_quantity
    spec = as_table(field, spec)
    dist = spec.get("distribution")
    keys = {"normal": {"mean", "sd", "relative_sd"}, "uniform": {"low", "high", "relative"}}
    if dist not in keys:
        raise HydroarmError(f"{field}.distribution", f"must be normal or uniform, got {dist!r}")
    reject_unknown_keys(field, spec, keys[dist] | {"distribution"})
    if dist == "normal":
        mean = (
            number_or_quantity(f"{field}.mean", spec["mean"], dim) if "mean" in spec else base_value
        )
        if "sd" in spec and "relative_sd" in spec:
            raise HydroarmError(f"{field}.sd", "give sd or relative_sd, not both")
        if "sd" in spec:
            sd = number_or_quantity(f"{field}.sd", spec["sd"], dim, nonnegative=True)
        elif "relative_sd" in spec:
            rel = number_or_quantity(
                f"{field}.relative_sd", spec["relative_sd"], "dimensionless", nonnegative=True
            )
            sd = abs(mean) * rel
        else:
            raise HydroarmError(f"{field}.sd", "is missing (give sd or relative_sd)")
        return rng.normal(mean, sd, n)
    if "relative" in spec:
        if "low" in spec or "high" in spec:
            raise HydroarmError(f"{field}.relative", "give relative or low/high, not both")
        r = number_or_quantity(
            f"{field}.relative", spec["relative"], "dimensionless", nonnegative=True
        )
        lo, hi = base_value * (1 - r), base_value * (1 + r)
    else:
        require_keys(field, spec, ("low", "high"), "or give relative")
        lo = number_or_quantity(f"{field}.low", spec["low"], dim)
        hi = number_or_quantity(f"{field}.high", spec["high"], dim)
    if not hi >= lo:
        raise HydroarmError(f"{field}.high", "must not be below low")
    return rng.uniform(lo, hi, n)


@dataclass
class Varied:
    """The rows of a sweep: the varied names (grid's first) and their SI values."""

    names: list
    values: np.ndarray  # (rows, len(names))
    grid_names: list

    def field(self, name: str) -> str:
        """The dotted field of a varied name, for errors (``grid.x``, ``monte_carlo.x``)."""
        return f"{'grid' if name in self.grid_names else 'monte_carlo'}.{name}"


def varied_rows(grid, mc, known, what, *, read, dimension, base_value, check_grid=None):
    """The rows of ``[grid]`` × ``[monte_carlo]`` (n draws per grid point, one seeded
    generator): names checked against ``known``; ``read(name)`` gives a grid reader
    ``(field, value) -> SI`` (None: the joint's), ``dimension(name)`` the Monte Carlo
    dimension (None: the joint's) or a reader ``(field, value) -> SI``, ``base_value(name)``
    the base scenario's value (the draws' default mean and the centre of relative draws);
    ``check_grid(gnames, glists, combos, n_mc)`` checks the grid points before any draw."""
    for k in list(grid) + [k for k in mc if k not in ("n", "seed")]:
        if k not in known:
            sec = "grid" if k in grid else "monte_carlo"
            names = [*known, *(("n", "seed") if sec == "monte_carlo" else ())]
            raise unknown_name(f"{sec}.{k}", what, k, names)
    gnames = list(grid)
    glists = [_grid_values(k, grid[k], read(k)) for k in gnames]
    n_grid = math.prod(len(g) for g in glists)
    if n_grid > MAX_SCENARIOS:
        raise HydroarmError("grid", f"{n_grid:.3g} points (at most {MAX_SCENARIOS:.0e})")
    combos = list(itertools.product(*glists)) if gnames else [()]
    n_mc = 1
    mnames = [k for k in mc if k not in ("n", "seed")]
    if mc:
        n_mc = whole_number("monte_carlo.n", mc.get("n", 1))
        seed = mc.get("seed")
        if seed is None or isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise HydroarmError(
                "monte_carlo.seed",
                "is missing or not a whole number ≥ 0 (a seed makes the study repeatable)",
            )
    n = len(combos) * n_mc
    if n > MAX_SCENARIOS:
        raise HydroarmError(
            "monte_carlo.n" if mc else "grid",
            f"the sweep has {n:.3g} scenarios (at most {MAX_SCENARIOS:.0e})",
        )
    if check_grid is not None:
        check_grid(gnames, glists, combos, n_mc)
    names = gnames + mnames
    values = np.empty((n, len(names)))
    if gnames:
        values[:, : len(gnames)] = np.repeat(np.array(combos, float), n_mc, axis=0)
    if mnames:
        rng = np.random.default_rng(mc["seed"])
        for i, k in enumerate(mnames):
            values[:, len(gnames) + i] = _draw(k, mc[k], base_value(k), n, rng, dimension(k))
    return Varied(names=names, values=values, grid_names=gnames)
