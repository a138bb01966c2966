"""FMI export: a hydroarm joint or the whole arm as an FMI 2.0 co-simulation FMU
(:func:`export_fmu`, ``hydroarm fmu``; docs/fmu.md). The slaves (:mod:`hydroarm.fmu.slave`)
need pythonfmu, the optional extra ``hydroarm[fmu]``; importing this package does not."""

from .export import export_fmu

__all__ = ["export_fmu"]
