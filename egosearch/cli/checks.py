"""Checks the commands run on their options and input files before any work: each failure is one
line naming the option or file and what is allowed. Standard library only at import time, so
that the report commands, which never load torch, can use them too."""

from __future__ import annotations

import codecs
import json
import os
from collections.abc import Iterable
from pathlib import Path

from egosearch.core.seeds import MAX_SEED

PathLike = str | os.PathLike

IGNORED_CONFIG_FIELDS = ("seed", "device", "num_threads", "compile", "cuda_graph", "keep_checkpoint",
                         "checkpoint_every")
"""Learner config fields that say how or where a run ran, not what it learned: never a preset's mark."""


def _num(x: int | float) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def at_least(option: str, value: int | float | None, low: int | float, meaning: str = "it") -> None:
    """``value >= low`` (a None value is an option not given); ``meaning`` says what the value is."""
    if value is not None and not value >= low:
        raise ValueError(f"{option}={_num(value)}: {meaning} must be >= {_num(low)}")


def check_seed(option: str, seed: int | None, numpy_legacy: bool = False) -> None:
    """``seed >= 0``, and with ``numpy_legacy`` (a command whose run seeds numpy's global generator, as a
    training does) at most :data:`MAX_SEED`: either is refused only once the run starts, with a message
    that names no option."""
    at_least(option, seed, 0, "a seed")
    if numpy_legacy and seed is not None and seed > MAX_SEED:
        raise ValueError(f"{option}={seed}: a seed must be at most 2**32 - 1 = {MAX_SEED} (numpy's global seed is "
                         "32-bit)")


def check_suffix(option: str, path: PathLike | None, allowed: tuple[str, ...], what: str) -> None:
    """``path`` ends in one of ``allowed`` (case-insensitive), the formats its writer knows."""
    if path is not None and not os.fspath(path).lower().endswith(allowed):
        raise ValueError(f"{option}={os.fspath(path)}: {what} must end in {' or '.join(allowed)}")


def check_text_files(option: str, paths: Iterable[PathLike | None], what: str = "CSV") -> None:
    """Each existing file is a non-empty UTF-8 text file: pandas and csv otherwise fail with
    messages that name neither the file nor the option ("No columns to parse", "'utf-8' codec...").
    A missing file is left to the reader, whose message says what file it wanted."""
    for raw in paths:
        if raw is None:
            continue
        path = Path(raw)
        if not path.is_file():
            if path.is_dir():
                raise ValueError(f"{option}: {path} is a folder; a {what} file is expected")
            continue
        if path.stat().st_size == 0:
            raise ValueError(f"{option}: {path} is empty; a {what} file has a header line and rows")
        decoder = codecs.getincrementaldecoder("utf-8")()
        with open(path, "rb") as f:
            offset = 0
            for block in iter(lambda: f.read(1 << 20), b""):
                try:
                    decoder.decode(block)
                except UnicodeDecodeError as err:
                    raise ValueError(f"{option}: {path} is not a text {what} file (byte {offset + err.start} is "
                                     "not UTF-8)") from None
                offset += len(block)


def read_json_object(option: str, path: PathLike, what: str) -> dict:
    """The JSON object in ``path``, the file ``option`` names; ``what`` says what such a file is and
    what writes it. The json module's own message names neither the file nor the option ("Expecting
    property name enclosed in double quotes"), and a list or a number read as a record fails later with
    an AttributeError."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{option}: {path} is a folder; {what}")
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"{option}: {path} not found; {what}") from None
    except UnicodeDecodeError as err:
        raise ValueError(f"{option}: {path} is not a text file (byte {err.start} is not UTF-8); {what}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise ValueError(f"{option}: {path} is not JSON ({err.msg} at line {err.lineno}); {what}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{option}: {path} holds a JSON {type(data).__name__}, not an object; {what}")
    return data


def check_npz_files(option: str, paths: Iterable[PathLike]) -> None:
    """Each existing file is a zip archive, as numpy's ``.npz`` files are: numpy otherwise fails
    with a message that names no file."""
    for raw in paths:
        path = Path(raw)
        if not path.is_file():
            continue
        with open(path, "rb") as f:
            magic = f.read(4)
        if magic != b"PK\x03\x04":
            shown = "is empty" if not magic else "is not an .npz file (numpy's zip format)"
            raise ValueError(f"{option}: {path} {shown}; a trace file is written by `egosearch evaluate --traces`")


def learner_preset_of(config: dict, variant: str | None = None) -> tuple[str | None, str]:
    """(the learner preset, smoke, cpu or paper, whose config ``config`` is, how that was read)
    for a trained run's recorded config: the preset whose config, with the run's variant's
    overrides when its file is known, differs from it in the fewest fields (runs recorded before a
    field existed are read on the fields they have). None when two presets are as near."""
    # local: the learner's config module is plain data, but the variants layer loads gymnasium's registry
    from egosearch.rl.config import PRESETS, load_variant_config
    from egosearch.variants import load_variant

    overrides: dict = {}
    if variant:
        try:
            overrides = load_variant(variant).config
        except ValueError:
            overrides = {}
    distance = {}
    for preset in PRESETS:
        try:
            wanted = load_variant_config(preset, overrides).to_dict()
        except ValueError:
            wanted = load_variant_config(preset).to_dict()
        distance[preset] = sum(1 for key, value in config.items()
                                if key in wanted and key not in IGNORED_CONFIG_FIELDS and wanted[key] != value)
    ranked = sorted(distance, key=distance.get)
    if len(ranked) > 1 and distance[ranked[0]] == distance[ranked[1]]:
        return None, ""
    own = f" with {variant}'s overrides" if overrides else ""
    how = (f"its config is the {ranked[0]} preset's{own}" if distance[ranked[0]] == 0 else
           f"its config is nearest the {ranked[0]} preset's{own}: {distance[ranked[0]]} field(s) differ")
    return ranked[0], how
