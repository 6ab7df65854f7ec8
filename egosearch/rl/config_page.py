"""The page of every learner's whole config: the docs site's ``config.md``, made at each build by the docs'
hook (docs/hooks.py), and written by ``egosearch config page`` (to docs/config.md, git-ignored) for a reader
without the site. Never kept in git: a new learner or field is on it without a file to regenerate.

One table of the fields every learner shares (the run settings and the observation options'), then one per
registered learner of the fields it adds (the training aids it opts into, the building blocks its settings
are made of, its own). Each row: the field, its paper value (its default), the ``cpu`` preset's value where
the preset sets it, the settings class that declares it and its whole docstring. So a reader opens one file
for one learner's config, whichever files declare it; ``egosearch config show ALGORITHM --preset P`` gives
the same fields at any preset, with a variant on top.
"""

from __future__ import annotations

from egosearch.rl.config import (
    DEFAULT_ALGORITHM,
    config_class,
    declaring_class,
    field_defaults,
    field_docs,
    field_order,
    own_settings,
    shared_fields,
)
from egosearch.rl.learner_registry import LEARNERS
from egosearch.rl.presets import PRESETS

CONFIG_PAGE = "docs/config.md"
"""Where ``egosearch config page`` writes it by default (git-ignored; the docs build makes its own)."""

_HEAD = """# Every learner's config

<!-- generated from the settings classes' fields and docstrings (egosearch.rl.config_page), by the docs
     build and by `egosearch config page`; never kept in git -->

A learner's config is the fields every learner shares (the run settings and the observation options') and
the fields its settings add: the training aids it opts into, the networks and SAC's settings it is built from,
and its own. Each row gives the paper's value (the field's default; the `paper` preset changes only
housekeeping), the `cpu` preset's value where that preset sets one, the settings class that declares the
field, and the field's docstring, which names where its value comes from. `egosearch config show ALGORITHM
--preset P [--variant V]` prints the same fields at any preset, with a variant's values on top.
"""


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _table(algorithm: str, names: list[str]) -> list[str]:
    defaults, docs, cpu, klass = field_defaults(), field_docs(), PRESETS["cpu"](), config_class(algorithm)
    rows = ["| field | paper | cpu | declared in | what it is |", "|---|---|---|---|---|"]
    for name in names:
        owner = declaring_class(name, klass)
        preset = repr(cpu[name]) if name in cpu and name != "algorithm" else ""
        rows.append(f"| `{name}` | `{defaults[name]!r}` | {f'`{preset}`' if preset else ''} | "
                    f"`{owner.__module__}.{owner.__name__}` | {_cell(docs.get(name, ''))} |")
    return rows


def config_page() -> str:
    """The page's text."""
    order = field_order()
    shared = sorted(shared_fields(), key=order.index)
    lines = [_HEAD, "## Shared by every learner", "", *_table(DEFAULT_ALGORITHM, shared), ""]
    for name, entry in LEARNERS.items():
        own = list(own_settings(name))
        lines += [f"## {entry.display_name} (`algorithm: {name}`)", "",
                  f"{len(shared) + len(own)} fields: the {len(shared)} shared ones and these {len(own)}.", ""]
        lines += [*_table(name, own), ""] if own else ["None of its own.", ""]
    return "\n".join(lines).rstrip() + "\n"
