"""The evaluation card of a joint (issue 17): the numbers a prosthetist recognises, per load
case and direction, beside the requirements and the paper's measured values
(``hydroarm evaluate --config FILE --out DIR``; docs/evaluate.md).

The card's numbers are those of the commands they come from, computed by the same
functions: the motions' metrics by `hydroarm.analysis.requirements.case_metrics` (the
saturation tests of ``simulate``, run on the batch engine: ``time_constant`` is
``simulate(sc).metric_values()["time_constant_start"]``, the jack's saturation velocity the one
``hydroarm validate`` reports), the stall mass by
`hydroarm.batch.saturation.stall_mass` (``validate``'s), the requirement rows by
`check`. The backlash rows are arithmetic on the joint's
``backlash`` field: the arm's angle is uncertain by ±b/2 (the gearbox's play operator,
`hydroarm.core.lever.play_operator`), the hand by the arc ±(b/2)·d at the hand distance
d. The paper's measured values are not known here (they live in `hydroarm.paper`, a
layer above): the caller passes them (``paper``), as ``hydroarm evaluate`` does.

The file: ``[joint]`` (and ``[physics]``) as in scenario files; optional ``[[load_case]]``
(default `default_cases`: the paper's real loads 1 and 5, both directions, those of
Table I); optional ``[requirements]`` (default `default_requirements`: the paper's
time constant ≤ 50 ms, and the effective delay ≤ 125 ms, the top of the 100–125 ms Farrell
and Weir (2007) found best); optional ``[card] hand_distance`` (default: the paper's hand,
0.511 m from the shoulder, `hydroarm.batch.saturation.hand_distance`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..batch.saturation import hand_distance as paper_hand_distance
from ..errors import HydroarmError
from ..files import check_output_folder, csv_text, move_into, staging_folder
from ..io.catalog import paper_load
from ..io.sections import (
    as_table,
    field_value,
    joint_from_table,
    optional_table,
    parse_toml,
    read_text_file,
    reject_unknown_keys,
    text_value,
)
from ..model.joint import ServoJoint
from ..plotting.evaluate import fig_card
from ..plotting.joint import save_figure
from .requirements import (
    LoadCase,
    Requirement,
    case_metrics,
    check,
    check_cases,
    read_load_cases,
    read_requirements,
)

SECTIONS = {"name", "description", "joint", "physics", "load_case", "requirements", "card"}
CARD_KEYS = {"hand_distance"}
# the metrics every card shows (the requirements may add more)
CARD_METRICS = ("time_constant", "effective_delay", "saturation_angular_velocity", "stall_mass")
# Farrell and Weir (2007): the controller delay that gave the best performance
FARRELL_WEIR_BAND = (0.100, 0.125)  # [s]
OUTPUT_FILES = ("card.csv", "card.md", "card.png")
CSV_COLUMNS = [
    "case",
    "direction",
    "quantity",
    "value",
    "unit",
    "requirement",
    "limit",
    "met",
    "margin",
    "paper",
    "source",
]

# metric -> (card quantity, display unit, SI -> display factor)
DISPLAY = {
    "time_constant": ("time constant (63 %)", "ms", 1e3),
    "dead_time": ("dead time (1 %)", "ms", 1e3),
    "effective_delay": ("effective delay (dead time + τ after it = T′)", "ms", 1e3),
    "saturation_velocity": ("jack saturation velocity", "mm/s", 1e3),
    "saturation_angular_velocity": ("saturation angular velocity", "rad/s", 1.0),
    "saturation_angular_velocity_deg": ("saturation angular velocity", "deg/s", 180.0 / math.pi),
    "peak_pressure": ("peak load pressure", "bar", 1e-5),
    "pump_flow": ("pump flow at saturation", "l/min", 6e4),
    "energy_per_task": ("hydraulic energy per task", "J", 1.0),
    "stall_mass": ("stall mass in the hand", "kg", 1.0),
    "backlash_angle": ("positioning error from backlash (joint angle)", "deg", 180.0 / math.pi),
    "backlash_hand": ("positioning error from backlash (at the hand)", "mm", 1e3),
}
MOTION_ORDER = (
    "time_constant",
    "dead_time",
    "effective_delay",
    "saturation_velocity",
    "saturation_angular_velocity",
    "saturation_angular_velocity_deg",
    "peak_pressure",
    "pump_flow",
)
SOURCE = {
    "time_constant": "simulate --metrics: time_constant_start_ms (the batch engine)",
    "dead_time": "time_constant_start at 1 % of e_o (the batch engine)",
    "effective_delay": "dead time + 63 % time constant after it (= T' from the step)",
    "saturation_velocity": "validate / simulate: saturation velocity, middle 80 %",
    "saturation_angular_velocity": "joint angle over the middle 80 % of the travel",
    "saturation_angular_velocity_deg": "the same in deg/s",
    "peak_pressure": "simulate --metrics: peak_pressure_bar",
    "pump_flow": "piston area × jack saturation velocity",
    "energy_per_task": "p_s·A·|Δx| over the case's motions",
    "stall_mass": "validate: stall_mass_kg (bisection on simulations)",
    "backlash_angle": "± backlash / 2",
    "backlash_hand": "± backlash / 2 × hand distance (arc)",
}


def default_cases() -> tuple[LoadCase, ...]:
    """The paper's real loads of Table I: load 1 (the arm alone) and load 5 (0.45 kg in the
    hand), raising and lowering."""
    return (
        LoadCase("load 1 (arm alone)", paper_load(1)),
        LoadCase("load 5 (arm + 0.45 kg in the hand)", paper_load(5)),
    )


def default_requirements() -> tuple[Requirement, ...]:
    """The paper's time constant ≤ 50 ms, and the effective delay ≤ 125 ms (Farrell and Weir
    2007: 100–125 ms best)."""
    return read_requirements(
        {"time_constant": "<= 50 ms", "effective_delay": "<= 125 ms"}, field="requirements"
    )


@dataclass(frozen=True)
class Evaluation:
    """What a card evaluates: a joint, its load cases and requirements, the hand distance.

    Parameters
    ----------
    joint : ServoJoint
        The joint evaluated.
    cases : tuple of LoadCase
        The load cases (default: the paper's).
    requirements : tuple of Requirement
        The requirements checked (default: the paper's).
    hand_distance : float, optional
        Distance from the joint to the hand [m] (None: the paper's hand).
    name : str
        Label.
    """

    joint: ServoJoint
    cases: tuple[LoadCase, ...] = field(default_factory=default_cases)
    requirements: tuple[Requirement, ...] = field(default_factory=default_requirements)
    hand_distance: float | None = None  # [m]; None: the paper's hand
    name: str = "evaluation"

    def __post_init__(self):
        check_cases(self.requirements, self.cases)
        if self.hand_distance is not None and not (
            math.isfinite(self.hand_distance) and self.hand_distance > 0
        ):
            raise HydroarmError("card.hand_distance", f"must be positive, got {self.hand_distance}")


def read_evaluation_file(path) -> Evaluation:
    """Read an evaluation file; every problem is a one-line error before any simulation.

    Parameters
    ----------
    path : str or pathlib.Path
        The evaluation file (docs/evaluate.md).

    Returns
    -------
    Evaluation
        The evaluation, checked.
    """
    text, p = read_text_file(path)
    return evaluation_from_doc(parse_toml(text, p.name), p.stem, base_dir=p.parent)


def evaluation_from_doc(
    doc: dict, name: str = "evaluation", *, base_dir: Path = Path(".")
) -> Evaluation:
    reject_unknown_keys("", doc, SECTIONS)
    if "joint" not in doc:
        raise HydroarmError("joint", "is missing (give [joint] with a parameter_set or fields)")
    joint = joint_from_table(
        "joint",
        as_table("joint", doc["joint"]),
        default_set="paper-calibrated",
        physics=optional_table(doc, "physics"),
        base_dir=base_dir,
    )
    cases = read_load_cases(doc["load_case"]) if "load_case" in doc else default_cases()
    reqs = (
        read_requirements(doc["requirements"]) if "requirements" in doc else default_requirements()
    )
    card = as_table("card", doc.get("card", {}))
    reject_unknown_keys("card", card, CARD_KEYS)
    d = None
    if "hand_distance" in card:
        d = field_value("card.hand_distance", "arm", card["hand_distance"])
        if not d > 0:
            raise HydroarmError("card.hand_distance", "must be positive")
    return Evaluation(
        joint=joint,
        cases=cases,
        requirements=reqs,
        hand_distance=d,
        name=text_value("name", doc.get("name", name)),
    )


# ------------------------------------------------------------------------ the card ---
@dataclass
class Card:
    """The evaluation card of one joint.

    Parameters
    ----------
    evaluation : Evaluation
        What was evaluated.
    metrics : dict
        The metrics of each case and direction (those of `case_metrics`, SI).
    checks : list
        The requirement checks (the rows of `check`, SI).
    rows : list
        The card's table, one row per case, direction and quantity, in display units
        (`CSV_COLUMNS`).
    elapsed_s : float
        Wall-clock time of the evaluation [s].
    """

    evaluation: Evaluation
    metrics: dict
    checks: list
    rows: list
    elapsed_s: float = 0.0

    def value(self, quantity: str, case=None, direction=None, unit=None) -> float:
        """The card's value of a quantity key (`DISPLAY`) in a case and direction."""
        want = DISPLAY[quantity][1] if unit is None else unit
        for r in self.rows:
            if (r["key"], r["case"], r["direction"], r["unit"]) == (
                quantity,
                case,
                direction,
                want,
            ):
                return r["value"]
        raise KeyError((quantity, case, direction))

    def all_met(self) -> bool:
        return all(c["met"] for c in self.checks)

    def csv(self) -> str:
        return csv_text(CSV_COLUMNS, self.rows)

    def markdown(self, figure: str | None = "card.png") -> str:
        ev = self.evaluation
        lines = [
            f"# Evaluation card: {ev.name}",
            "",
            f"Joint `{ev.joint.name}`; {len(ev.cases)} load cases "
            f"({', '.join(c.name for c in ev.cases)}); hand distance "
            f"{1e3 * self.hand_distance:.0f} mm; computed in {self.elapsed_s:.2f} s. "
            "What each number is: docs/evaluate.md.",
            "",
            *card_table_lines(self.rows),
            "",
            "## Requirements",
            "",
            *requirement_lines(self.checks),
            "",
        ]
        if figure:
            lines += [f"![the card's numbers against the requirements]({figure})", ""]
        return "\n".join(lines)

    @property
    def hand_distance(self) -> float:
        d = self.evaluation.hand_distance
        return paper_hand_distance() if d is None else d

    def figure(self):
        return card_figure(self.rows, title=f"{self.evaluation.name}: {self.evaluation.joint.name}")

    def write(self, out) -> Path:
        """``card.csv``, ``card.md`` and ``card.png`` into the folder ``out`` (staged, then
        moved into place)."""
        folder = check_output_folder("--out", out)
        with staging_folder(folder) as stage:
            (stage / "card.csv").write_text(self.csv())
            (stage / "card.md").write_text(self.markdown())
            save_figure(self.figure(), stage / "card.png")
            move_into(stage, folder, OUTPUT_FILES)
        return folder


def _requirement_of(checks, metric, case, direction, senses) -> dict | None:
    """The requirement rows of one card value, merged: labels joined, met if all are, the
    smallest margin, the limit and sense of the tightest (the smallest margin)."""
    rs = [
        c
        for c in checks
        if c["metric"] == metric and c["case"] == case and c["direction"] == direction
    ]
    if not rs:
        return None
    tight = min(rs, key=lambda c: c["margin"])
    return {
        "requirement": "; ".join(c["requirement"] for c in rs),
        "limit": tight["limit"],
        "met": all(c["met"] for c in rs),
        "margin": tight["margin"],
        "sense": senses[tight["requirement"]],
    }


def card_rows(
    evaluation: Evaluation, metrics: Mapping, checks: Sequence[dict], paper: Mapping | None = None
) -> list[dict]:
    """The card's rows (display units): per case and direction the motion metrics, then the
    joint's stall mass and backlash rows. ``paper``: {(case, direction, key): value in the
    key's display unit} of the paper's measured values (key of `DISPLAY`)."""
    paper = paper or {}
    senses = {r.label: r.sense for r in evaluation.requirements}
    rows = []

    def add(key, case, direction, si):
        # a requirement bounds the metric of the key's name; the deg/s row repeats a number
        name, unit, k = DISPLAY[key]
        req = _requirement_of(checks, key, case, direction, senses)
        limit = req["limit"] * k if req is not None else None
        rows.append(
            {
                "key": key,
                "case": case,
                "direction": direction,
                "quantity": name,
                "value": si * k,
                "unit": unit,
                "requirement": req["requirement"] if req else "",
                "limit": limit,
                "met": req["met"] if req else None,
                "margin": req["margin"] if req else None,
                "sense": req["sense"] if req else None,
                "paper": paper.get((case, direction, key)),
                "source": SOURCE[key],
            }
        )

    for c in evaluation.cases:
        for direction in c.directions:
            m = metrics.get((c.name, direction), {})
            for key in MOTION_ORDER:
                metric = "saturation_angular_velocity" if key.endswith("_deg") else key
                if metric in m:
                    add(key, c.name, direction, float(m[metric]))
        task = metrics.get((c.name, None), {})
        if "energy_per_task" in task:
            add("energy_per_task", c.name, None, float(task["energy_per_task"]))
    joint = metrics.get((None, None), {})
    if "stall_mass" in joint:
        add("stall_mass", None, None, float(joint["stall_mass"]))
    b = evaluation.joint.backlash
    hand = evaluation.hand_distance
    add("backlash_angle", None, None, 0.5 * b)
    add("backlash_hand", None, None, 0.5 * b * (paper_hand_distance() if hand is None else hand))
    return rows


def evaluation_card(
    evaluation: Evaluation,
    *,
    paper: Mapping | None = None,
    stall_mass: float | None = None,
    progress=None,
) -> Card:
    """The card of ``evaluation``. ``paper``: the paper's values (`card_rows`);
    ``stall_mass`` [kg]: the joint's stall mass when already known (``hydroarm reproduce``
    reuses ``validate``'s), else searched (`stall_mass`)."""
    tick = progress or (lambda label: None)
    t0 = time.perf_counter()
    ev = evaluation
    want = {*CARD_METRICS, *(r.metric for r in ev.requirements)}
    if stall_mass is not None:
        want.discard("stall_mass")
    tick(
        f"evaluate: {sum(len(c.directions) for c in ev.cases)} saturation tests"
        + (" and the stall mass (bisection)" if "stall_mass" in want else "")
    )
    metrics = case_metrics([ev.joint], ev.cases, metrics=tuple(sorted(want)), jack_velocity=True)[0]
    if stall_mass is not None:
        metrics[(None, None)] = {"stall_mass": stall_mass}
    checks = check(ev.requirements, metrics)
    rows = card_rows(ev, metrics, checks, paper)
    return Card(ev, metrics, checks, rows, elapsed_s=time.perf_counter() - t0)


# ------------------------------------------------------------------ presentation ---
def _fmt(v, digits=4) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if v != v:
            return "—"
        if math.isinf(v):
            return "∞" if v > 0 else "−∞"
        return f"{v:.{digits}g}"
    return str(v)


CARD_HEADER = [
    "case",
    "direction",
    "quantity",
    "value",
    "unit",
    "requirement",
    "met",
    "margin",
    "paper",
]


def _pct(margin: float) -> str:
    """A margin (fraction) in %: one decimal below 10 %, none above."""
    if not math.isfinite(margin):
        return _fmt(margin)
    return f"{100 * margin:+.1f} %" if abs(margin) < 0.1 else f"{100 * margin:+.0f} %"


def card_table(rows) -> list[list[str]]:
    """The card's rows as text cells (`CARD_HEADER`)."""
    return [
        [
            r["case"] or "joint",
            r["direction"] or "",
            r["quantity"],
            _fmt(r["value"]),
            r["unit"],
            r["requirement"],
            _fmt(r["met"]),
            "" if r["margin"] is None else _pct(r["margin"]),
            _fmt(r["paper"]),
        ]
        for r in rows
    ]


def card_table_lines(rows) -> list[str]:
    """The card as a Markdown table."""
    out = ["| " + " | ".join(CARD_HEADER) + " |", "|" + "---|" * len(CARD_HEADER)]
    return out + ["| " + " | ".join(cells) + " |" for cells in card_table(rows)]


def requirement_lines(checks) -> list[str]:
    out = [
        "| requirement | case | direction | value | limit | unit | met | margin |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for c in checks:
        out.append(
            f"| {c['requirement']} | {c['case'] or 'joint'} | {c['direction'] or ''} | "
            f"{_fmt(c['value'])} | {_fmt(c['limit'])} | {c['unit']} | {_fmt(c['met'])} | "
            f"{100 * c['margin']:+.1f} % |"
        )
    return out


def card_lines(card: Card) -> list[str]:
    """The card as the terminal lines of ``hydroarm evaluate``."""
    lines = []
    for r in card.rows:
        where = f"{r['case']}, {r['direction']}" if r["direction"] else (r["case"] or "joint")
        req = ""
        if r["met"] is not None:
            req = (
                f"  [{'met' if r['met'] else 'NOT MET'}: {r['requirement']}, margin "
                f"{_pct(r['margin'])}]"
            )
        paper = "" if r["paper"] is None else f"  (paper {_fmt(r['paper'])})"
        lines.append(
            f"{where:<44} {r['quantity']:<46} {_fmt(r['value']):>9} {r['unit']:<6}{paper}{req}"
        )
    return lines


# the panels of the figure: (key, band)
FIGURE_KEYS = (
    "time_constant",
    "effective_delay",
    "saturation_velocity",
    "saturation_angular_velocity",
    "peak_pressure",
    "pump_flow",
    "energy_per_task",
    "stall_mass",
    "backlash_hand",
)


def card_figure(rows, *, title=None):
    """Bars of each card number against its requirement (`hydroarm.plotting.evaluate.fig_card`), the
    effective delay with the Farrell and Weir band."""
    panels = []
    for key in FIGURE_KEYS:
        rs = [r for r in rows if r["key"] == key]
        if not rs:
            continue
        name, unit, k = DISPLAY[key]
        withreq = [r for r in rs if r["limit"] is not None]
        p: dict = {
            "quantity": name,
            "unit": unit,
            "labels": [
                f"{r['case']}, {r['direction']}" if r["direction"] else (r["case"] or "joint")
                for r in rs
            ],
            "values": [r["value"] for r in rs],
            "paper": [r["paper"] for r in rs],
        }
        if withreq:
            tight = min(withreq, key=lambda r: r["margin"])
            p["limit"] = tight["limit"]
            p["sense"] = tight["sense"]
        if key == "effective_delay":
            p["band"] = (
                FARRELL_WEIR_BAND[0] * k,
                FARRELL_WEIR_BAND[1] * k,
                "Farrell & Weir 2007: 100–125 ms",
            )
        panels.append(p)
    return fig_card(panels, title=title)
