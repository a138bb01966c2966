"""Batch engine (many scenarios at compiled speed) and sweeps (grid, Monte Carlo, Dask)."""

from .engine import METRICS, run_batch
from .sweep import load_sweep, parse_sweep, run_sweep

__all__ = ["METRICS", "load_sweep", "parse_sweep", "run_batch", "run_sweep"]
