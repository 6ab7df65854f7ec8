"""Reading the CSVs the experiments write, and telling a result's coordinates from its path.

Only pandas here: the report layer is *CSV in, files out* and never imports torch, the simulator
or any other egosearch module (see ``ARCHITECTURE.md``).

Path patterns (written by ``egosearch evaluate`` / ``train`` / ``fullbody``):

- per-episode evaluation: ``results/{preset}/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv``
- training curve:         ``results/{preset}/train/{variant}/seed{seed}/curve.csv``
- full body:              ``results/{preset}/fullbody/{setting}/seed{seed}.csv``

The functions below never glob: callers pass explicit file lists; the path is parsed only to
learn the seed and which scenario file an episode came from.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterable
from pathlib import Path

import pandas as pd

from egosearch.report.failures import stuck
from egosearch.searchers.searcher_registry import modular_floors

EPISODE_COLUMNS = ("scenario_id", "success", "steps", "path_length", "shortest_path", "spl", "collisions",
                   "episode_return")
CURVE_LEVEL_COLUMNS = ("home", "height", *EPISODE_COLUMNS)
"""A searcher's episodes on a training curve's scenarios (egosearch.runs.evaluate writes them): Figure 6's levels."""
CURVE_COLUMNS = ("env_steps", "success_rate", "spl", "episode_return", "critic_loss", "actor_loss", "curl_loss",
                 "alpha", "entropy", "steps_per_s", "updates_per_s", "wall_s")
FULLBODY_COLUMNS = ("scenario_id", "method", "mg", "M", "T", "success", "steps", "path_length", "shortest_path",
                    "spl", "attempts", "penetrations", "penetration_rate", "collisions")

PathLike = str | os.PathLike

_SEED_DIR = re.compile(r"^seed(\d+)$")
_SEED_FILE = re.compile(r"^seed(\d+)\.csv$")
HEIGHT_FILE = re.compile(r"^h(\d+(?:\.\d+)?)\.csv$")
"""The name of a per-episode evaluation CSV, ``h{height}.csv``: group 1 is the camera height."""


