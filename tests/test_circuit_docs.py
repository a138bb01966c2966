"""Every component has its docs page, and the page's generated block is its declaration's
(hydroarm/core/circuit/docs.py; refresh with ``python -m hydroarm.core.circuit.docs``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from hydroarm.core.circuit.components import TYPES
from hydroarm.core.circuit.docs import END, START, page_block

DOCS = Path(__file__).resolve().parents[1] / "docs" / "components"


@pytest.mark.parametrize("name", sorted(TYPES))
def test_component_page_matches_declaration(name):
    page = DOCS / f"{name}.md"
    assert page.exists(), f"docs/components/{name}.md is missing"
    text = page.read_text(encoding="utf-8")
    block = re.search(re.escape(START) + r".*?" + re.escape(END), text, flags=re.S)
    assert block is not None, f"{page.name}: no generated block"
    assert block.group(0) == page_block(TYPES[name]), (
        f"{page.name} is out of date: run python -m hydroarm.core.circuit.docs"
    )
