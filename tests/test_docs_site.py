"""The documentation site's hooks (tools/mkdocs_hooks.py, mkdocs.yml; issue 33): a plain-text
mention of another docs page becomes a link relative to the mentioning page; code blocks,
existing links and unknown pages are left alone; Sphinx roles lose their markup. The gallery
(docs/gallery/*.py, executed by mkdocs-gallery on every build; the CI's docs step runs them):
each script has a titled docstring and saves a figure, the nav holds the gallery and every
page, and a build starts the generated gallery from scratch."""

import importlib.util
from pathlib import Path

import pytest

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


# the gallery (docs/gallery/*.py, mkdocs-gallery): scripts executed on every site build
GALLERY = ROOT / "docs" / "gallery"


def _gallery_scripts():
    return sorted(GALLERY.glob("*.py"))


def test_gallery_scripts_have_a_titled_docstring_and_save_a_figure():
    import ast

    scripts = _gallery_scripts()
    assert len(scripts) >= 5, scripts
    for path in scripts:
        tree = ast.parse(path.read_text(), str(path))
        doc = ast.get_docstring(tree)
        # mkdocs-gallery's format: a title underlined with "=", then at least a paragraph
        assert doc, f"{path.name}: no docstring"
        title, underline, *body = doc.splitlines()
        assert title.strip() and set(underline.strip()) == {"="}, f"{path.name}: no title"
        assert len(underline.strip()) >= len(title.strip()), f"{path.name}: short underline"
        assert " ".join(body).strip(), f"{path.name}: a title and no text"
        # a figure saved where the script runs (the site shows the figures it draws)
        saves = [
            node
            for node in ast.walk(tree)
            if isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "savefig"
        ]
        assert saves, f"{path.name}: saves no figure"
        # no __file__: mkdocs-gallery runs a script without it (the examples come from
        # hydroarm.io.examples.examples_folder, which works from a checkout and a wheel)
        assert "__file__" not in path.read_text(), f"{path.name}: uses __file__"
    assert (GALLERY / "README.md").read_text().startswith("# Gallery")


def _site_config():
    yaml = pytest.importorskip("yaml")  # with mkdocs (the docs extra)

    class Loader(yaml.SafeLoader):
        pass

    # mkdocs.yml may name Python objects (!!python/name:...); only the structure matters here
    Loader.add_multi_constructor("tag:yaml.org,2002:python/", lambda loader, suffix, node: None)
    return yaml.load((ROOT / "mkdocs.yml").read_text(), Loader=Loader)


def _nav_entries(nav):
    for item in nav:
        if isinstance(item, str):
            yield item
        else:
            for value in item.values():
                yield from _nav_entries(value) if isinstance(value, list) else [value]


def test_the_gallery_is_built_and_in_the_nav_with_every_page():
    config = _site_config()
    gallery = next(
        p["gallery"] for p in config["plugins"] if isinstance(p, dict) and "gallery" in p
    )
    assert gallery["examples_dirs"] == "docs/gallery"
    assert gallery["gallery_dirs"] == "docs/generated/gallery"
    # every script executed, on every build (not only plot_*.py, not only the changed ones)
    assert gallery["filename_pattern"] == "." and gallery["run_stale_examples"] is True
    entries = list(_nav_entries(config["nav"]))
    assert "generated/gallery" in entries and "notebooks.md" in entries
    # every page of docs/ is in the nav (strict: a page left out fails the build anyway)
    docs = ROOT / "docs"
    pages = {
        p.relative_to(docs).as_posix()
        for p in docs.rglob("*.md")
        if not p.relative_to(docs).as_posix().startswith(("gallery/", "generated/"))
    }
    assert pages == {e for e in entries if e.endswith(".md")}
    # the home page links the gallery, the notebooks page its notebooks
    assert "(generated/gallery/index.md)" in (docs / "index.md").read_text()
    notebooks = (docs / "notebooks.md").read_text()
    for nb in sorted((docs / "notebooks").glob("*.ipynb")):
        assert f"(notebooks/{nb.name})" in notebooks, nb.name
    # the CI script builds the site after the tests (numba's kernels are warm then)
    ci = (ROOT / ".ci" / "run").read_text()
    assert ci.index('step "tests"') < ci.index('step "docs site"')


def test_a_build_starts_the_gallery_from_scratch(tmp_path):
    class Plugin:
        config = {"gallery_dirs": [tmp_path / "docs" / "generated" / "gallery"]}

    generated = tmp_path / "docs" / "generated" / "gallery"
    generated.mkdir(parents=True)
    (generated / "removed_script.md").write_text("# a page of a script since removed")
    (tmp_path / "docs" / "index.md").write_text("# home")
    config = {"docs_dir": str(tmp_path / "docs"), "plugins": {"gallery": Plugin()}}
    hooks.on_pre_build(config)
    assert not generated.exists() and (tmp_path / "docs" / "index.md").exists()
    # the docs folder itself, or one outside it, is never removed
    for folder in (tmp_path / "docs", tmp_path):
        Plugin.config["gallery_dirs"] = [folder]
        hooks.on_pre_build(config)
        assert (tmp_path / "docs" / "index.md").exists()
    # without the gallery plugin, nothing to do
    hooks.on_pre_build({"docs_dir": str(tmp_path / "docs"), "plugins": {}})