def read_checked_csv(path: PathLike, required: tuple[str, ...], what: str) -> pd.DataFrame:
    """The CSV at ``path``; an error naming ``what`` when it is missing or lacks a ``required`` column."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{what} CSV not found: {path}")
    df = pd.read_csv(path)
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise ValueError(f"{path}: not a {what} CSV, missing columns {missing}")
    return df


def seed_from_path(path: PathLike) -> int:
    """The seed of a result file: the last ``seed{N}`` directory, or a ``seed{N}.csv`` file name."""
    parts = Path(path).parts
    m = _SEED_FILE.match(parts[-1])
    if m:
        return int(m.group(1))
    for part in reversed(parts[:-1]):
        m = _SEED_DIR.match(part)
        if m:
            return int(m.group(1))
    raise ValueError(f"cannot tell the seed from {path}: expected a 'seed<N>' directory or 'seed<N>.csv' file")


def scenario_set_from_path(path: PathLike) -> str:
    """Which scenario file the episodes of an evaluation CSV came from: the path below ``seed{N}/``.

    For ``.../eval/head_on/seed3/kitchen/everywhere/h1.65.csv`` this is ``kitchen/everywhere/h1.65.csv``:
    the same for every variant and seed evaluated on the same scenarios, different for each layout
    (scenario ids restart at 0 in every scenario file, so ids alone do not identify a scenario
    once layouts are pooled).
    """
    parts = Path(path).parts
    for i in range(len(parts) - 2, -1, -1):
        if _SEED_DIR.match(parts[i]):
            return "/".join(parts[i + 1:])
    raise ValueError(f"cannot tell the seed from {path}: expected a 'seed<N>' directory")


def parse_eval_path(path: PathLike) -> dict:
    """``{variant, seed, layout, placement, height}`` of a per-episode evaluation CSV path."""
    p = Path(path)
    parts = p.parts
    m = HEIGHT_FILE.match(parts[-1])
    if m is None or len(parts) < 5 or not _SEED_DIR.match(parts[-4]):
        raise ValueError(f"{path}: expected .../{{variant}}/seed{{seed}}/{{layout}}/{{placement}}/h{{height}}.csv")
    return {"variant": parts[-5], "seed": int(_SEED_DIR.match(parts[-4]).group(1)), "layout": parts[-3],
            "placement": parts[-2], "height": float(m.group(1))}


def _as_paths(value) -> list[Path]:
    if isinstance(value, (str, os.PathLike)):
        return [Path(value)]
    return [Path(v) for v in value]


def read_episodes(paths: PathLike | Iterable[PathLike], seed: int | None = None) -> pd.DataFrame:
    """Per-episode CSVs stacked, with ``seed``, ``scenario_set`` (see :func:`scenario_set_from_path`) and
    ``stuck`` (failed with 50 or more collisions: :func:`egosearch.report.failures.stuck`) added.

    ``seed`` given: every file gets that seed and paths need no ``seed{N}`` directory (the scenario set
    is then the path below one, or else the file's path). Otherwise the seed is read from each path.

    Raises ValueError on no paths, on an empty file, or when two files have the same seed and
    scenario set (the same episodes counted twice).
    """
    paths = _as_paths(paths)
    if not paths:
        raise ValueError("no per-episode CSVs given")
    frames, seen = [], set()
    for path in paths:
        df = read_checked_csv(path, EPISODE_COLUMNS, "per-episode evaluation")
        if df.empty:
            raise ValueError(f"{path}: no episodes")
        if seed is None:
            s, sset = seed_from_path(path), scenario_set_from_path(path)
        else:
            s = int(seed)
            try:
                sset = scenario_set_from_path(path)
            except ValueError:
                sset = str(path)
        if (s, sset) in seen:
            raise ValueError(f"{path}: seed {s} on {sset} given twice")
        seen.add((s, sset))
        if df["scenario_id"].duplicated().any():
            raise ValueError(f"{path}: repeated scenario_id")
        df = df.assign(seed=s, scenario_set=sset, stuck=stuck(df))
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def read_curves(paths: Iterable[PathLike]) -> pd.DataFrame:
    """Training-curve CSVs stacked with a ``run`` column (position in ``paths``) and ``seed`` (from the path,
    or the position when the path names no seed); rows without a success rate are dropped."""
    frames = []
    for i, path in enumerate(_as_paths(paths)):
        df = read_checked_csv(path, ("env_steps", "success_rate"), "training curve")
        try:
            seed = seed_from_path(path)
        except ValueError:
            seed = i
        df = df.dropna(subset=["env_steps", "success_rate"]).assign(run=i, seed=seed)
        frames.append(df)
    if not frames:
        return pd.DataFrame(columns=[*CURVE_COLUMNS, "run", "seed"])
    return pd.concat(frames, ignore_index=True)


def read_fullbody(paths: Iterable[PathLike]) -> pd.DataFrame:
    """Full-body CSVs stacked with a ``seed`` column (from ``seed{N}.csv``; the position in ``paths`` otherwise)."""
    frames = []
    for i, path in enumerate(_as_paths(paths)):
        df = read_checked_csv(path, FULLBODY_COLUMNS, "full-body")
        try:
            seed = seed_from_path(path)
        except ValueError:
            seed = i
        frames.append(df.assign(seed=seed, source=str(path)))
    if not frames:
        return pd.DataFrame(columns=[*FULLBODY_COLUMNS, "seed", "source"])
    return pd.concat(frames, ignore_index=True)


def group_eval_paths(paths: Iterable[PathLike], variant: str | None = None) -> dict:
    """Flat list of evaluation CSV paths -> ``{(seed, height, placement): [paths over layouts]}`` (for ``table1``).

    ``variant``, if given, keeps only that variant's files; mixing variants otherwise is an error.
    """
    out: dict[tuple, list[Path]] = {}
    variants = set()
    for path in _as_paths(paths):
        info = parse_eval_path(path)
        if variant is not None and info["variant"] != variant:
            continue
        variants.add(info["variant"])
        out.setdefault((info["seed"], info["height"], info["placement"]), []).append(Path(path))
    if len(variants) > 1:
        raise ValueError(f"evaluation files of several variants {sorted(variants)}; pass variant=")
    return out


def cells_from_paths(paths: Iterable[PathLike]) -> dict:
    """Flat list of evaluation CSV paths (one variant) -> ``{(height, placement): [paths over seeds and layouts]}``
    (for ``compare_report``)."""
    out: dict[tuple, list[Path]] = {}
    for (_seed, height, placement), files in group_eval_paths(paths).items():
        out.setdefault((height, placement), []).extend(files)
    return out


def sorted_cells(cells: Iterable[tuple]) -> list[tuple]:
    """``(height, placement)`` cells in the tables' order: by height, then no_low_cabinets, everywhere, others."""
    order = {"no_low_cabinets": 0, "everywhere": 1}
    return sorted(cells, key=lambda c: (float(c[0]), order.get(c[1], 2), str(c[1])))


def output_base(out_prefix: PathLike, default_name: str) -> Path:
    """Where outputs go: ``out_prefix`` names a directory (an existing one, or given with a trailing ``/``) ->
    ``dir/default_name``; otherwise it is the prefix itself (``out/table1`` -> ``out/table1.csv``, ``.md``...).
    Parent directories are created."""
    raw = os.fspath(out_prefix)
    p = Path(raw)
    base = p / default_name if (raw.endswith(("/", os.sep)) or p.is_dir()) else p
    base.parent.mkdir(parents=True, exist_ok=True)
    return base


def suffixed(base: Path, ext: str) -> Path:
    """``base`` with ``ext`` added to its name: ``out/h1.65`` -> ``out/h1.65.csv`` (``with_suffix`` drops ``.65``)."""
    return base.with_name(base.name + ext)


def counts_decisions(curve_path: str | os.PathLike) -> bool:
    """Whether the training beside ``curve_path`` is a modular searcher's, whose env steps are decisions (its
    ``config.json``'s ``modular_searcher``, or its env id for runs stored before that field)."""
    try:
        stored = json.loads((Path(curve_path).parent / "config.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    # runs stored before the field: their env id is one of the decision envs (the ids the modular floors are of)
    return bool(stored.get("config", {}).get("modular_searcher")) or stored.get("env_id") in modular_floors()
