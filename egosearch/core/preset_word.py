"""The learner preset's old word, "profile", as records and logs written before the rename still spell it.

The smoke, cpu and paper settings were called profiles until egosearch 0.1 took "preset" for them (Snakemake's
``--profile`` is a folder of its own options, ``profiles/``). Stored files are never rewritten, so their readers
take both spellings: a provenance or estimate record's ``"profile"`` key, and a Snakemake log's ``profile=``
wildcard. The learner benchmark's and the GPU check's keys (``updates_per_s_cpu_profile``, ...) keep the old word
in new records too, so that one reader serves the stored ones and the new.
"""

from __future__ import annotations

OLD_WORD = "profile"
"""The key and the wildcard records written before the rename use for the preset."""


def recorded_preset(record: dict) -> str | None:
    """The preset a record names: its ``preset`` key, else the ``profile`` key of one written before the rename."""
    return record.get("preset", record.get(OLD_WORD))


def with_preset_wildcard(wildcards: dict[str, str]) -> dict[str, str]:
    """A logged job's wildcards with an old ``profile=`` read as ``preset=`` (its place kept)."""
    return {("preset" if key == OLD_WORD else key): value for key, value in wildcards.items()}
