"""Named entries registered in one place: the helper behind both registries of the package, the learners'
(:mod:`egosearch.rl.learner_registry`) and the searchers' (:mod:`egosearch.searchers.searcher_registry`).

A :class:`Registry` keeps its entries in registration order, refuses a name that would not do as a folder
name or is taken (unless replaced), and answers an unknown name with one line that lists the registered
ones. :func:`resolve` turns a ``"module:attribute"`` reference into the attribute, imported on first use, so
that a registry names its factories without importing them.

Standard library only, like the searchers' registry that every stage may read (tests/test_layout.py)."""

from __future__ import annotations

import importlib
import re
from collections.abc import Callable, Iterator
from typing import Any, Generic, TypeVar

Entry = TypeVar("Entry")

NAME = re.compile(r"[A-Za-z0-9_\-]+")
"""A registered name: it names output folders and workflow wildcards (a searcher's results, a learner's runs)."""


def resolve(ref: str | Callable) -> Callable:
    """A ``"module:attribute"`` reference -> the attribute (imported now); anything else as it is."""
    if not isinstance(ref, str):
        return ref
    module, _, attribute = ref.partition(":")
    return getattr(importlib.import_module(module), attribute)


class Registry(Generic[Entry]):
    """Entries by name, in registration order. ``kind`` names an entry in error lines ("algorithm",
    "searcher"); ``reserved``: names no entry may take, each with the reason; ``describe(entry)``: words
    after a taken name's line."""

    def __init__(self, kind: str, reserved: dict[str, str] | None = None,
                 describe: Callable[[Entry], str] | None = None):
        self.kind = kind
        self.reserved = dict(reserved or {})
        self.describe = describe
        self.entries: dict[str, Entry] = {}
        """Every registered entry by name (the registry's own dict: a module may publish it)."""

    def add(self, name: str, entry: Entry, replace: bool = False) -> Entry:
        """Register ``entry`` as ``name``; a name already taken needs ``replace``."""
        if not isinstance(name, str) or not NAME.fullmatch(name):
            raise ValueError(f"{self.kind} name {name!r}: letters, digits, '_' and '-' only (it names output "
                             "folders and workflow wildcards)")
        if name in self.reserved:
            raise ValueError(f"{self.kind} name {name!r} is reserved: {self.reserved[name]}")
        if name in self.entries and not replace:
            detail = f" ({self.describe(self.entries[name])})" if self.describe else ""
            raise ValueError(f"{self.kind} {name!r} is registered already{detail}")
        self.entries[name] = entry
        return entry

    def get(self, name: str) -> Entry:
        """The entry registered as ``name``; one line listing the registered names for any other."""
        try:
            return self.entries[name]
        except (KeyError, TypeError):
            raise ValueError(f"unknown {self.kind} {name!r}; registered: {', '.join(self.entries)}") from None

    def remove(self, name: str) -> Entry:
        """Remove a registered entry (a test's own, after it); returns it."""
        self.get(name)  # an unknown name: the same one line as a lookup
        return self.entries.pop(name)

    def names(self) -> tuple[str, ...]:
        """Every registered name, in registration order."""
        return tuple(self.entries)

    def __contains__(self, name: Any) -> bool:
        return name in self.entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.entries)
