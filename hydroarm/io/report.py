"""A tiny document model rendered to Markdown and to self-contained HTML.

A report is a list of blocks: ("h", level, text), ("p", text), ("table", header, rows),
("fig", filename, caption) and ("details", title, blocks), a section folded in HTML (a
``<details>`` element, closed) and a level-2 heading before its blocks in Markdown (the same
order). Figures are linked in Markdown and embedded (base64) in HTML. In HTML tables numbers
are right-aligned and text left-aligned (`is_number`).
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path
from typing import Any

Block = tuple[Any, ...]  # ("h", level, text) | ("p", text) | ("table", header, rows) | ("fig", …)

#: a cell that reads as a number: digits with a sign, a decimal point, an exponent, a
#: percent sign or a ± (the rest is text: left-aligned in HTML)
NUMBER_CELL = re.compile(r"[+\-−±]?(\d[\d,]*(\.\d*)?|\.\d+)([eE][+\-]?\d+)?( ?%)?|—")


def is_number(v) -> bool:
    """Whether a table cell is a number (a float, an int, or text such as "+1.2 %")."""
    if isinstance(v, bool):
        return False
    if isinstance(v, (int, float)):
        return True
    return isinstance(v, str) and NUMBER_CELL.fullmatch(v.strip()) is not None


def fold(blocks) -> list[Block]:
    """``blocks`` with each level-2 section (a level-2 heading and the blocks up to the next
    one) turned into a ("details", heading, blocks) section; blocks before the first level-2
    heading stay as they are."""
    out: list[Block] = []
    section: list[Block] | None = None
    for b in blocks:
        if b[0] == "h" and b[1] == 2:
            section = []
            out.append(("details", b[2], section))
        elif section is not None:
            section.append(b)
        else:
            out.append(b)
    return out


def fmt(v, digits=4):
    if v is None or v == "":
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if v != v:
            return "—"
        return f"{v:.{digits}g}"
    return str(v)


def to_markdown(blocks) -> str:
    out = []
    for b in blocks:
        if b[0] == "details":  # Markdown has no folding: the heading, then the section
            out.append(to_markdown([("h", 2, b[1]), *b[2]]).rstrip("\n"))
        elif b[0] == "h":
            out.append("#" * b[1] + " " + b[2])
        elif b[0] == "p":
            out.append(b[1])
        elif b[0] == "table":
            header, rows = b[1], b[2]
            out.append("| " + " | ".join(header) + " |")
            out.append("|" + "---|" * len(header))
            for r in rows:
                out.append("| " + " | ".join(fmt(v) for v in r) + " |")
        elif b[0] == "fig":
            out.append(f"![{b[2]}]({b[1]})\n\n*{b[2]}*")
        out.append("")
    return "\n".join(out)


def _inline(text: str) -> str:
    # escape, then the two Markdown marks the reports use: **bold** and `code`
    t = html.escape(text)
    parts = t.split("**")
    t = "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))
    parts = t.split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))


def to_html(blocks, folder: Path, title: str) -> str:
    out = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
        "</title><style>body{font-family:sans-serif;max-width:60em;margin:2em auto;"
        "line-height:1.45}table{border-collapse:collapse;margin:1em 0}td,th{border:1px "
        "solid #bbb;padding:2px 8px;text-align:left;vertical-align:top}td.num{text-align:right;"
        "white-space:nowrap}th{background:#eee}img{max-width:100%}figcaption{font-style:italic}"
        "details{border-top:1px solid #ddd;padding:0.2em 0}summary{cursor:pointer}"
        "summary h2{display:inline;font-size:1.2em}</style></head><body>"
    ]
    _html_blocks(blocks, folder, out)
    out.append("</body></html>")
    return "\n".join(out)


def _cell(v) -> str:
    cls = " class='num'" if is_number(v) else ""
    return f"<td{cls}>{html.escape(fmt(v))}</td>"


def _html_blocks(blocks, folder: Path, out: list[str]) -> None:
    for b in blocks:
        if b[0] == "details":
            out.append(f"<details><summary><h2>{_inline(b[1])}</h2></summary>")
            _html_blocks(b[2], folder, out)
            out.append("</details>")
        elif b[0] == "h":
            out.append(f"<h{b[1]}>{_inline(b[2])}</h{b[1]}>")
        elif b[0] == "p":
            for para in b[1].split("\n\n"):
                if para.lstrip().startswith("- "):
                    # "- a\n- b": the first item keeps its "- ", the split took the others'
                    items = [i.strip() for i in para.strip().split("\n- ")]
                    items[0] = items[0].removeprefix("-").strip()
                    out.append("<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in items) + "</ul>")
                else:
                    out.append(f"<p>{_inline(para)}</p>")
        elif b[0] == "table":
            out.append(
                "<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in b[1]) + "</tr>"
            )
            for r in b[2]:
                out.append("<tr>" + "".join(_cell(v) for v in r) + "</tr>")
            out.append("</table>")
        elif b[0] == "fig":
            data = base64.b64encode((folder / b[1]).read_bytes()).decode("ascii")
            out.append(
                f"<figure><img src='data:image/png;base64,{data}' alt='{html.escape(b[2])}'>"
                f"<figcaption>{html.escape(b[2])}</figcaption></figure>"
            )
