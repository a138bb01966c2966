"""The human labels of the reproduce and validate reports' rows, from one declaration.

The CSV files and the returned data keep their code names (``table1_load1_raise_mm_s``:
stable column values a script can read); a report shows `label` of them
("load 1 raising velocity, Table I (mm/s)"). A code name is the quantity's words, then its
unit as a suffix (`UNITS`); the words come from `WORDS` (exact names) or
`PATTERNS` (names with a load and a direction in them); the unit is appended in
parentheses. A code name declared nowhere is an error (`KeyError`), so that a new row
cannot reach a report under its code name (tests/test_report_layout.py).
"""

from __future__ import annotations

import re

#: code-name suffix → the unit shown (longest first: ``_mm_s`` before ``_s``)
UNITS: tuple[tuple[str, str], ...] = (
    ("_mm_s", "mm/s"),
    ("_rad_s", "rad/s"),
    ("_mm2", "mm²"),
    ("_Nm", "N m"),
    ("_kN", "kN"),
    ("_kg", "kg"),
    ("_ms", "ms"),
    ("_mm", "mm"),
    ("_pct", "%"),
    ("_N", "N"),
)

_DIRECTION = {"raise": "raising", "lower": "lowering"}

#: names with a load and a direction: (pattern of the name without its unit, label); the
#: label's {load} and {direction} are the pattern's groups (the direction as a word)
PATTERNS: tuple[tuple[str, str], ...] = (
    (
        r"table3_load(?P<load>\d+)_(?P<direction>raise|lower)",
        "load {load} {direction} saturation velocity, Model 2",
    ),
    (r"table1_load(?P<load>\d+)_(?P<direction>raise|lower)", "load {load} {direction} velocity"),
    (
        r"model1_load(?P<load>\d+)_(?P<direction>raise|lower)",
        "load {load} {direction} velocity, Model 1",
    ),
)

#: exact names (without their unit suffix) → words
WORDS: dict[str, str] = {
    # the experiment comparison (reproduce)
    "mean_raise": "mean raising velocity",
    "mean_lower": "mean lowering velocity",
    "lower_over_raise": "mean lowering velocity above raising",
    "no_load_time_constant": "no-load time constant",
    "no_load_time_constant_formula": "no-load time constant, formula A/K_q",
    "no_load_start_time_constant": "no-load initial time constant",
    "max_loaded_time_constant_tested": "largest loaded time constant, as tested",
    "max_time_constant_to_stall": "largest time constant, up to stall",
    # the stall and efficiency arithmetic (reproduce)
    "theoretical_stall_force": "theoretical stall force A·p_s",
    "crank_torque": "crank torque",
    "expected_output_torque": "expected output torque",
    "measured_stall_torque": "measured stall torque",
    "torque_loss": "torque lost in the gearbox",
    "elbow.loss": "elbow loss",
    "friction.spring_balance_loss": "spring-balance friction, share of stall torque",
    "friction.stiction_pct_of_stall": "piston stiction, share of stall force (%)",
    # the validation against the measured arm (reproduce and validate)
    "lower_to_raise_ratio": "lowering over raising velocity (ratio)",
    "stall_mass": "stall hand mass",
    "stall_torque": "stall torque",
    "spring_balance_friction": "spring-balance friction torque",
    "piston_coulomb_friction": "piston Coulomb friction",
    "piston_stiction": "piston stiction",
    "gearbox_efficiency_half_stall": "gearbox efficiency at half stall (fraction)",
}


def _split(code: str) -> tuple[str, str]:
    """(name, unit) of a code name: its unit suffix taken off and shown as text."""
    for suffix, unit in UNITS:
        if code.endswith(suffix) and code not in WORDS:
            return code[: -len(suffix)], unit
    return code, ""


def label(code: str) -> str:
    """The human label with its unit of a report row's code name (module doc)."""
    name, unit = _split(code)
    words = WORDS.get(name)
    if words is None:
        for pattern, text in PATTERNS:
            m = re.fullmatch(pattern, name)
            if m is not None:
                g = m.groupdict()
                words = text.format(load=g["load"], direction=_DIRECTION[g["direction"]])
                break
    if words is None:
        raise KeyError(f"no report label declared for {code!r} (hydroarm/paper/labels.py)")
    return f"{words} ({unit})" if unit else words


def is_code_name(text: str) -> bool:
    """Whether a table cell reads as a code identifier (``snake_case`` or ``a.b``), not as
    words: what `label` turns into words."""
    return bool(re.fullmatch(r"[A-Za-z][A-Za-z0-9]*(?:[_.][A-Za-z0-9]+)+", text.strip()))
