"""The evaluation card with the paper's measured values beside it: ``hydroarm evaluate``
([`evaluate`][hydroarm.evaluate]) and the "Evaluation card" section of ``hydroarm reproduce``
(`reproduce_card`, `report_blocks`).

The card itself is `hydroarm.analysis.evaluate`; this module adds what only the paper's
layer knows: the measured values (`hydroarm.paper.data`): Table I's saturation
velocities of loads 1 and 5 and the 0.45 kg stall mass in the hand.
"""

from __future__ import annotations

from ..analysis.evaluate import (
    CARD_HEADER,
    FARRELL_WEIR_BAND,
    Card,
    Evaluation,
    card_table,
    evaluation_card,
    read_evaluation_file,
)
from ..io.catalog import paper_load
from ..io.report import Block
from ..io.schema import parameter_set
from .data import measurement, table1

REPRODUCE_SET = "ucl-arm-measured"  # the joint of the reproduce report's card: the measured arm


def paper_values(evaluation: Evaluation) -> dict:
    """{(case, direction, key): the paper's measured value in the key's display unit} for the
    cases whose load is one of the paper's measured loads (1 and 5: Table I, mm/s of the
    jack), and the stall mass in the hand (0.45 kg)."""
    t1 = table1()
    out: dict = {(None, None, "stall_mass"): measurement("stall_hand_mass_kg")}
    for c in evaluation.cases:
        for n in (1, 5):
            if c.load == paper_load(n):
                for d in c.directions:
                    out[(c.name, d, "saturation_velocity")] = t1[(n, d)]
    return out


def evaluate(source, out=None, *, progress=None) -> Card:
    """The evaluation card of an evaluation file, with the paper's measured values beside it.

    Parameters
    ----------
    source : str, pathlib.Path or Evaluation
        An evaluation file, or an [`Evaluation`][hydroarm.Evaluation] already read.
    out : str or pathlib.Path, optional
        Folder written (``card.csv``, ``card.md``, ``card.png``); None writes nothing.
    progress : callable, optional
        ``progress(label)``, called as the cases run (`Progress`).

    Returns
    -------
    Card
        The card: its metrics, requirement checks and rows.
    """
    ev = source if isinstance(source, Evaluation) else read_evaluation_file(source)
    card = evaluation_card(ev, paper=paper_values(ev), progress=progress)
    if out is not None:
        card.write(out)
    return card


def reproduce_card(validation_rows) -> Card:
    """The card of the measured arm (``ucl-arm-measured``) for ``hydroarm reproduce``: the
    default cases and requirements, the stall mass reused from the validation's rows (the
    same search; only the card's 4 saturation tests run, on the batch engine)."""
    by = {r["quantity"]: r for r in validation_rows}
    ev = Evaluation(joint=parameter_set(REPRODUCE_SET), name="the measured UCL shoulder")
    return evaluation_card(ev, paper=paper_values(ev), stall_mass=by["stall_mass_kg"]["hydroarm"])


def report_values(card: Card) -> dict:
    """The numbers the section's prose quotes (``reproduce`` returns them with the card)."""
    unmet = [c for c in card.checks if not c["met"]]
    return {
        "card": card,
        "rows": card.rows,
        "checks": card.checks,
        "unmet": len(unmet),
        "checked": len(card.checks),
        "farrell_weir_ms": [1e3 * v for v in FARRELL_WEIR_BAND],
    }


def report_blocks(card: Card) -> list[Block]:
    """The reproduce report's "Evaluation card" section: every number of its prose is one of
    `report_values` or the paper's."""
    ev = card.evaluation
    v = report_values(card)
    unmet = [c for c in card.checks if not c["met"]]
    verdict = (
        "every requirement is met"
        if not unmet
        else f"{v['unmet']} of {v['checked']} requirement rows are not met ("
        + "; ".join(
            f"{c['requirement']}, {c['case']} {c['direction'] or ''}".strip() for c in unmet
        )
        + ")"
    )
    lo, hi = v["farrell_weir_ms"]
    limits = "; ".join(r.label for r in ev.requirements)
    # no number typed here: the prose quotes only computed values (tests/test_report_prose.py)
    why = (
        "The effective delay equals the time constant on every row, by definition: it is the "
        "dead time L (until the jack visibly starts; on the card's own rows) plus the time "
        "constant of the motion after it, T′ − L, and the paper's T′ is timed from the lever "
        "step, so it holds L already: L + (T′ − L) = T′."
    )
    return [
        ("h", 2, "Evaluation card"),
        (
            "p",
            f"The numbers a prosthetist recognises for the measured arm (`{ev.joint.name}`), "
            "per load and direction of the paper's saturation tests, beside the requirements "
            f"({limits}: the paper's time constant, and the top of the {lo:g}–{hi:g} ms of "
            "effective delay that Farrell and Weir found best, docs/evaluate.md) and the "
            f"paper's measurements (Table I; the stall mass in the hand). `hydroarm evaluate` "
            f"gives the same card for any joint. Here {verdict}.",
        ),
        ("table", CARD_HEADER, card_table(card.rows)),
        ("p", why),
    ]
