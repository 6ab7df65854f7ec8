"""Demonstrations from the classical searcher: the frontier searcher's transitions, as a learner stores them.

The teacher is the learner config's ``demo_teacher`` (:data:`TEACHERS`): by default
:class:`egosearch.searchers.frontier.FrontierPolicy`, untuned (it is Table 1's reference bound), or
:class:`egosearch.searchers.frontier_tuned.FrontierTunedPolicy` (tuned on training-side sets, its own bound
row); head moving in an env whose body has a head (``head_on``), head fixed where the body has none
(``head_off``). It searches the variant's training homes under the training distribution: the same env
id (with the observation the learner sees, ``target_memory`` included), heights, reward form and
privileged state as :func:`egosearch.rl.train_env.train_env_kwargs` gives a training, but no start-distance
curriculum (a training aid of RL's, not part of the task). Episodes are seeded apart from the training
curve's evaluation episodes (:data:`DEMO_SEED_BASE`).

Each transition is stored as the learner's replay stores it (pooled depth frames once each, mask,
proprioception, privileged state, action, reward, flags): a :class:`egosearch.rl.replay.ReplayBuffer`
saved as an ``.npz`` (``*.replay.npz``, git-ignored: hundreds of MB), with a JSON summary beside it
(the teacher, episodes, steps, the teacher's success, CPU seconds). Imitation samples (obs, action)
batches from it; RL can draw part of every batch from it (:func:`load_demonstrations` gives it n-step
returns).

A file is read only after its checks, each one line naming it (:class:`DemonstrationsError`):
:func:`check_demonstrations` reads the summary and the ``.npz``'s header (a truncated or corrupt file, a summary
that does not describe its ``.npz``), and compares the summary with what a run needs (:func:`wanted_summary`:
another variant's, teacher's, preset's or observation's demonstrations are refused).
"""

from __future__ import annotations

import json
import time
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from egosearch.envs import observed_env_id
from egosearch.rl.config import LearnerConfig
from egosearch.rl.pooled import pool_depth, pooled_side
from egosearch.rl.replay import MultiReplay, ReplayBuffer
from egosearch.rl.run_files import atomic_json
from egosearch.rl.train_env import make_train_env, replay_layout, train_env_kwargs
from egosearch.rl.training_aids import critic_reads_state, demonstration_settings
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.searchers.frontier_tuned import FrontierTunedPolicy
from egosearch.sim.scenarios import MAX_STEPS

DEMO_SEED_BASE = 7_000_000
"""Episode i of a collection with ``seed`` s resets with seed DEMO_SEED_BASE + 100_000 s + i: apart from the
training curve's evaluation episodes (``rl.train.EVAL_SEED_BASE`` + i); Table 1's scenario sets fix their
episodes by stored start poses and targets, not by seeds."""
DEMO_FORMAT = "egosearch-demos-v1"
TEACHERS = {"frontier": FrontierPolicy, "frontier_tuned": FrontierTunedPolicy}
"""``DemonstrationSettings.demo_teacher`` -> the searcher class (``training_aids.DEMO_TEACHERS`` names the same)."""


class DemonstrationsError(ValueError):
    """A demonstrations file that cannot be read, whose summary does not describe it, or that is not the
    demonstrations a run needs: one line naming the file and what was expected."""


MATCHED = ("variant", "env_id", "env_kwargs", "teacher", "seed", "episodes", "frame_history", "image_size")
"""The summary's entries that say whose demonstrations a file holds (:func:`wanted_summary`)."""


def replay_downsample(cfg) -> int:
    """How the depth frames are pooled where the learner's replay stores them: ``obs_downsample`` for a
    learner whose replay pools them (SAC-DrQ, its recurrent form, PPO: ``egosearch.rl.pooled.PooledAgent``), 1
    for one that stores the env's frames (SAC+CURL, the paper preset's learner, has no such field: its
    config does not hold it, which is not a second default of it)."""
    return int(cfg.obs_downsample) if "obs_downsample" in cfg.to_dict() else 1


def stored_side(cfg) -> int:
    """Side of the depth frames a demonstrations file holds for ``cfg``'s learner (its replay's)."""
    return pooled_side(cfg.image_size, replay_downsample(cfg))


def wanted_summary(env_id: str, cfg: LearnerConfig, env_kwargs: dict, variant: str | None = None,
                   seed: int | None = None, episodes: int | None = None) -> dict[str, Any]:
    """What the summary of the demonstrations that ``cfg`` collects (a training's: its seed and
    ``demo_episodes`` unless given) in ``env_id`` says, as JSON reads it back: the :data:`MATCHED` entries."""
    wanted = {"env_id": observed_env_id(env_id, cfg.target_memory, cfg.modular_searcher),
              "env_kwargs": json.loads(json.dumps(train_env_kwargs(cfg, env_kwargs))),
              "teacher": demonstration_settings(cfg).demo_teacher,
              "seed": cfg.seed if seed is None else seed,
              "episodes": demonstration_settings(cfg).demo_episodes if episodes is None else episodes,
              "frame_history": cfg.frame_history, "image_size": stored_side(cfg)}
    return wanted if variant is None else {"variant": variant, **wanted}


