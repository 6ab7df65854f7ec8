"""Train SAC + CURL on an egosearch env, resumably; and ``ActorPolicy`` to run the result.

``train(env_id, cfg, out_dir)`` writes into ``out_dir``:

- ``config.json``: the whole config (also printed at start);
- ``curve.csv``: one row per evaluation (every ``eval_every`` env steps, at step 0 and at the
  end) with the fixed columns :data:`CURVE_COLUMNS`;
- ``train.csv``: one row every ``log_every`` env steps with :data:`TRAIN_COLUMNS`;
- ``ckpt/train_state.ckpt``: the resumable state (agent + optimisers + replay + RNG states + step
  counter + CSV row counts), rewritten atomically every ``checkpoint_every`` env steps and
  deleted at the end unless ``cfg.keep_checkpoint`` (it holds the replay buffer: up to ~1 GB,
  never commit it);
- ``actor.pt``: actor-only weights + metadata (variant, env_id, config), readable with
  ``torch.load(weights_only=True)``; load it with :class:`ActorPolicy`;
- ``done.json``: written last; its presence means the run is complete.

Killing the process at any moment and running the same call again resumes from the last
checkpoint: CSV rows written after that checkpoint are dropped and recomputed, so the CSVs end up
with neither duplicate nor missing rows. Every env's episode is cut (counted as truncated) at each
checkpoint, in the uninterrupted run as in the resumed one, so a resumed run equals the run that
was not stopped. Every file is written atomically (temp file in the same
folder, fsync, ``os.replace``).
"""

from __future__ import annotations

import json
import math
import os
import random
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import torch

from egosearch.machine import cpu_model
from egosearch.rl.config import SacCurlConfig
from egosearch.rl.replay import MultiReplay
from egosearch.rl.sac_curl import (
    METRIC_KEYS,
    AgentStateError,
    SacCurlAgent,
    load_actor_net,
    obs_to_tensors,
    resolve_device,
)

CHECKPOINT_FORMAT = "egosearch-sac-curl-checkpoint-v1"
CHECKPOINT_NAME = Path("ckpt") / "train_state.ckpt"
"""The resumable state inside ``out_dir`` (``*.ckpt`` is git-ignored: it holds the replay)."""
CURVE_COLUMNS = ("env_steps", "success_rate", "spl", "episode_return", "critic_loss", "actor_loss",
                 "curl_loss", "alpha", "entropy", "steps_per_s", "updates_per_s", "wall_s")
TRAIN_COLUMNS = ("env_steps", "episodes", "updates", "train_return", "train_success", "critic_loss",
                 "actor_loss", "alpha_loss", "curl_loss", "alpha", "entropy", "q_mean", "steps_per_s",
                 "updates_per_s", "wall_s")
_ALGORITHM_NAMES = {"sac_curl": "SAC+CURL", "sac_drq": "SAC-DrQ"}
EVAL_SEED_BASE = 1_000_000
"""Default evaluation: episode i is ``reset(seed=EVAL_SEED_BASE + i)``, the same at every
evaluation, for every training seed and variant."""
RESUMABLE_FIELDS = ("device", "num_threads", "compile", "keep_checkpoint")
"""Config fields that may differ between a checkpoint and the run resuming it."""


class CheckpointError(RuntimeError):
    """A checkpoint / finished run in ``out_dir`` is unreadable or belongs to another run."""


# ---- small utilities ----------------------------------------------------------------------

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
            values.append(str(int(v)) if isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                          else repr(float(v)))
        with open(self.path, "a") as f:
            f.write(",".join(values) + "\n")
            f.flush()
            os.fsync(f.fileno())


class _Mean:
    """Running nan-mean of update metrics since the last reset."""

    def __init__(self):
        self.sums: dict[str, float] = {}
        self.counts: dict[str, int] = {}

    def add(self, metrics: dict[str, float]) -> None:
        for k, v in metrics.items():
            if v == v:  # not NaN
                self.sums[k] = self.sums.get(k, 0.0) + v
                self.counts[k] = self.counts.get(k, 0) + 1

    def mean(self) -> dict[str, float]:
        return {k: self.sums.get(k, 0.0) / self.counts[k] if self.counts.get(k) else float("nan")
                for k in METRIC_KEYS}


