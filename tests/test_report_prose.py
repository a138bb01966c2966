"""The report's prose quotes only computed or published numbers.

`hydroarm reproduce` claims that every number in its report is computed by the run, the
paper's values printed beside them. The tables are built from the computed rows; this test
checks the prose: every number in a paragraph of ``report.md`` must be, to the digits shown,
a value of the run's results (the returned data: tables, stall analysis, sweep, the notes the
prose is written from) or a value of the paper (measurements.csv, the published tables,
Appendix I) — a number typed into the prose by hand fails it, unless it names a figure, an
equation, a table or a load.
"""

import math
import re

import numpy as np
import pytest

from hydroarm.io.catalog import loads_table, read_data_csv
from hydroarm.paper.data import measurements, published_table

NUMBER = re.compile(r"(?<![\w.])[-+−]?(\d+(?:\.\d+)?)(?:(e[-+]\d+)|×10([⁰¹²³⁴⁵⁶⁷⁸⁹]+))?(?![\w])")
SUPERSCRIPT = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹", "0123456789")
# references, not data: "Fig. 11", "Figs. 7-10", "eqs. 5–7", "Eq. (1)", "Eqs. (5)–(7)",
# "Model 2", "loads 1 and 5", "loads 6–10", "load 10", `code`
REFERENCE = re.compile(
    r"`[^`]*`|\b(?:Figs?|[Ee]qs?)\.\s*\(?\d+\)?(?:\s*[–-]\s*\(?\d+\)?)?"
    r"|\bModel \d+|\b[Ll]oads? \d+(?:\s*(?:[–-]|and)\s*\d+)?|docs/\S+"
)


def prose(markdown: str) -> list[str]:
    """The paragraphs of a report (no headings, tables, figures or captions)."""
    out = []
    for line in markdown.splitlines():
        s = line.strip()
        if s and not s.startswith(("#", "|", "![", "*")):
            out.append(s)
    return out


def numbers(text: str) -> list[tuple[str, float, float]]:
    """(token, value, half of the last shown digit) of every number not in a reference."""
    out = []
    for m in NUMBER.finditer(REFERENCE.sub(" ", text)):
        digits, exp, sup = m.groups()
        d = len(digits.split(".")[1]) if "." in digits else 0
        scale = (
            10.0 ** int(exp[1:]) if exp else 10.0 ** int(sup.translate(SUPERSCRIPT)) if sup else 1.0
        )
        out.append((m.group(0), float(digits) * scale, 0.5 * 10.0**-d * scale))
    return out


def flatten(obj, out: list) -> list:
    """Every finite number inside nested dicts, lists, tuples and arrays."""
    if isinstance(obj, dict):
        for v in obj.values():
            flatten(v, out)
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            flatten(v, out)
    elif isinstance(obj, np.ndarray) and obj.dtype.kind in "fiu":
        out.extend(float(v) for v in obj.ravel() if np.isfinite(v))
    elif isinstance(obj, (int, float, np.floating, np.integer)) and not isinstance(obj, bool):
        if math.isfinite(obj):
            out.append(float(obj))
    return out


def paper_values() -> list:
    vals = list(measurements().values())
    for name in ("table1", "table2", "table3"):
        flatten(published_table(name), vals)
    flatten(loads_table(), vals)
    for r in read_data_csv("appendix1_parameters.csv"):
        for c in ("si_value", "imperial_value"):
            try:
                vals.append(float(r[c]))
            except ValueError:
                pass
    return vals


def unexplained(text: str, values) -> list[str]:
    """The numbers of ``text`` that no value (nor 100× one: a fraction shown in %) gives."""
    cand = np.abs(np.array(values, float))
    cand = np.concatenate([cand, 100 * cand])
    bad = []
    for token, v, tol in numbers(text):
        if not np.any(np.abs(cand - v) <= tol * (1 + 1e-9)):
            bad.append(token)
    return bad


@pytest.fixture(scope="module")
def known(repro):
    _, data = repro
    runs = {"model1", "model2", "transients"}  # simulation objects, not numbers
    return flatten({k: v for k, v in data.items() if k not in runs}, []) + paper_values()


def test_every_number_in_the_prose_is_computed_or_published(repro, known):
    out, _ = repro
    paragraphs = prose((out / "report.md").read_text())
    assert len(paragraphs) >= 10
    bad = {p[:60]: unexplained(p, known) for p in paragraphs}
    assert not {k: v for k, v in bad.items() if v}


def test_the_check_catches_a_typed_number(known):
    assert unexplained("the model agrees within 0.123456 % (Fig. 11, loads 6–10)", known) == [
        "0.123456"
    ]
    assert unexplained("see Fig. 11, eqs. 5–7, Model 2 and loads 1 and 5", known) == []
    assert [t for t, _, _ in numbers("λ_o = 6.4×10⁴ lb/in, 4.8e-05 %, -0.1 %")] == [
        "6.4×10⁴",
        "4.8e-05",
        "-0.1",
    ]


def test_prose_follows_the_computed_values(repro):
    # the prose states what the computed values say, not what they once said
    out, data = repro
    n = data["notes"]
    md = (out / "report.md").read_text()
    assert (
        f"{n['printed_table3_mean_mm_s']:.1f} against {n['published_table3_mean_mm_s']:.1f}" in md
    )
    assert f"ms from γ = {n['raise_tc_over_limit_from_pct']:.0f} % and reaches" in md
    tc, ratio = n["no_load_start_tc_ms"], n["no_load_start_over_tau"]
    assert f"gives {tc:.1f} ms ({ratio:.2f}·A/K_q)" in md
    assert f"step {n['step_us']:g} µs" in md
    # the paper's printed no-load mean, 25.8 ms, is the one compared against
    assert "the measured no-load 25.8 ms" in md
    v = data["validation_notes"]
    assert f"a {v['efficiency_loss_pct']:.0f} % loss" in md
