"""The reproduce report reads well (issue 33): a one-screen summary first (Table III's
published cells beside hydroarm's, with verdicts and their tolerance), the details folded
below it (HTML ``<details>``; Markdown in the same order), rows labelled in words with their
units, never by code names, numbers right-aligned and text left-aligned, well-formed HTML."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import pytest

from hydroarm.io.report import fold, is_number, to_html, to_markdown
from hydroarm.paper.labels import PATTERNS, WORDS, is_code_name, label
from hydroarm.paper.reproduce import TABLE3_TOLERANCE, within_text

VOID = {"meta", "img", "br", "hr", "input", "link"}


class Page(HTMLParser):
    """An HTML page parsed into its element stack: every end tag must close the element open
    last (well-formed), and the cells of each table are collected with their class."""

    def __init__(self):
        super().__init__()
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.order: list[str] = []  # "details", "table" and "h1"/"h2" as they open
        self.cells: list[tuple[str, str, int]] = []  # (text, class, column) of every <td>
        self.first_cells: list[str] = []  # each table row's first cell
        self._cell: list[str] | None = None
        self._cls = ""
        self._col = -1

    def handle_starttag(self, tag, attrs):
        if tag in ("details", "table", "h1", "h2"):
            self.order.append(tag)
        if tag == "tr":
            self._col = -1
        if tag == "td":
            self._col += 1
            self._cell, self._cls = [], dict(attrs).get("class") or ""
        if tag not in VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()
        if tag == "td" and self._cell is not None:
            text = "".join(self._cell).strip()
            self.cells.append((text, self._cls, self._col))
            if self._col == 0:
                self.first_cells.append(text)
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def parse(page: str) -> Page:
    p = Page()
    p.feed(page)
    p.close()
    assert not p.errors, p.errors[:5]
    assert p.stack == [], p.stack  # every element closed
    return p


# ------------------------------------------------------------------ the renderer ---
BLOCKS = [
    ("h", 1, "Title"),
    ("p", "A short paragraph."),
    ("h", 2, "Summary"),
    ("table", ["quantity", "value", "verdict"], [["load 6 raising (mm/s)", 27.3, "yes"]]),
    ("h", 2, "Details one"),
    ("p", "- an item\n- another"),
    ("table", ["a", "b"], [["words here", "+1.5 %"], ["more words", 3]]),
    ("h", 3, "A subsection"),
    ("p", "Inside the first fold."),
    ("h", 2, "Details two"),
    ("p", "The second fold."),
]


def test_fold_keeps_the_head_and_folds_each_section():
    head = BLOCKS[:4]
    folded = fold(BLOCKS[4:])
    assert [b[0] for b in folded] == ["details", "details"]
    assert folded[0][1] == "Details one" and ("h", 3, "A subsection") in folded[0][2]
    # Markdown: the same text as the unfolded blocks (the same order, headings and all)
    assert to_markdown(head + folded) == to_markdown(BLOCKS)


def test_html_folds_the_details_below_the_summary_and_is_well_formed(tmp_path):
    page = to_html(BLOCKS[:4] + fold(BLOCKS[4:]), tmp_path, "t")
    p = parse(page)
    assert p.order == ["h1", "h2", "table", "details", "h2", "table", "details", "h2"]
    assert page.count("<details>") == 2 and "<details open" not in page  # folded: closed
    assert "<summary><h2>Details one</h2></summary>" in page


def test_numbers_right_aligned_text_left_aligned(tmp_path):
    p = parse(to_html(BLOCKS, tmp_path, "t"))
    for text, cls, _ in p.cells:
        assert (cls == "num") == bool(re.fullmatch(r"[+\-]?[\d.]+( %)?", text)), (text, cls)
    assert "td,th{border:1px solid #bbb;padding:2px 8px;text-align:left" in to_html(
        [], tmp_path, "t"
    )
    assert ".num{text-align:right" in to_html([], tmp_path, "t")


@pytest.mark.parametrize(
    ("cell", "number"),
    [(27.3, True), (6, True), ("+1.5 %", True), ("−0.8 %", True), ("—", True), ("1e-05", True),
     (True, False), ("yes, within ±3 %", False), ("load 6", False), ("", False)],
)  # fmt: skip
def test_is_number(cell, number):
    assert is_number(cell) is number


# -------------------------------------------------------------------- the labels ---
def test_labels_come_from_one_declaration_with_units():
    assert label("table1_load1_raise_mm_s") == "load 1 raising velocity (mm/s)"
    assert label("model1_load5_lower_mm_s") == "load 5 lowering velocity, Model 1 (mm/s)"
    assert label("torque_loss_pct") == "torque lost in the gearbox (%)"
    assert label("torque_loss_Nm") == "torque lost in the gearbox (N m)"
    assert label("elbow.loss_pct") == "elbow loss (%)"
    with pytest.raises(KeyError, match="no report label declared"):
        label("a_new_quantity_ms")  # a row cannot reach a report under its code name
    for words in [*WORDS.values(), *(text for _, text in PATTERNS)]:
        # words, not identifiers (symbols such as p_s or K_q are the paper's)
        assert not is_code_name(words) and not re.search(r"[a-z]{2,}_[a-z]{2,}", words)


def test_verdicts_state_their_tolerance():
    assert within_text(-0.012, TABLE3_TOLERANCE) == "yes, within ±3 %"
    assert within_text(0.041, TABLE3_TOLERANCE) == "no: off by 4.1 % (more than ±3 %)"


# ------------------------------------------------------------ the real report ---
def _md_tables_first_cells(md: str) -> list[str]:
    """The first cell of every body row of the Markdown tables (not the header rows)."""
    lines = md.splitlines()
    cells = []
    for i, ln in enumerate(lines):
        if not ln.startswith("|") or ln.startswith("|---"):
            continue
        if i + 1 < len(lines) and lines[i + 1].startswith("|---"):
            continue  # a header
        cells.append(ln.split("|")[1].strip())
    return cells


def test_the_report_opens_with_its_summary(repro):
    out, data = repro
    md = (out / "report.md").read_text()
    headings = [ln for ln in md.splitlines() if ln.startswith("## ")]
    assert headings[0] == "## Summary"
    summary = md[md.index("## Summary") : md.index(headings[1])]
    published = [r for r in data["table3"] if r["paper_mm_s"] is not None]
    for r in published:  # every published cell: paper, hydroarm and the verdict on one row
        row = next(
            ln
            for ln in summary.splitlines()
            if ln.startswith(
                f"| load {r['load']} "
                f"{'raising' if r['direction'] == 'raise' else 'lowering'} saturation"
            )
        )
        assert f"| {r['paper_mm_s']:.4g} | {r['model_mm_s']:.4g} |" in row
        assert within_text(r["rel_error"], TABLE3_TOLERANCE) in row
    s = data["summary"]
    assert s["table3_published"] == len(published) == 4
    assert f"{s['table3_within']} of {s['table3_published']} published cells" in summary
    assert f"{s['statements_holding']} of the paper's {s['statements']} statements" in summary
    # short enough for one screen: the summary is the table and a few lines
    assert len(summary.splitlines()) < 20

    page = (out / "report.html").read_text()
    p = parse(page)
    # the title, the summary's heading and table, then only folded sections
    assert p.order[:3] == ["h1", "h2", "table"] and p.order[3] == "details"
    assert page.index("Summary") < page.index("<details>")
    body = page[page.index("<details>") :]
    assert body.count("<details>") == len(headings) - 1  # every other section folded
    assert "## Evaluation card" in md and "<summary><h2>Evaluation card</h2></summary>" in page


def test_no_row_label_is_a_code_name(repro):
    out, _ = repro
    md = (out / "report.md").read_text()
    labels = _md_tables_first_cells(md)
    assert "load 1 raising velocity (mm/s)" in labels
    bad = [x for x in labels if is_code_name(x)]
    assert not bad, bad
    p = parse((out / "report.html").read_text())
    assert p.first_cells and not [x for x in p.first_cells if is_code_name(x)]
    # prose left, numbers right: no text cell is right-aligned
    for text, cls, _ in p.cells:
        if cls == "num":
            assert is_number(text), text
        elif text:
            assert not is_number(text), text
