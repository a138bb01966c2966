"""FMI export: a hydroarm joint or the whole arm as an FMI 2.0 co-simulation FMU
([`export_fmu`][hydroarm.export_fmu], ``hydroarm fmu``; docs/fmu.md). The slaves
(`hydroarm.fmu.slave`) need pythonfmu, the optional extra ``hydroarm[fmu]``; importing this package
does not."""

from .export import export_fmu

__all__ = ["export_fmu"]
