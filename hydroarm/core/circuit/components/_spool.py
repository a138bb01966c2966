"""The spool of a directional valve: its dynamics and its stroke (shared by the 4/3 spool
valve and the linearised valve; not a component: the registry skips ``_`` modules).

The spool follows the demand u, limited to ±x_max, at once (``dynamics = "none"``: the
state records it), with a first-order lag τ·ẋ_v = u − x_v, or as a second-order system
ẍ_v = ω_n²·(u − x_v) − 2ζω_n·ẋ_v (Merritt 1967 §5.6: a servo valve's dynamics as a
low-order transfer function). The step's projection holds the spool inside its stroke.
"""

from __future__ import annotations

from ..declare import HYDRAULIC, SIGNAL_IN, Input, Param, Port, State
from ..laws import clip, kernel, signal_or

#: the spool's declaration, shared by the valves' parameter lists
DYNAMICS = (
    Param(
        "dynamics",
        "",
        "none",
        "",
        "the spool's dynamics",
        ("none", "first_order", "second_order"),
        sweepable=False,
    ),
    Param("time_constant", "s", 1.0e-3, "> 0", "first order: τ"),
    Param("natural_frequency", "rad/s", 600.0, "> 0", "second order: ω_n"),
    Param("damping_ratio", "", 0.7, "> 0", "second order: ζ"),
)
#: the spool's start, the last parameters of both valves (the states ``spool`` and
#: ``spool_velocity`` start there)
INITIAL_SPOOL = Param(
    "initial_spool", "m", 0.0, "", "spool position at the start (held within the stroke)"
)
INITIAL_SPOOL_VELOCITY = Param(
    "initial_spool_velocity", "m/s", 0.0, "", "spool velocity at the start (second order)"
)
STATES = (
    State("spool", "m", 1e-3, "initial_spool", "spool position x_v"),
    State("spool_velocity", "m/s", 1e-1, "initial_spool_velocity", "spool velocity (second order)"),
)
#: a directional valve's ports and its held-demand input
PORTS = (
    Port("P", HYDRAULIC, "pressure port"),
    Port("T", HYDRAULIC, "tank port"),
    Port("A", HYDRAULIC, "work port A (fed for x_v > 0)"),
    Port("B", HYDRAULIC, "work port B"),
    Port("command", SIGNAL_IN, "spool demand [m]", optional=True),
)
INPUTS = (Input("demand", "demand", "spool demand, held over each step", unless_port="command"),)
NONE, FIRST_ORDER, SECOND_ORDER = range(3)


@kernel
def spool_demand(sig, command, value, lim):
    """The spool demand [m]: the signal at index ``command`` (``value`` when the port is
    unconnected, −1), limited to the stroke ±``lim``."""
    return clip(signal_or(command, sig, value), -lim, lim)


@kernel
def spool_position(u, dyn, tau, w, zeta, s, d, i):
    """The spool position x_v [m] the edges see at demand u [m], with its rates written to
    d[i], d[i + 1] (i: the index of the ``spool`` state, ``spool_velocity`` after it)."""
    if dyn == NONE:
        d[i] = 0.0
        d[i + 1] = 0.0
        return u
    x_v = s[i]
    if dyn == FIRST_ORDER:
        d[i] = (u - x_v) / tau
        d[i + 1] = 0.0
    else:
        vv = s[i + 1]
        d[i] = vv
        d[i + 1] = w * w * (u - x_v) - 2.0 * zeta * w * vv
    return x_v


@kernel
def project_spool(u, dyn, lim, s, i):
    """The step's projection of the spool state s[i], s[i + 1]: the demand u recorded when the
    spool has no dynamics, else the position held within ±lim, its velocity into the stop
    removed."""
    if dyn == NONE:
        s[i] = u  # algebraic: recorded, not integrated
    elif s[i] > lim:
        s[i] = lim
        s[i + 1] = min(s[i + 1], 0.0)
    elif s[i] < -lim:
        s[i] = -lim
        s[i + 1] = max(s[i + 1], 0.0)


@kernel
def valve_spool(P, lim, dyn, dem, command, sig, s, d, i):
    """A valve's spool position x_v [m] with its rates into d (`spool_position`), its
    demand the command signal (or the ``demand`` parameter) limited to the stroke. ``lim``,
    ``dyn``, ``dem``: the indices in P of ``max_stroke``, ``dynamics`` (the four of
    `DYNAMICS` in order) and ``demand``; i: the ``spool`` state's index."""
    u = spool_demand(sig, command, P[dem], P[lim])
    return spool_position(u, P[dyn], P[dyn + 1], P[dyn + 2], P[dyn + 3], s, d, i)


@kernel
def valve_spool_projection(P, lim, dyn, dem, command, sig, s, i):
    """The step's projection of a valve's spool (`project_spool`); arguments as
    `valve_spool`."""
    project_spool(spool_demand(sig, command, P[dem], P[lim]), P[dyn], P[lim], s, i)