def read_summary(path: str | Path) -> dict[str, Any]:
    """The summary beside the demonstrations file ``path``; DemonstrationsError when it is missing, not JSON or
    not a demonstrations summary."""
    where = summary_path(path)
    try:
        meta = json.loads(where.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DemonstrationsError(f"{path}: its summary {where} is not there (`egosearch demos` writes both)") from None
    except (OSError, ValueError) as err:
        raise DemonstrationsError(f"{where}: not a readable JSON summary ({type(err).__name__}); expected the "
                                  f"summary `egosearch demos` writes beside {Path(path).name}") from None
    if not isinstance(meta, dict) or meta.get("format") != DEMO_FORMAT:
        got = meta.get("format") if isinstance(meta, dict) else type(meta).__name__
        raise DemonstrationsError(f"{where} is not a demonstrations summary (format={got!r}; expected "
                                  f"{DEMO_FORMAT!r})")
    return meta


def check_demonstrations(path: str | Path, wanted: dict[str, Any] | None = None) -> dict[str, Any]:
    """The summary of the demonstrations file ``path``, once ``path`` opens as the ``.npz`` a replay buffer
    saves and its header holds what the summary says (frame side, frame history, transitions), and, with
    ``wanted`` (:func:`wanted_summary`), once the summary is what a run needs (a summary without a ``variant``,
    written before it was recorded, is not compared on it). DemonstrationsError, one line, otherwise."""
    path = Path(path)
    if not path.is_file():
        raise DemonstrationsError(f"{path}: no demonstrations file there")
    meta = read_summary(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            head = json.loads(bytes(data["__meta__"]).decode())
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        raise DemonstrationsError(f"{path}: not a readable demonstrations file, truncated or corrupt "
                                  f"({type(err).__name__}: {err}); expected the .npz `egosearch demos` writes, of "
                                  f"{meta.get('transitions')} transitions as {summary_path(path).name} says") from None
    held = {"image_size": head.get("image_size"), "frame_history": head.get("k"), "transitions": head.get("n_added")}
    differ = [key for key, value in held.items() if meta.get(key) != value]
    if differ:
        raise DemonstrationsError(
            f"{path} does not match its summary {summary_path(path).name}: the file holds "
            + ", ".join(f"{key}={held[key]!r}" for key in differ) + "; the summary says "
            + ", ".join(f"{key}={meta.get(key)!r}" for key in differ))
    if wanted is not None:
        differ = [key for key in MATCHED if key in wanted and (key != "variant" or "variant" in meta)
                  and meta.get(key) != wanted[key]]
        if differ:
            raise DemonstrationsError(
                f"{path} holds other demonstrations than this run's: "
                + ", ".join(f"{key}={meta.get(key)!r}" for key in differ) + "; expected "
                + ", ".join(f"{key}={wanted[key]!r}" for key in differ))
    return meta


def summary_path(replay_path: str | Path) -> Path:
    """The JSON summary beside a demonstrations file ``x.replay.npz``: ``x.json``."""
    path = Path(replay_path)
    return path.with_name(path.name.removesuffix(".replay.npz") + ".json")


def collect_demonstrations(env_id: str, cfg: LearnerConfig, env_kwargs: dict, episodes: int, out_path: str | Path,
                           seed: int = 0, progress: bool = True, variant: str | None = None) -> dict[str, Any]:
    """Run the teacher ``demo_teacher`` of ``cfg`` for ``episodes`` training-side episodes of ``env_id`` under
    ``cfg``'s training env settings and the variant's ``env_kwargs``; store its transitions at ``out_path``
    (``*.replay.npz``) and return the summary written beside it (:func:`summary_path`), which names
    ``variant`` when given."""
    if episodes < 1:
        raise ValueError(f"episodes={episodes}; allowed: >= 1")
    out_path, teacher_name = Path(out_path), demonstration_settings(cfg).demo_teacher
    observed = observed_env_id(env_id, cfg.target_memory, cfg.modular_searcher)
    env = make_train_env(observed, train_env_kwargs(cfg, env_kwargs))
    cpu0, wall0 = time.process_time(), time.perf_counter()
    try:
        obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * seed)
        side = stored_side(cfg)
        state_dim = int(np.asarray(obs["state"]).shape[0]) if critic_reads_state(cfg) else 0
        action_dim = int(env.action_space.shape[0])
        buffer = ReplayBuffer(episodes * MAX_STEPS, side, cfg.frame_history, int(np.asarray(obs["mask"]).shape[0]),
                              int(np.asarray(obs["proprio"]).shape[0]), action_dim, seed=seed, state_dim=state_dim,
                              **replay_layout(cfg))
        successes, lengths, returns = [], [], []
        bar = _progress(episodes, progress)
        for episode in range(episodes):
            if episode:
                obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * seed + episode)
            teacher = new_teacher(env, teacher_name)
            stored = stored_observation(obs, cfg)
            total, steps, terminated, truncated = 0.0, 0, False, False
            while not (terminated or truncated):
                action = teacher.act(obs)
                obs, reward, terminated, truncated, _ = env.step(action)
                next_stored = stored_observation(obs, cfg)
                buffer.add(stored, action, float(reward), next_stored, terminated, truncated)
                stored, total, steps = next_stored, total + float(reward), steps + 1
            successes.append(bool(terminated))
            lengths.append(steps)
            returns.append(total)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(success=f"{np.mean(successes):.2f}", steps=sum(lengths), refresh=False)
        if bar is not None:
            bar.close()
    finally:
        env.close()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    buffer.save(out_path)
    summary = {
        "format": DEMO_FORMAT, **({"variant": variant} if variant is not None else {}), "teacher": teacher_name,
        "teacher_head": bool(teacher.head), "env_id": observed,
        "env_kwargs": train_env_kwargs(cfg, env_kwargs), "seed": seed, "episodes": episodes,
        "transitions": int(sum(lengths)), "teacher_success": round(float(np.mean(successes)), 4),
        "mean_episode_steps": round(float(np.mean(lengths)), 2), "mean_return": round(float(np.mean(returns)), 3),
        "cpu_s": round(time.process_time() - cpu0, 1), "wall_s": round(time.perf_counter() - wall0, 1),
        "image_size": side, "frame_history": cfg.frame_history, "state_dim": state_dim,
    }
    atomic_json(summary_path(out_path), summary)
    return summary