# ---- policies -----------------------------------------------------------------------------

class AgentPolicy:
    """The live agent behind the shared policy interface (deterministic actions)."""

    def __init__(self, agent):
        self.agent = agent

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: dict) -> np.ndarray:
        return self.agent.act(obs, deterministic=True)


def load_any_actor_net(state: dict, device) -> torch.nn.Module:
    """An actor file's network, SAC+CURL's or SAC-DrQ's (by its ``format``)."""
    from egosearch.rl import sac_drq

    if isinstance(state, dict) and state.get("format") == sac_drq.ACTOR_FORMAT:
        return sac_drq.load_drq_actor_net(state, device)
    return load_actor_net(state, device)


class ActorPolicy:
    """A trained actor (``actor.pt``) behind the project's policy interface:
    ``reset(seed=None)`` (no-op: the actor is memoryless given the env's frame history) and
    ``act(obs) -> np.ndarray`` (deterministic: tanh of the Gaussian mean, in [-1, 1])."""

    def __init__(self, path: str | os.PathLike, device: str = "auto"):
        path = Path(path)
        # torch's own message for a non-torch file advises weights_only=False, which is wrong here.
        not_actor = (f"{path} is not an egosearch actor file; an actor file is the actor.pt that "
                     "`egosearch train` writes (results/<profile>/train/<variant>/seed<N>/actor.pt)")
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such actor file" if not path.exists() else not_actor)
        try:
            state = torch.load(path, map_location="cpu", weights_only=True)
        except Exception as err:  # noqa: BLE001 - any unreadable file gets one line
            raise AgentStateError(f"{not_actor} (torch cannot read it: {type(err).__name__})") from None
        if not isinstance(state, dict) or "format" not in state:
            raise AgentStateError(not_actor)
        self.device = resolve_device(device)
        try:
            self.net = load_any_actor_net(state, self.device)
        except AgentStateError as err:
            raise AgentStateError(f"{path}: {err}") from None
        self.arch = state["arch"]
        self.metadata = state.get("metadata", {})
        self.variant = self.metadata.get("variant")
        self.env_id = self.metadata.get("env_id")
        self.config = self.metadata.get("config")
        self.action_dim = int(self.arch["action_dim"])

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: dict) -> np.ndarray:
        with torch.inference_mode():
            depth, extra = obs_to_tensors(obs, self.device, self.arch["crop_size"])
            mu, _ = self.net(depth.float(), extra)
            return torch.tanh(mu)[0].cpu().numpy().astype(np.float32)


# ---- evaluation ---------------------------------------------------------------------------

def default_evaluator(env_id: str, env_kwargs: dict, episodes: int) -> Callable[[Any], dict]:
    """``evaluate(policy) -> {success_rate, spl, episode_return}`` over ``episodes`` episodes of
    a separate env instance with the fixed seeds ``EVAL_SEED_BASE + i``. Success = the episode
    ended with ``terminated``; SPL is averaged from ``info["spl"]`` when the env reports it
    (else NaN: the env team's evaluator computes it on the held-out scenarios)."""
    holder: dict[str, Any] = {}

    def evaluate(policy) -> dict[str, float]:
        if "env" not in holder:
            holder["env"] = gymnasium.make(env_id, **env_kwargs)
        env = holder["env"]
        successes, returns, spls = [], [], []
        for i in range(episodes):
            obs, info = env.reset(seed=EVAL_SEED_BASE + i)
            policy.reset(seed=EVAL_SEED_BASE + i)
            total, terminated, truncated = 0.0, False, False
            while not (terminated or truncated):
                obs, reward, terminated, truncated, info = env.step(policy.act(obs))
                total += float(reward)
            successes.append(float(terminated))
            returns.append(total)
            if "spl" in info:
                spls.append(float(info["spl"]))
        return {"success_rate": float(np.mean(successes)),
                "spl": float(np.mean(spls)) if spls else float("nan"),
                "episode_return": float(np.mean(returns))}

    evaluate.close = lambda: holder.pop("env").close() if "env" in holder else None  # type: ignore[attr-defined]
    return evaluate


# ---- checkpoint helpers -------------------------------------------------------------------

