"""Errors that hydroarm reports to users as one clear line."""


class HydroarmError(ValueError):
    """Bad input: names the field and the problem.

    The CLI prints ``hydroarm: error: <message>`` and exits with status 2.
    """

    def __init__(self, field: str, problem: str):
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}" if field else problem)


class StabilityError(HydroarmError):
    """A fixed integration step above the stability limit of the chosen method."""

    def __init__(self, field: str, problem: str, largest_stable_step: float):
        self.largest_stable_step = largest_stable_step
        super().__init__(field, problem)
