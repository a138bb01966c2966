"""The documentation site's hooks (tools/mkdocs_hooks.py, mkdocs.yml; issue 33): a plain-text
mention of another docs page becomes a link relative to the mentioning page; code blocks,
existing links and unknown pages are left alone; Sphinx roles lose their markup."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("mkdocs_hooks", ROOT / "tools" / "mkdocs_hooks.py")
hooks = importlib.util.module_from_spec(spec)
spec.loader.exec_module(hooks)

PAGES = {"fit.md", "model.md", "components.md", "examples/water_hammer.md", "index.md"}


def test_mentions_become_relative_links():
    text = "See docs/fit.md, and `docs/model.md` (equations); docs/examples/water_hammer.md."
    assert hooks._link(text, "index.md", PAGES) == (
        "See [docs/fit.md](fit.md), and [`docs/model.md`](model.md) (equations); "
        "[docs/examples/water_hammer.md](examples/water_hammer.md)."
    )
    # from a page in a subfolder, the link climbs out of it
    assert hooks._link("(docs/fit.md)", "examples/water_hammer.md", PAGES) == (
        "([docs/fit.md](../fit.md))"
    )


def test_what_is_left_alone():
    for text in (
        "docs/missing.md is no page",
        "[docs/fit.md](fit.md) is a link already",
        "a link [to it](docs/fit.md)",
        "hydroarm/docs/fit.md is another path",
        "```bash\ncat docs/fit.md\n```",
    ):
        assert hooks._link(text, "index.md", PAGES) == text, text
    # a page does not link to itself
    assert hooks._link("docs/fit.md", "fit.md", PAGES) == "docs/fit.md"


def test_sphinx_roles_lose_their_markup():
    html = ":func:<code>~hydroarm.model.scenario.simulate</code> and :class:<code>Scenario</code>"
    assert hooks.on_page_content(html, None, None, None) == (
        "<code>simulate</code> and <code>Scenario</code>"
    )


def test_site_config_names_the_hooks_and_every_page_is_under_docs():
    config = (ROOT / "mkdocs.yml").read_text()
    assert "tools/mkdocs_hooks.py" in config and "strict: true" in config
    api = (ROOT / "docs" / "api.md").read_text()
    import hydroarm

    listed = {ln.split("hydroarm.", 1)[1] for ln in api.splitlines() if ln.startswith(":::")}
    assert listed == set(hydroarm.__all__)