def _to_tensors(obj: Any) -> Any:
    """numpy arrays -> torch tensors (so ``weights_only=True`` can read the checkpoint)."""
    if isinstance(obj, np.ndarray):
        return torch.from_numpy(np.ascontiguousarray(obj))
    if isinstance(obj, dict):
        return {k: _to_tensors(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_to_tensors(v) for v in obj]
    return obj


def _to_numpy(obj: Any) -> Any:
    if isinstance(obj, torch.Tensor):
        return obj.numpy()
    if isinstance(obj, dict):
        return {k: _to_numpy(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_to_numpy(v) for v in obj]
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


def _rng_states(envs) -> dict:
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


def _restore_rng_states(states: dict, envs) -> None:
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


def _describe(err: BaseException) -> str:
    text = str(err).strip().splitlines()
    return f"{type(err).__name__}: {text[0] if text else ''}"


def load_checkpoint(path: Path) -> dict:
    """Read a checkpoint (``weights_only=True``); unreadable -> one-line ``CheckpointError``."""
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # noqa: BLE001
        raise CheckpointError(f"cannot read checkpoint {path} ({_describe(err)}); delete it to "
                              "start over") from None
    if not isinstance(state, dict) or state.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not a SAC+CURL training checkpoint")
    return state


def _kwargs_key(env_kwargs: dict) -> str:
    return repr(sorted(env_kwargs.items()))


def _check_same_run(what: str, path: Path, saved: dict, variant: str, env_id: str, env_kwargs: dict,
                    cfg: SacCurlConfig) -> None:
    if saved.get("variant") != variant or saved.get("env_id") != env_id:
        raise CheckpointError(f"{path} belongs to variant={saved.get('variant')!r} env_id={saved.get('env_id')!r}, "
                              f"not variant={variant!r} env_id={env_id!r}; use another out_dir")
    if saved.get("env_kwargs") != _kwargs_key(env_kwargs):
        raise CheckpointError(f"{what} {path} was written with env_kwargs {saved.get('env_kwargs')}, "
                              f"not {_kwargs_key(env_kwargs)}; use another out_dir")
    mine, theirs = cfg.to_dict(), saved.get("config", {})
    diff = sorted(k for k in set(mine) | set(theirs) if k not in RESUMABLE_FIELDS and mine.get(k) != theirs.get(k))
    if diff:
        shown = ", ".join(f"{k}={theirs.get(k)!r} (now {mine.get(k)!r})" for k in diff[:4])
        raise CheckpointError(f"{what} {path} was written with a different config: {shown}"
                              f"{' ...' if len(diff) > 4 else ''}; use another out_dir")


def _env_spaces(env, cfg: SacCurlConfig) -> tuple[int, int, int]:
    space = env.observation_space
    try:
        depth, mask, proprio = space["depth"], space["mask"], space["proprio"]
    except (KeyError, TypeError):
        raise ValueError(f"observation space must be a Dict with depth, mask, proprio; got {space}") from None
    want = (cfg.frame_history, cfg.image_size, cfg.image_size)
    if tuple(depth.shape) != want or depth.dtype != np.uint8:
        raise ValueError(f"env depth is {tuple(depth.shape)} {depth.dtype}; config expects {want} uint8 "
                         "(frame_history, image_size)")
    if proprio.shape[0] != 2 * (1 + cfg.head_history):
        raise ValueError(f"env proprio has {proprio.shape[0]} values; head_history={cfg.head_history} "
                         f"expects {2 * (1 + cfg.head_history)}")
    act = env.action_space
    if not isinstance(act, gymnasium.spaces.Box) or len(act.shape) != 1:
        raise ValueError(f"action space must be a 1-d Box, got {act}")
    if not (np.allclose(act.low, -1) and np.allclose(act.high, 1)):
        raise ValueError("action space must be Box(-1, 1): the actor's tanh output is not rescaled")
    return int(act.shape[0]), int(mask.shape[0]), int(proprio.shape[0])


def keep_freed_memory() -> bool:
    """Ask glibc to keep freed blocks of up to 32 MB instead of returning them to the OS.

    Every update allocates and frees the same few-MB tensors; with glibc's defaults each one is a
    fresh mmap whose pages fault in again, which measured ~1/3 of a small update's time here
    (page faults 4x fewer with this). Same numbers either way. False where glibc is absent."""
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    if not name or os.name != "posix":
        return False
    try:
        libc = ctypes.CDLL(name)
        m_trim_threshold, m_mmap_threshold = -1, -3
        return bool(libc.mallopt(m_mmap_threshold, 32 * 1024 * 1024) and libc.mallopt(m_trim_threshold, 1 << 30))
    except (OSError, AttributeError):
        return False


def torch_threads(requested: int = 0) -> int:
    """``requested`` or, for 0, every core this process may run on."""
    if requested:
        return requested
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def _make_env(env_id: str, env_kwargs: dict):
    if env_id not in gymnasium.registry:
        try:
            import egosearch.envs  # noqa: F401  (registers the EgoSearch ids)
        except ImportError:
            pass
    if env_kwargs.get("layout") in ("generated", "paper_homes"):  # several homes (egosearch.home_pool)
        from egosearch.home_pool import HomePoolEnv
        from egosearch.scene.layouts import LAYOUT_NAMES

        if env_kwargs["layout"] == "paper_homes":
            return HomePoolEnv(env_id, home_names=LAYOUT_NAMES, **env_kwargs)
        return HomePoolEnv(env_id, **env_kwargs)
    return gymnasium.make(env_id, **env_kwargs)


# ---- training -----------------------------------------------------------------------------

def train(env_id: str, cfg: SacCurlConfig, out_dir: str | os.PathLike, env_kwargs: dict | None = None,
          evaluate_fn: Callable[[Any], dict] | None = None, *, variant: str | None = None,
          progress: bool = True, on_step: Callable[[int], None] | None = None) -> dict:
    """Train (or resume, or return at once if ``done.json`` is there) and return the summary.

    ``evaluate_fn(policy) -> dict`` with success_rate, spl, episode_return is called every
    ``cfg.eval_every`` env steps (default: :func:`default_evaluator`). ``variant`` names the run
    in the checkpoint / actor metadata (default: ``env_id``). ``on_step(env_steps)`` is called
    after every env step (tests use it to interrupt a run).
    """
    cfg = cfg.validate()
    env_kwargs = dict(env_kwargs or {})
    out_dir = Path(out_dir)
    variant = variant or env_id
    ckpt_path = out_dir / CHECKPOINT_NAME
    done_path = out_dir / "done.json"

    # -- a finished run, or a checkpoint to resume: validated before anything is written ----
    if done_path.exists():
        try:
            done = json.loads(done_path.read_text())
        except (OSError, ValueError) as err:
            raise CheckpointError(f"cannot read {done_path} ({_describe(err)})") from None
        _check_same_run("finished run", done_path, done, variant, env_id, env_kwargs, cfg)
        return done
    ours = {CHECKPOINT_NAME.name, "actor.pt", "done.json", "config.json", "curve.csv", "train.csv"}
    for stale in [*out_dir.glob(".tmp*"), *(out_dir / CHECKPOINT_NAME.parent).glob(".tmp*")]:
        if stale.name.split(".", 2)[-1] in ours:  # temp files of a killed run of ours
            stale.unlink()
    ckpt = load_checkpoint(ckpt_path) if ckpt_path.exists() else None
    if ckpt is not None:
        _check_same_run("checkpoint", ckpt_path, ckpt, variant, env_id, env_kwargs, cfg)

    threads_before = torch.get_num_threads()
    torch.set_num_threads(torch_threads(cfg.num_threads))
    keep_freed_memory()
    envs: list = []
    try:
        for _ in range(cfg.num_envs):
            envs.append(_make_env(env_id, train_env_kwargs(cfg, env_kwargs)))
        return _train(envs, env_id, cfg, out_dir, env_kwargs, evaluate_fn, variant, progress, on_step, ckpt)
    finally:
        for env in envs:
            env.close()
        torch.set_num_threads(threads_before)


def train_env_kwargs(cfg: SacCurlConfig, env_kwargs: dict) -> dict:
    """The training envs' keyword arguments: the variant's, with r_d's form
    (``train_distance_reward``) and the training heights (``train_height_min``) from the learner
    config unless the variant sets ``distance_reward`` / ``train_heights`` itself, and the
    privileged state when the critic reads it (``critic_privileged_state``). The paper's values are
    the env's defaults, so they are not passed (envs without the options still train)."""
    from egosearch.agent import AgentSpec

    aids: dict = {}
    if cfg.train_distance_reward != "distance":
        aids["distance_reward"] = cfg.train_distance_reward
    paper_low, paper_high = AgentSpec().train_height_range
    if cfg.train_height_min != paper_low:
        aids["train_heights"] = (cfg.train_height_min, paper_high)
    if cfg.critic_privileged_state:
        aids["privileged_state"] = True
    return {**aids, **env_kwargs}


def make_agent(cfg: SacCurlConfig, action_dim: int, mask_dim: int, proprio_dim: int, device,
               state_dim: int = 0):
    """The learner ``cfg.algorithm`` names (both share act / update / state_dict / actor_state);
    ``state_dim``: size of the env's privileged state (``critic_privileged_state``)."""
    if cfg.algorithm == "sac_drq":
        from egosearch.rl.sac_drq import SacDrqAgent

        return SacDrqAgent(cfg, action_dim, mask_dim, proprio_dim, device=device, state_dim=state_dim)
    return SacCurlAgent(cfg, action_dim, mask_dim, proprio_dim, device=device)


def _act_batch(agent, observations: list[dict]) -> list[np.ndarray]:
    if len(observations) == 1 or not hasattr(agent, "act_batch"):
        return [agent.act(o, deterministic=False) for o in observations]
    stacked = {k: np.stack([o[k] for o in observations]) for k in observations[0]}
    return list(agent.act_batch(stacked, deterministic=False))


def _train(envs: list, env_id: str, cfg: SacCurlConfig, out_dir: Path, env_kwargs: dict, evaluate_fn, variant: str,
           progress: bool, on_step, ckpt: dict | None) -> dict:
    ckpt_path = out_dir / CHECKPOINT_NAME
    done_path = out_dir / "done.json"
    device = resolve_device(cfg.device)
    random.seed(cfg.seed)
    np.random.seed(cfg.seed)
    torch.manual_seed(cfg.seed)
    env = envs[0]
    action_dim, mask_dim, proprio_dim = _env_spaces(env, cfg)
    state_dim = 0
    if cfg.critic_privileged_state:
        if "state" not in env.observation_space.spaces:
            raise ValueError(f"critic_privileged_state needs an env whose observations hold a 'state' "
                             f"entry (privileged_state=True); {env_id} gives none")
        state_dim = int(env.observation_space["state"].shape[0])
    for i, e in enumerate(envs):
        e.action_space.seed(cfg.seed + 7 * i)
    agent = make_agent(cfg, action_dim, mask_dim, proprio_dim, device, state_dim)
    to_replay = getattr(agent, "replay_obs", lambda o: o)
    replay = MultiReplay(cfg.num_envs, cfg.replay_capacity, getattr(agent, "replay_image_size", cfg.image_size),
                         cfg.frame_history, mask_dim, proprio_dim, action_dim, n_step=cfg.n_step, gamma=cfg.gamma,
                         device=device, seed=cfg.seed, state_dim=state_dim)
    curve = CsvLogger(out_dir / "curve.csv", CURVE_COLUMNS)
    train_log = CsvLogger(out_dir / "train.csv", TRAIN_COLUMNS)

    step, episodes, wall_before = 0, 0, 0.0
    recent: deque[tuple[float, float]] = deque(maxlen=20)  # (return, success) of train episodes
    if ckpt is not None:
        try:
            agent.load_state_dict(ckpt["agent"])
            replay.load_state_dict(_to_numpy(ckpt["replay"]))
            _restore_rng_states(ckpt["rng"], envs)
        except (AgentStateError, ValueError, KeyError, RuntimeError) as err:
            raise CheckpointError(f"checkpoint {ckpt_path} does not fit this run ({_describe(err)})") from None
        step, episodes, wall_before = int(ckpt["env_steps"]), int(ckpt["episodes"]), float(ckpt["wall_s"])
        recent.extend((float(r), float(s)) for r, s in ckpt["recent"])
        curve.truncate(int(ckpt["csv_rows"]["curve"]))
        train_log.truncate(int(ckpt["csv_rows"]["train"]))
        # The run that was not stopped cut its episodes here too (see restart_episodes below).
        replay.end_episodes()
        reset_seeds = [cfg.seed + 7919 * step + 104_729 * i for i in range(len(envs))]
    else:
        curve.truncate(0)
        train_log.truncate(0)
        reset_seeds = [cfg.seed + 104_729 * i for i in range(len(envs))]
    def reset(e, seed=None):
        radius = cfg.start_radius(step)
        return e.reset(seed=seed, options=None if radius is None else {"start_radius": radius})[0]

    observations = [reset(e, sd) for e, sd in zip(envs, reset_seeds)]
    stored = [to_replay(o) for o in observations]  # as the replay stores them, each computed once
    ep_returns = [0.0] * len(envs)

    def restart_episodes() -> None:
        """Cut every env's episode at a checkpoint and reset it with a seed of the step, exactly as
        a run resumed from that checkpoint does: so killing and resuming gives the same run as not
        stopping (the cut transitions count as truncated, so they still bootstrap)."""
        replay.end_episodes()
        for i, e in enumerate(envs):
            observations[i] = reset(e, cfg.seed + 7919 * step + 104_729 * i)
            stored[i] = to_replay(observations[i])
            ep_returns[i] = 0.0
    del ckpt
    atomic_json(out_dir / "config.json", {"variant": variant, "env_id": env_id,
                                          "env_kwargs": _kwargs_key(env_kwargs), "config": cfg.to_dict()})

    own_eval = evaluate_fn is None
    evaluate_fn = evaluate_fn or default_evaluator(env_id, env_kwargs, cfg.eval_episodes)
    policy = AgentPolicy(agent)
    threads = torch.get_num_threads()
    say = print
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=cfg.total_env_steps, initial=step, unit="step", dynamic_ncols=True,
                   mininterval=1.0, desc=f"{variant} seed {cfg.seed}")
        say = bar.write
    say(f"{_ALGORITHM_NAMES[cfg.algorithm]} {variant} on {env_id} -> {out_dir} | device {device}, "
        f"{threads} torch threads, {cfg.num_envs} env(s) | "
        f"{'resuming at step ' + str(step) if step else 'fresh start'}")
    say("config: " + json.dumps(cfg.to_dict(), sort_keys=True))

    t_start = time.perf_counter()
    marks = {"curve": (step, agent.num_updates, t_start, 0.0), "train": (step, agent.num_updates, t_start, 0.0)}
    eval_time = 0.0
    means = {"curve": _Mean(), "train": _Mean()}

    def wall() -> float:
        return wall_before + time.perf_counter() - t_start

    def rates(key: str) -> tuple[float, float]:
        s0, u0, t0, e0 = marks[key]
        dt = max(time.perf_counter() - t0 - (eval_time - e0), 1e-9)
        marks[key] = (step, agent.num_updates, time.perf_counter(), eval_time)
        if step == s0:
            return float("nan"), float("nan")
        return (step - s0) / dt, (agent.num_updates - u0) / dt

    def do_eval() -> dict:
        nonlocal eval_time
        t0 = time.perf_counter()
        result = evaluate_fn(policy)
        eval_time += time.perf_counter() - t0
        sps, ups = rates("curve")
        m = means["curve"].mean()
        means["curve"] = _Mean()
        row = {"env_steps": step, "success_rate": result.get("success_rate", float("nan")),
               "spl": result.get("spl", float("nan")), "episode_return": result.get("episode_return", float("nan")),
               "critic_loss": m["critic_loss"], "actor_loss": m["actor_loss"], "curl_loss": m["curl_loss"],
               "alpha": agent.alpha, "entropy": m["entropy"], "steps_per_s": sps, "updates_per_s": ups,
               "wall_s": wall()}
        curve.write(row)
        say(f"eval @ {step}: success {row['success_rate']:.3f}  return {row['episode_return']:.2f}  "
            f"spl {row['spl']:.3f}  ({sps:.1f} steps/s, {ups:.1f} updates/s)")
        return row

    def save_checkpoint() -> None:
        state = {
            "format": CHECKPOINT_FORMAT, "variant": variant, "env_id": env_id,
            "env_kwargs": _kwargs_key(env_kwargs), "config": cfg.to_dict(),
            "env_steps": step, "episodes": episodes, "wall_s": wall(),
            "csv_rows": {"curve": curve.rows(), "train": train_log.rows()},
            "recent": [list(x) for x in recent],
            "agent": agent.state_dict(), "replay": _to_tensors(replay.state_dict()), "rng": _rng_states(envs),
        }
        atomic_write(ckpt_path, lambda f: torch.save(state, f))

    last_row = None
    try:
        if step == 0 and curve.rows() == 0:
            last_row = do_eval()
        def crossed(every: int, before: int) -> bool:
            return step // every > before // every or step == cfg.total_env_steps

        while step < cfg.total_env_steps:
            before = step
            live = envs[: cfg.total_env_steps - step]  # the last round may need fewer envs
            if step < cfg.init_steps:
                actions = [e.action_space.sample() for e in live]
            else:
                actions = _act_batch(agent, observations[: len(live)])
            for i, (e, action) in enumerate(zip(live, actions)):
                next_obs, reward, terminated, truncated, info = e.step(action)
                next_stored = to_replay(next_obs)
                replay.add(i, stored[i], action, reward, next_stored, terminated, truncated)
                step += 1
                ep_returns[i] += float(reward)
                if terminated or truncated:
                    episodes += 1
                    recent.append((ep_returns[i], float(terminated)))
                    ep_returns[i] = 0.0
                    observations[i] = reset(e)
                    stored[i] = to_replay(observations[i])
                else:
                    observations[i], stored[i] = next_obs, next_stored
            if step >= cfg.init_steps:
                first_due = max(before, cfg.init_steps - 1)
                for _ in range((step // cfg.update_every - first_due // cfg.update_every) * cfg.updates_per_step):
                    metrics = agent.update(replay.sample(cfg.batch_size))
                    means["curve"].add(metrics)
                    means["train"].add(metrics)
            if step // cfg.log_every > before // cfg.log_every:
                sps, ups = rates("train")
                m = means["train"].mean()
                means["train"] = _Mean()
                ret = float(np.mean([r for r, _ in recent])) if recent else float("nan")
                succ = float(np.mean([s for _, s in recent])) if recent else float("nan")
                train_log.write({"env_steps": step, "episodes": episodes, "updates": agent.num_updates,
                                 "train_return": ret, "train_success": succ, **m, "alpha": agent.alpha,
                                 "steps_per_s": sps, "updates_per_s": ups, "wall_s": wall()})
                if bar is not None:
                    bar.set_postfix(success=f"{succ:.2f}", ret=f"{ret:.1f}", ups=f"{ups:.1f}", refresh=False)
            if crossed(cfg.eval_every, before):
                last_row = do_eval()
            if crossed(cfg.checkpoint_every, before):
                save_checkpoint()
                if step < cfg.total_env_steps:
                    restart_episodes()
            if bar is not None:
                bar.update(step - before)
            if on_step is not None:
                on_step(step)
    finally:
        if bar is not None:
            bar.close()
        if own_eval:
            evaluate_fn.close()

    if last_row is None:  # resumed exactly at the end: the last curve row is already written
        import csv

        with open(curve.path) as f:
            rows = list(csv.DictReader(f))
        last_row = {k: float(v) for k, v in rows[-1].items()} if rows else {}
    meta = {"variant": variant, "env_id": env_id, "env_kwargs": _kwargs_key(env_kwargs),
            "config": cfg.to_dict(), "env_steps": step,
            "updates": agent.num_updates, "seed": cfg.seed, "torch": str(torch.__version__)}
    atomic_write(out_dir / "actor.pt", lambda f: torch.save(agent.actor_state(meta), f))
    summary = {"variant": variant, "env_id": env_id, "env_kwargs": _kwargs_key(env_kwargs),
               "env_steps": step, "updates": agent.num_updates,
               "episodes": episodes, "wall_s": round(wall(), 3), "actor": "actor.pt",
               "final_eval": {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in last_row.items()},
               # wall_s is core time only on the machine that ran it: the budget study shows which
               "machine": {"cpu": cpu_model(), "cores": os.cpu_count()},
               "config": cfg.to_dict()}
    atomic_json(done_path, summary)
    if not cfg.keep_checkpoint and ckpt_path.exists():
        ckpt_path.unlink()
        try:
            ckpt_path.parent.rmdir()
        except OSError:  # not empty: leave other files alone
            pass
    return summary