def load_demonstrations(path: str | Path, cfg: LearnerConfig, device: str = "cpu",
                        wanted: dict[str, Any] | None = None) -> MultiReplay:
    """A demonstrations file as a one-ring :class:`MultiReplay` with ``cfg``'s n-step returns and
    discount, ready to sample as the learner's own replay; checked first (:func:`check_demonstrations`,
    against ``wanted`` when given), and its frames against ``cfg``'s learner's. DemonstrationsError, one
    line naming the file, when it cannot serve."""
    meta = check_demonstrations(path, wanted)
    if meta["image_size"] != stored_side(cfg) or meta["frame_history"] != cfg.frame_history:
        raise DemonstrationsError(f"{path} holds {meta['image_size']} px frames in stacks of {meta['frame_history']}; "
                                  f"this learner's replay holds {stored_side(cfg)} px in stacks of "
                                  f"{cfg.frame_history}")
    with np.load(path, allow_pickle=False) as data:
        head = json.loads(bytes(data["__meta__"]).decode())
    sizes = [int(head[name]) for name in ("capacity", "image_size", "k", "mask_dim", "proprio_dim", "action_dim")]
    replay = MultiReplay(1, *sizes, n_step=cfg.n_step, gamma=cfg.gamma, device=device, seed=cfg.seed,
                         state_dim=int(meta["state_dim"]), **replay_layout(cfg))
    try:
        replay.buffers[0].load(path)
    except ValueError as err:  # an array that does not read back (a corrupt member) or does not fit the header
        said = str(err) if str(path) in str(err) else f"{path}: {err}"
        raise DemonstrationsError(f"{said}; expected the .npz `egosearch demos` writes") from None
    return replay


def new_teacher(env, name: str = "frontier") -> FrontierPolicy:
    """The teacher ``name`` (:data:`TEACHERS`) for an episode just reset in ``env``, reset itself (a pool of
    homes swaps its env at each reset, so the teacher is made per episode, for the home the episode is in).
    Its head moves where the env's body has one, and is fixed where it has none."""
    teacher = TEACHERS[name](getattr(env, "current", env))
    teacher.reset()
    return teacher


def stored_observation(obs: dict, cfg: LearnerConfig) -> dict:
    """An env observation as the learner's replay stores it: the depth frames pooled by
    :func:`replay_downsample`."""
    return {**obs, "depth": pool_depth(np.asarray(obs["depth"]), replay_downsample(cfg))}


def _progress(total: int, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="demonstrations", unit="episode", mininterval=5.0)
