"""The failure test shared by the integrators' step loops: a run stops at the first state
that is not finite (the system kernel's `hydroarm.integrators.system.advance_steps` and the
servo kernel's loop both call `all_finite`; neither kernel imports the other)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def all_finite(s):
    """Whether every entry of a state vector is finite (the run's failure test)."""
    for i in range(s.shape[0]):
        if not np.isfinite(s[i]):
            return False
    return True
