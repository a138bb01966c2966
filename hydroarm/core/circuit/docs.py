"""The docs tables of the components, generated from their declarations.

Each component has a page ``docs/components/<type>.md`` holding, between the markers
``<!-- declaration -->`` and ``<!-- /declaration -->``, what is made here from its module:
the module's docstring (its equations and their sources) and the tables of its
``DECLARATION`` (ports, parameters with file key, SI unit, default and rule, the derived
quantities computed from them once a run, states);
notes, figures and validation written by hand go below the block.
``python -m hydroarm.core.circuit.docs`` rewrites the tables of every page;
``tests/test_circuit_docs.py`` fails when a page's tables differ from its declaration.
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

from .components import TYPES
from .declare import Component

START, END = "<!-- declaration -->", "<!-- /declaration -->"


def _default(v) -> str:
    if v is None:
        return "required"
    if isinstance(v, float) and math.isinf(v):
        return "∞" if v > 0 else "−∞"
    return f"{v:g}" if isinstance(v, float | int) else f'"{v}"'


def _unit(u: str) -> str:
    return {"": "–", "*": "any (SI)"}.get(u, u)


def declaration_tables(decl: Component) -> str:
    """Markdown tables of a component's ports, parameters, states and energy terms."""
    lines = [f'`type = "{decl.type}"`: {decl.summary}.', "", "| port | domain | |", "|---|---|---|"]
    for p in decl.ports:
        flags = [
            w
            for w, on in (
                ("optional", p.optional),
                ("compliant", p.compliant),
                ("drives", p.drives),
                ("inertial", p.inertial),
                ("prescribes", p.prescribes),
                ("slaved", p.slaved),
            )
            if on
        ]
        lines.append(
            f"| `{p.name}` | {p.domain}{' (' + ', '.join(flags) + ')' if flags else ''} | {p.doc} |"
        )
    lines += ["", "| parameter | unit | default | rule | |", "|---|---|---|---|---|"]
    for q in decl.parameters + decl.arrays:
        rule = " / ".join(q.choices) if q.choices else (q.rule or "–")
        default = "list" if q in decl.arrays else _default(q.default)
        lines.append(f"| `{q.name}` | {_unit(q.unit)} | {default} | {rule} | {q.doc} |")
    if decl.derived:
        lines += ["", "| derived (once per run) | unit | from | |", "|---|---|---|---|"]
        for d in decl.derived:
            args = ", ".join(f"`{a}`" for a in d.arguments)
            lines.append(f"| `{d.name}` | {_unit(d.unit)} | {args} | {d.doc} |")
    if decl.states:
        lines += ["", "| state | unit | |", "|---|---|---|"]
        for s in decl.states:
            lines.append(f"| `{s.name}` | {_unit(s.unit)} | {s.doc} |")
    if decl.energies:  # its energy account's terms (docs/components.md "Energy")
        lines += ["", "| energy term | |", "|---|---|"]
        for e in decl.energies:
            lines.append(f"| `{e.name}` | {e.doc} |")
    if decl.source:
        lines += ["", f"Source: {decl.source}."]
    return "\n".join(lines)


def page_block(module) -> str:
    """The generated part of a page: the module's docstring (its equations and source, as
    a literal block) and the declaration's tables."""
    doc = (module.__doc__ or "").strip()
    law = f"```text\n{doc}\n```\n\n" if doc else ""
    return f"{START}\n{law}{declaration_tables(module.DECLARATION)}\n{END}"


def update_page(path: Path, module) -> bool:
    """Rewrite the tables of one page; True if it changed."""
    text = path.read_text(encoding="utf-8")
    if START not in text or END not in text:
        raise ValueError(f"{path}: no {START} … {END} block")
    new = re.sub(
        re.escape(START) + r".*?" + re.escape(END), lambda _: page_block(module), text, flags=re.S
    )
    if new != text:
        path.write_text(new, encoding="utf-8")
    return new != text


INDEX_START, INDEX_END = "<!-- component-index -->", "<!-- /component-index -->"


def index_block() -> str:
    """The table of every registered component (type, summary, link to its page), for
    docs/components.md."""
    lines = [INDEX_START, "| type | what it is |", "|---|---|"]
    for name, module in TYPES.items():
        lines.append(f"| [`{name}`](components/{name}.md) | {module.DECLARATION.summary} |")
    lines.append(INDEX_END)
    return "\n".join(lines)


def update_index(path: Path) -> bool:
    """Rewrite the component index of docs/components.md; True if it changed."""
    text = path.read_text(encoding="utf-8")
    pattern = re.escape(INDEX_START) + r".*?" + re.escape(INDEX_END)
    new = re.sub(pattern, lambda _: index_block(), text, flags=re.S)
    if new != text:
        path.write_text(new, encoding="utf-8")
    return new != text


def main(argv: list[str]) -> int:
    root = Path(argv[0]) if argv else Path("docs/components")
    if update_index(root.parent / "components.md"):
        print(f"updated {root.parent / 'components.md'}")
    for name, module in TYPES.items():
        page = root / f"{name}.md"
        if not page.exists():
            page.write_text(f"# {name}\n\n{page_block(module)}\n", encoding="utf-8")
            print(f"created {page}")
        elif update_page(page, module):
            print(f"updated {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
