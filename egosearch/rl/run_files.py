"""A training run's files: atomic writes, the fixed-column CSV logger, and the resumable checkpoint
(its format, the RNG states it carries, and the checks that it belongs to the run resuming it).

:mod:`egosearch.rl.train` runs the loop that writes them; nothing here knows a learner.
"""

from __future__ import annotations

import json
import os
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch

from egosearch.envs import ALL_ENV_IDS, env_options
from egosearch.rl.config import RESUMABLE_FIELDS, LearnerConfig, field_defaults, format_set, identity_set

CHECKPOINT_FORMAT = "egosearch-sac-curl-checkpoint-v1"




class CheckpointError(RuntimeError):
    """A checkpoint / finished run in ``out_dir`` is unreadable or belongs to another run."""


def atomic_write(path: Path, write: Callable[[Any], None], mode: str = "wb") -> None:
    """Write ``path`` via a temp file in the same folder, fsync, ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".tmp{os.getpid()}.{path.name}")  # same suffix: same ignore rules
    try:
        with open(tmp, mode) as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    try:  # make the rename itself durable
        fd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError:
        pass


def atomic_json(path: Path, obj: Any) -> None:
    atomic_write(path, lambda f: f.write(json.dumps(obj, indent=2, sort_keys=True) + "\n"), mode="w")


class CsvLogger:
    """A fixed-column CSV (DrQ-v2 style): header once, one row per ``write``, flushed and fsynced.

    Values are written with ``repr``-precision floats; NaN for missing metrics. ``truncate(n)``
    keeps the header and the first ``n`` rows (used on resume)."""

    def __init__(self, path: Path, columns: tuple[str, ...]):
        self.path, self.columns = Path(path), tuple(columns)
        self.header = ",".join(self.columns)

    def rows(self) -> int:
        if not self.path.exists():
            return 0
        with open(self.path) as f:
            lines = [line for line in f.read().splitlines() if line]
        return max(0, len(lines) - 1)

    def truncate(self, n_rows: int) -> None:
        lines: list[str] = []
        if self.path.exists():
            with open(self.path) as f:
                lines = [line for line in f.read().splitlines() if line]
            if lines and lines[0] != self.header:
                raise CheckpointError(f"{self.path} has columns {lines[0]!r}, expected {self.header!r}")
        body = lines[1:1 + n_rows]
        if len(body) < n_rows:
            raise CheckpointError(f"{self.path} has {len(body)} rows but the checkpoint expects {n_rows}")
        atomic_write(self.path, lambda f: f.write("\n".join([self.header] + body) + "\n"), mode="w")

    def write(self, row: dict[str, Any]) -> None:
        extra = set(row) - set(self.columns)
        if extra:
            raise ValueError(f"{self.path.name}: unknown column(s) {sorted(extra)}")
        values = []
        for c in self.columns:
            v = row.get(c, float("nan"))
            if isinstance(v, str):  # a name (a home): the writer's own columns never hold commas
                values.append(v)
                continue
            values.append(str(int(v)) if isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                          else repr(float(v)))
        with open(self.path, "a") as f:
            f.write(",".join(values) + "\n")
            f.flush()
            os.fsync(f.fileno())


def to_tensors(obj: Any) -> Any:
    """numpy arrays -> torch tensors (so ``weights_only=True`` can read the checkpoint)."""
    if isinstance(obj, np.ndarray):
        return torch.from_numpy(np.ascontiguousarray(obj))
    if isinstance(obj, dict):
        return {k: to_tensors(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [to_tensors(v) for v in obj]
    return obj


def to_numpy(obj: Any) -> Any:
    if isinstance(obj, torch.Tensor):
        return obj.numpy()
    if isinstance(obj, dict):
        return {k: to_numpy(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [to_numpy(v) for v in obj]
    return obj


def _plain_bitgen_state(state: dict) -> dict:
    """numpy bit-generator state with its (128-bit) ints as strings: pickle-safe, plain."""
    out: dict[str, Any] = {}
    for k, v in state.items():
        if isinstance(v, dict):
            out[k] = _plain_bitgen_state(v)
        elif isinstance(v, int) and not isinstance(v, bool):
            out[k] = str(v)
        else:
            out[k] = v
    return out


def _from_plain_bitgen_state(state: dict) -> dict:
    out: dict[str, Any] = {}
    for k, v in state.items():
        if isinstance(v, dict):
            out[k] = _from_plain_bitgen_state(v)
        elif isinstance(v, str) and k != "bit_generator":
            out[k] = int(v)
        else:
            out[k] = v
    return out


def rng_states(envs) -> dict:
    np_state = np.random.get_state()
    states = {
        "torch": torch.get_rng_state(),
        "numpy": {"key": torch.from_numpy(np_state[1].astype(np.int64)), "pos": int(np_state[2]),
                  "has_gauss": int(np_state[3]), "cached_gaussian": float(np_state[4])},
        "python": random.getstate(),
        "action_space": _plain_bitgen_state(envs[0].action_space.np_random.bit_generator.state),
    }
    if len(envs) > 1:
        states["action_spaces"] = [_plain_bitgen_state(e.action_space.np_random.bit_generator.state) for e in envs]
    if torch.cuda.is_available():
        states["cuda"] = torch.cuda.get_rng_state_all()
    return states


def restore_rng_states(states: dict, envs) -> None:
    torch.set_rng_state(states["torch"])
    n = states["numpy"]
    np.random.set_state(("MT19937", n["key"].numpy().astype(np.uint32), n["pos"], n["has_gauss"],
                         n["cached_gaussian"]))
    version, internal, gauss = states["python"]
    random.setstate((version, tuple(internal), gauss))
    envs[0].action_space.np_random.bit_generator.state = _from_plain_bitgen_state(states["action_space"])
    for e, state in zip(envs[1:], states.get("action_spaces", [])[1:]):
        e.action_space.np_random.bit_generator.state = _from_plain_bitgen_state(state)
    if "cuda" in states and torch.cuda.is_available():
        torch.cuda.set_rng_state_all(states["cuda"])


def describe_error(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0] if text else ''}"


def load_checkpoint(path: Path) -> dict:
    """Read a checkpoint (``weights_only=True``); unreadable -> one-line ``CheckpointError``."""
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # noqa: BLE001
        raise CheckpointError(f"cannot read checkpoint {path} ({describe_error(err)}); delete it to "
                              "start over") from None
    if not isinstance(state, dict) or state.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not an egosearch training checkpoint")
    return state


def env_kwargs_key(env_kwargs: dict) -> str:
    return repr(sorted(env_kwargs.items()))


def check_same_run(what: str, path: Path, saved: dict, variant: str, env_id: str, env_kwargs: dict,
                    cfg: LearnerConfig, set_overrides: dict | None = None) -> None:
    """A checkpoint or finished run (``saved``) is the run asked for: its variant and env id, its training env, its
    ``--set`` overrides and its config (but the fields a resume may change), else one-line ``CheckpointError``."""
    if saved.get("variant") != variant or saved.get("env_id") != env_id:
        raise CheckpointError(f"{path} belongs to variant={saved.get('variant')!r} env_id={saved.get('env_id')!r}, "
                              f"not variant={variant!r} env_id={env_id!r}; use another out_dir")
    theirs_set, mine_set = identity_set(saved.get("set") or {}), identity_set(set_overrides or {})
    if theirs_set != mine_set:
        # refused even where the configs agree (a --set of a value the variant already has): the run's record
        # would name overrides it was not trained with
        raise CheckpointError(f"{what} {path} was trained with --set {format_set(theirs_set) or 'none'}, not "
                              f"{format_set(mine_set) or 'none'}; give the same --set to resume it, or use another "
                              "out_dir")
    if saved.get("env_kwargs") != env_kwargs_key(env_kwargs):
        raise CheckpointError(f"{what} {path} was written with env_kwargs {saved.get('env_kwargs')}, "
                              f"not {env_kwargs_key(env_kwargs)}; use another out_dir")
    theirs = saved_config(saved)
    mine = cfg.to_dict()
    # the env id, compared above, is what these two fields select (observed_env_id): a run stored under its
    # *Memory-v0 id observed the memory whatever its flag said. Only the fields of this config's learner are
    # compared: a run stored before the config was split also recorded other learners' fields, never read
    diff = sorted(k for k in mine
                  if k not in RESUMABLE_FIELDS + ENV_ID_FIELDS and mine.get(k) != theirs.get(k))
    if diff:
        shown = ", ".join(f"{k}={theirs.get(k)!r} (now {mine.get(k)!r})" for k in diff[:4])
        raise CheckpointError(f"{what} {path} was written with a different config: {shown}"
                              f"{' ...' if len(diff) > 4 else ''}; use another out_dir")


ENV_ID_FIELDS = ("target_memory", "modular_searcher")
"""Config fields whose whole effect is the env id a run observes (``observed_env_id``)."""


def saved_config(saved: dict) -> dict:
    """The config a checkpoint or done.json ran with, fields added after it was stored at their defaults."""
    # a field added after the run was stored: the run ran as its default (each new field's default is its "off")
    theirs = {**field_defaults(), **saved.get("config", {})}
    env_id = str(saved.get("env_id"))
    # runs saved before these fields existed named them in their env id only: read them from the id's table
    options = env_options(env_id) if env_id in ALL_ENV_IDS else None
    recorded = saved.get("config", {})
    if "modular_searcher" not in recorded:
        theirs["modular_searcher"] = bool(options and options.modular)
    if "target_memory" not in recorded:
        theirs["target_memory"] = bool(options and options.target_memory)
    return theirs
