"""Errors that hydroarm reports to users as one clear line, and the shared number check."""

import math


class HydroarmError(ValueError):
    """Bad input: names the field and the problem.

    The CLI prints ``hydroarm: error: <message>`` and exits with status 2.

    Parameters
    ----------
    field : str
        The field at fault: a file's key (``joint.supply_pressure``), a CLI option, a
        parameter's name; empty for none.
    problem : str
        What is wrong with it, one line.
    """

    def __init__(self, field: str, problem: str):
        self.field = field
        self.problem = problem
        # a failed write (hydroarm.files.write_error): the path and the OSError, so that a
        # staging folder or the CLI can name the output option that gave the path
        self.path: str | None = None
        self.os_error: OSError | None = None
        super().__init__(f"{field}: {problem}" if field else problem)


class StabilityError(HydroarmError):
    """A fixed integration step above the stability limit of the chosen method.

    Parameters
    ----------
    field : str
        The field at fault (the step's).
    problem : str
        What is wrong with it, one line.
    largest_stable_step : float
        The largest stable step of the method [s].
    """

    def __init__(self, field: str, problem: str, largest_stable_step: float):
        self.largest_stable_step = largest_stable_step
        super().__init__(field, problem)


def check_number(
    field: str, v, *, positive: bool = False, nonnegative: bool = False, shown=None
) -> float:
    """Refuse non-numbers, NaN, infinities and wrong signs with a one-line error."""
    shown = v if shown is None else shown
    if isinstance(v, bool):
        raise HydroarmError(field, f"expected a number, got {v!r}")
    try:
        finite = math.isfinite(v)
    except TypeError:
        raise HydroarmError(field, f"expected a number, got {v!r}") from None
    if not finite:
        raise HydroarmError(field, f"{shown!r} is not a finite number")
    if positive and not v > 0:
        raise HydroarmError(field, f"must be positive, got {shown!r}")
    if nonnegative and v < 0:
        raise HydroarmError(field, f"must not be negative, got {shown!r}")
    return v
