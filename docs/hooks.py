"""mkdocs hook: the repository files the pages link to from outside ``docs/`` become part of the site.

The pages link the stored figures where they are committed (``../paper_figs/cpu/fig6.png``), so
that they read the same on GitHub as in the built site. mkdocs publishes only what is under
``docs/``, and its strict mode rejects a link that leaves it. This hook adds every such linked
file of the repository to the site at its path in the repository (``paper_figs/cpu/fig6.png``)
and points the link at it. A link to a file that does not exist, or to a Markdown file, is left
as written, so that a strict build still fails on it.

It also writes the one page that is generated rather than kept: ``config.md``, every learner's config
(``egosearch.rl.config_page``), when the nav names it. It is made at each build, so that a new learner or
field is on it without a file to regenerate by hand.
"""

from __future__ import annotations

import os
import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File

LINK = re.compile(r"(?P<open>\]\()(?P<target>\.\./[^)\s#]+)")


def _root(config) -> Path:
    return Path(config.config_file_path).resolve().parent


def _repository_path(page_uri: str, target: str, config) -> str | None:
    """The repository path of the file a page's relative link ``target`` names, when the link leaves
    ``docs/`` for an existing file that is not a page; else None."""
    docs, root = Path(config.docs_dir).resolve(), _root(config)
    path = Path(os.path.normpath(docs / Path(page_uri).parent / target))
    if path.is_relative_to(docs) or not path.is_relative_to(root) or not path.is_file() or path.suffix == ".md":
        return None
    return path.relative_to(root).as_posix()


def on_files(files, config):
    for page in list(files.documentation_pages()):
        text = Path(page.abs_src_path).read_text(encoding="utf-8")
        for match in LINK.finditer(text):
            rel = _repository_path(page.src_uri, match["target"], config)
            if rel is not None and files.get_file_from_path(rel) is None:
                files.append(File.generated(config, rel, abs_src_path=str(_root(config) / rel)))
    if "config.md" in str(config["nav"]):
        from egosearch.rl.config_page import config_page  # no torch: the settings classes and their docstrings

        kept = files.get_file_from_path("config.md")  # a local `egosearch config page` output
        if kept is not None:
            files.remove(kept)
        files.append(File.generated(config, "config.md", content=config_page()))
    return files


def on_page_markdown(markdown, page, config, files):
    def to_site(match: re.Match) -> str:
        rel = _repository_path(page.file.src_uri, match["target"], config)
        if rel is None:
            return match[0]
        return match["open"] + posixpath.relpath(rel, posixpath.dirname(page.file.src_uri) or ".")

    return LINK.sub(to_site, markdown)
