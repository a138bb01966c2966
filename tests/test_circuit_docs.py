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


def test_component_index_is_current():
    from hydroarm.core.circuit.docs import INDEX_END, INDEX_START, index_block

    text = (DOCS.parent / "components.md").read_text(encoding="utf-8")
    block = re.search(re.escape(INDEX_START) + r".*?" + re.escape(INDEX_END), text, flags=re.S)
    assert block is not None and block.group(0) == index_block()


def test_docs_circuit_example_runs(tmp_path):
    """The circuit written out in docs/components.md "Writing a circuit" runs as printed."""
    from hydroarm.io.circuit import circuit_from_doc
    from hydroarm.io.sections import parse_toml
    from hydroarm.model.circuit import simulate

    text = (DOCS.parent / "components.md").read_text(encoding="utf-8")
    toml = re.search(r"### Writing a circuit.*?```toml\n(.*?)```", text, flags=re.S).group(1)
    circuit = circuit_from_doc(parse_toml(toml, "doc"), "doc").replace(duration=0.05)
    r = simulate(circuit)
    assert r.bad_step == -1
    assert "cv1_flow_lpm" in r.to_pandas()
