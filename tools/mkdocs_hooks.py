"""mkdocs hooks of the documentation site (mkdocs.yml; issue 33).

The docs pages name each other as plain text ("docs/fit.md", "docs/examples/water_hammer.md",
in prose and in backticks), which reads well in a terminal and on a forge. On the site each
such mention of a page that exists becomes a link to it, relative to the page that mentions it;
fenced code blocks are left alone.

Before each build the gallery's generated folder (mkdocs-gallery's ``gallery_dirs``) is
emptied, so that a script removed or renamed leaves no page of its own behind on the site.
"""

from __future__ import annotations

import posixpath
import re
import shutil
from pathlib import Path

from mkdocs.plugins import event_priority

FENCE = re.compile(r"^(```|~~~).*?^\1[ \t]*$", re.S | re.M)
# docs/<path>.md, in backticks or not, not already the text or target of a link
MENTION = re.compile(r"(?<![\w/\[.-])(?<!\]\()(`?)docs/([\w./-]+?\.md)\1(?![\w/])(?!\]\()")


def _link(markdown: str, src_path: str, pages: set[str]) -> str:
    here = posixpath.dirname(src_path)

    def repl(m: re.Match) -> str:
        tick, target = m.group(1), m.group(2)
        if target not in pages or target == src_path:
            return m.group(0)
        rel = posixpath.relpath(target, here or ".")
        return f"[{tick}docs/{target}{tick}]({rel})"

    out, last = [], 0
    for f in FENCE.finditer(markdown):
        out.append(MENTION.sub(repl, markdown[last : f.start()]))
        out.append(f.group(0))
        last = f.end()
    out.append(MENTION.sub(repl, markdown[last:]))
    return "".join(out)


def on_page_markdown(markdown, page, config, files, **kwargs):
    pages = {f.src_uri for f in files if f.src_uri.endswith(".md")}
    return _link(markdown, page.file.src_uri, pages)


# a Sphinx role (:func:`x`, :class:`~a.b.C`), which mkdocstrings shows literally: the name
# alone, in code (a leading ~ keeps the last component, as Sphinx does). A safety net only:
# the docstrings have none (tests/test_docstrings.py; tools/sphinx_roles_to_autorefs.py made
# them cross-references or plain code)
ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|data|attr|exc|obj):<code>(~?)([^<]+)</code>")


def _role(m: re.Match) -> str:
    name = m.group(2).split(".")[-1] if m.group(1) else m.group(2)
    return f"<code>{name}</code>"


def on_page_content(html, page, config, files, **kwargs):
    return ROLE.sub(_role, html)


def _gallery_dirs(config) -> list[Path]:
    plugin = config["plugins"].get("gallery")
    if plugin is None:
        return []
    dirs = plugin.config["gallery_dirs"]
    return [Path(d) for d in (dirs if isinstance(dirs, list | tuple) else [dirs])]


@event_priority(100)  # before mkdocs-gallery's own on_pre_build, which writes the pages
def on_pre_build(config, **kwargs):
    docs = Path(config["docs_dir"]).resolve()
    for folder in _gallery_dirs(config):
        folder = folder.resolve()
        # only a folder inside docs/ that is not docs/ itself (never a source folder)
        if docs in folder.parents and folder.is_dir():
            shutil.rmtree(folder)
