"""The docstring convention (issue 33; docs/api.md): numpydoc sections, units in brackets, and
cross-references that the documentation site renders (mkdocstrings: ``[`Y`][hydroarm.Y]``, or
plain code for what the API reference does not document).

No docstring in hydroarm/ carries a Sphinx role (``:func:`x```, which the site would show
literally; tools/sphinx_roles_to_autorefs.py rewrites them). Every function and class of
``hydroarm.__all__`` has a numpydoc docstring whose Parameters section names each parameter of
its signature, with a type and a description, and a function's a Returns section (checked with
numpydoc's own validator, ``numpydoc.validate``, restricted to those codes); a ``float``
parameter gives its unit in brackets (``[Pa]``; ``[-]`` when it has none). The rewriting tool
(tools/sphinx_roles_to_autorefs.py) is tested on examples at the end.
"""

from __future__ import annotations

import ast
import importlib.util
import inspect
import re
from collections import Counter
from pathlib import Path

import pytest

import hydroarm

ROOT = Path(__file__).resolve().parents[1]
ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|data|attr|exc|obj):`")

# numpydoc.validate's codes held for the public API: GL08 no docstring; PR01 a parameter not
# documented; PR02 a documented parameter that is not in the signature; PR04 no type; PR07 no
# description; PR10 "name: type" without the space before the colon; RT01 no Returns section
CODES = {"GL08", "PR01", "PR02", "PR04", "PR07", "PR10", "RT01"}


def _docstrings(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield getattr(node, "lineno", 1), getattr(node, "name", "<module>"), doc


def test_no_docstring_has_a_sphinx_role():
    found = [
        f"{path.relative_to(ROOT)}:{line} ({name}): {ROLE.search(doc).group(0)}..."
        for path in sorted((ROOT / "hydroarm").rglob("*.py"))
        for line, name, doc in _docstrings(path)
        if ROLE.search(doc)
    ]
    assert not found, (
        "Sphinx roles show literally on the site; run python tools/sphinx_roles_to_autorefs.py:\n"
        + "\n".join(found)
    )


def _public_api() -> list[str]:
    return sorted(
        n
        for n in hydroarm.__all__
        if inspect.isclass(getattr(hydroarm, n)) or inspect.isfunction(getattr(hydroarm, n))
    )


def _errors(name: str) -> list[str]:
    validate = pytest.importorskip("numpydoc.validate", reason="numpydoc: the test extra")

    class Public(validate.Validator):
        """Private fields (a leading underscore) are no parameters a user passes."""

        def __init__(self, obj_name):
            super().__init__(validate.get_doc_object(validate.Validator._load_obj(obj_name)))

        @property
        def signature_parameters(self):
            return tuple(p for p in super().signature_parameters if not p.startswith("_"))

    result = validate.validate(f"hydroarm.{name}", validator_cls=Public)
    return [f"{code} {msg}" for code, msg in result["errors"] if code in CODES]


@pytest.mark.parametrize("name", _public_api())
def test_public_api_docstring_is_numpydoc(name):
    errors = _errors(name)
    assert not errors, f"hydroarm.{name}:\n" + "\n".join(errors)


def test_the_check_sees_every_public_function_and_class():
    # everything in __all__ but the tuple of method names is a function or a class
    assert set(hydroarm.__all__) - set(_public_api()) == {"METHODS"}


@pytest.mark.parametrize("name", _public_api())
def test_float_parameters_give_their_unit_in_brackets(name):
    docscrape = pytest.importorskip("numpydoc.docscrape", reason="numpydoc: the test extra")
    obj = getattr(hydroarm, name)
    doc = docscrape.ClassDoc(obj) if inspect.isclass(obj) else docscrape.FunctionDoc(obj)
    bare = [
        p.name
        for p in doc["Parameters"]
        if re.match(r"float\b", p.type) and not re.search(r"\[[^\]]+\]", " ".join(p.desc))
    ]
    assert not bare, f"hydroarm.{name}: no unit in brackets for {bare}"


# the rewriting tool, on examples
_spec = importlib.util.spec_from_file_location(
    "sphinx_roles_to_autorefs", ROOT / "tools" / "sphinx_roles_to_autorefs.py"
)
tool = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tool)


def _convert(text, module="hydroarm.model.scenario", cls=None):
    return tool.convert(text, module, False, tool._api(), Counter(), True, cls)


def test_tool_links_the_api_reference_and_writes_the_rest_as_code():
    # a public object, under its name in hydroarm.__all__; ~ shows the last name only
    assert (
        _convert(":func:`~hydroarm.model.scenario.simulate`") == "[`simulate`][hydroarm.simulate]"
    )
    assert _convert(":class:`hydroarm.model.joint.ServoJoint`") == (
        "[`hydroarm.model.joint.ServoJoint`][hydroarm.ServoJoint]"
    )
    # a member of a public class; a bare method name inside its class
    assert _convert(":meth:`SimulationResult.metrics`", "hydroarm.model.result") == (
        "[`SimulationResult.metrics`][hydroarm.SimulationResult.metrics]"
    )
    assert _convert(":meth:`get_state`", "hydroarm.model.stepper", cls="JointStepper") == (
        "[`get_state`][hydroarm.JointStepper.get_state]"
    )
    # internal, private, a module (relative to the package), a builtin, or nothing at all
    assert _convert(":func:`~hydroarm.model.joint.pack`") == "`pack`"
    assert _convert(":mod:`.servo`") == "`servo`"
    assert _convert(":exc:`KeyError`") == "`KeyError`"
    assert _convert(":data:`NO_SUCH_NAME`") == "`NO_SUCH_NAME`"
    # an explicit title; a target broken over two lines
    assert _convert(":func:`the run <hydroarm.model.scenario.simulate>`") == (
        "[`the run`][hydroarm.simulate]"
    )
    assert _convert(":func:`hydroarm.model.scenario.\n    simulate`") == (
        "[`hydroarm.model.scenario.simulate`][hydroarm.simulate]"
    )


def test_tool_rewraps_a_line_it_made_too_long():
    long = "    " + "word " * 18 + "[`x`][hydroarm.simulate] and the end of it"
    text = f"Summary.\n\n{long}\n    next line of the paragraph.\n    "
    out = tool.reflow(text, 4)
    assert all(len(line) <= tool.LIMIT for line in out.split("\n"))
    assert " ".join(out.split()) == " ".join(text.split())  # the same words, in order
    assert tool.reflow(out, 4) == out
