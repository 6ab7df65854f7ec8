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
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from egosearch.envs import observed_env_id
from egosearch.rl.base import pool_depth, pooled_side
from egosearch.rl.config import LearnerConfig
from egosearch.rl.replay import MultiReplay, ReplayBuffer
from egosearch.rl.run_files import atomic_json
from egosearch.rl.train_env import make_train_env, train_env_kwargs
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.searchers.frontier_tuned import FrontierTunedPolicy
from egosearch.sim.scenarios import MAX_STEPS

DEMO_SEED_BASE = 7_000_000
"""Episode i of a collection with ``seed`` s resets with seed DEMO_SEED_BASE + 100_000 s + i: apart from the
training curve's evaluation episodes (``rl.train.EVAL_SEED_BASE`` + i); Table 1's scenario sets fix their
episodes by stored start poses and targets, not by seeds."""
DEMO_FORMAT = "egosearch-demos-v1"
TEACHERS = {"frontier": FrontierPolicy, "frontier_tuned": FrontierTunedPolicy}
"""``LearnerConfig.demo_teacher`` -> the searcher class (``egosearch.rl.config.DEMO_TEACHERS`` names the same)."""


def summary_path(replay_path: str | Path) -> Path:
    """The JSON summary beside a demonstrations file ``x.replay.npz``: ``x.json``."""
    path = Path(replay_path)
    return path.with_name(path.name.removesuffix(".replay.npz") + ".json")


def collect_demonstrations(env_id: str, cfg: LearnerConfig, env_kwargs: dict, episodes: int, out_path: str | Path,
                           seed: int = 0, progress: bool = True) -> dict[str, Any]:
    """Run the teacher ``cfg.demo_teacher`` for ``episodes`` training-side episodes of ``env_id`` under
    ``cfg``'s training env settings and the variant's ``env_kwargs``; store its transitions at ``out_path``
    (``*.replay.npz``) and return the summary written beside it (:func:`summary_path`)."""
    if episodes < 1:
        raise ValueError(f"episodes={episodes}; allowed: >= 1")
    out_path = Path(out_path)
    observed = observed_env_id(env_id, cfg.target_memory, cfg.modular_searcher)
    env = make_train_env(observed, train_env_kwargs(cfg, env_kwargs))
    cpu0, wall0 = time.process_time(), time.perf_counter()
    try:
        obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * seed)
        side = pooled_side(cfg.image_size, cfg.obs_downsample)
        state_dim = int(np.asarray(obs["state"]).shape[0]) if cfg.critic_privileged_state else 0
        action_dim = int(env.action_space.shape[0])
        buffer = ReplayBuffer(episodes * MAX_STEPS, side, cfg.frame_history, int(np.asarray(obs["mask"]).shape[0]),
                              int(np.asarray(obs["proprio"]).shape[0]), action_dim, seed=seed, state_dim=state_dim)
        successes, lengths, returns = [], [], []
        bar = _progress(episodes, progress)
        for episode in range(episodes):
            if episode:
                obs, _ = env.reset(seed=DEMO_SEED_BASE + 100_000 * seed + episode)
            teacher = new_teacher(env, cfg.demo_teacher)
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
        "format": DEMO_FORMAT, "teacher": cfg.demo_teacher, "teacher_head": bool(teacher.head), "env_id": observed,
        "env_kwargs": train_env_kwargs(cfg, env_kwargs), "seed": seed, "episodes": episodes,
        "transitions": int(sum(lengths)), "teacher_success": round(float(np.mean(successes)), 4),
        "mean_episode_steps": round(float(np.mean(lengths)), 2), "mean_return": round(float(np.mean(returns)), 3),
        "cpu_s": round(time.process_time() - cpu0, 1), "wall_s": round(time.perf_counter() - wall0, 1),
        "image_size": side, "frame_history": cfg.frame_history, "state_dim": state_dim,
    }
    atomic_json(summary_path(out_path), summary)
    return summary


def load_demonstrations(path: str | Path, cfg: LearnerConfig, device: str = "cpu") -> MultiReplay:
    """A demonstrations file as a one-ring :class:`MultiReplay` with ``cfg``'s n-step returns and
    discount, ready to sample as the learner's own replay."""
    meta = json.loads(summary_path(path).read_text(encoding="utf-8"))
    if meta.get("format") != DEMO_FORMAT:
        raise ValueError(f"{summary_path(path)} is not a demonstrations summary (format={meta.get('format')!r})")
    with np.load(path, allow_pickle=False) as data:
        head = json.loads(bytes(data["__meta__"]).decode())
    sizes = [int(head[name]) for name in ("capacity", "image_size", "k", "mask_dim", "proprio_dim", "action_dim")]
    replay = MultiReplay(1, *sizes, n_step=cfg.n_step, gamma=cfg.gamma, device=device, seed=cfg.seed,
                         state_dim=int(meta["state_dim"]))
    replay.buffers[0].load(path)
    return replay


def new_teacher(env, name: str = "frontier") -> FrontierPolicy:
    """The teacher ``name`` (:data:`TEACHERS`) for an episode just reset in ``env``, reset itself (a pool of
    homes swaps its env at each reset, so the teacher is made per episode, for the home the episode is in).
    Its head moves where the env's body has one, and is fixed where it has none."""
    teacher = TEACHERS[name](getattr(env, "current", env))
    teacher.reset()
    return teacher


def stored_observation(obs: dict, cfg: LearnerConfig) -> dict:
    """An env observation as the learner's replay stores it: the depth frames pooled by ``obs_downsample``."""
    return {**obs, "depth": pool_depth(np.asarray(obs["depth"]), cfg.obs_downsample)}


def _progress(total: int, enabled: bool):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="demonstrations", unit="episode", mininterval=5.0)
