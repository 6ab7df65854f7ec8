"""The training loop: train the learner ``cfg.algorithm`` names (:mod:`egosearch.rl.learner_registry`) on an
egosearch env, resumably. Its files are written by :mod:`egosearch.rl.run_files`; the actor it
leaves is run by :class:`egosearch.rl.actor.ActorPolicy`.

``train(env_id, cfg, out_dir)`` writes into ``out_dir``:

- ``config.json``: the whole config (also printed at start);
- ``curve.csv``: one row per evaluation (every ``eval_every`` env steps, at step 0 and at the
  end) with the fixed columns :data:`CURVE_COLUMNS`;
- ``train.csv``: one row every ``log_every`` env steps with :data:`TRAIN_COLUMNS`;
- ``curve_episodes.csv``: the episodes behind each curve.csv row (:data:`CURVE_EPISODE_COLUMNS`),
  when the evaluator reports them: Figure 6's interval resamples them by scenario, then by seed;
- ``ckpt/train_state.ckpt``: the resumable state (agent + optimisers + replay + RNG states + step
  counter + CSV row counts), rewritten atomically every ``checkpoint_every`` env steps and
  deleted at the end unless ``cfg.keep_checkpoint`` (it holds the replay buffer: up to ~1 GB,
  never commit it);
- ``actor.pt``: actor-only weights + metadata (variant, env_id, config), readable with
  ``torch.load(weights_only=True)``; load it with :class:`egosearch.rl.actor.ActorPolicy`;
- ``actor_start.pt``: the same for the policy at step 0 (the clone after imitation, else the
  untrained net; metadata ``start: True``), written before the step-0 evaluation: what the run's
  learning starts from (runs stored before it have none);
- ``ckpt/demos.replay.npz`` (+ ``ckpt/demos.json``): with ``cfg.demo_episodes``, the frontier
  searcher's transitions that the run learns from (:mod:`egosearch.rl.demos`), collected at the
  fresh start, deleted with the checkpoint; ``done.json`` keeps their summary;
- ``done.json``: written last; its presence means the run is complete.

With ``cfg.bc_updates`` a fresh run clones the teacher (behaviour cloning of the encoder and the
actor on the demonstrations) before its step-0 evaluation, so curve.csv's first row is the cloned
policy; ``train.csv`` gets one row at step 0 with the cloning's last loss (``bc_loss``).

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
import re
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np
import torch

from egosearch.core.allocator import keep_freed_memory
from egosearch.core.machine import cpu_model, cpu_vector_unit, gpu_model
from egosearch.core.staging import CHECKPOINT_NAME, START_ACTOR_NAME
from egosearch.envs import observation_kwargs, observed_env_id
from egosearch.rl.actor import AgentPolicy
from egosearch.rl.common import METRIC_KEYS, AgentStateError, resolve_device
from egosearch.rl.config import LearnerConfig
from egosearch.rl.demos import (
    DemonstrationsError,
    check_demonstrations,
    collect_demonstrations,
    load_demonstrations,
    summary_path,
    wanted_summary,
)
from egosearch.rl.imitation import clone, dagger_round
from egosearch.rl.learner import Agent
from egosearch.rl.learner_registry import learner, make_agent
from egosearch.rl.replay import MultiReplay, rng_from_plain, rng_to_plain
from egosearch.rl.run_files import (
    CHECKPOINT_FORMAT,
    CheckpointError,
    CsvLogger,
    atomic_json,
    atomic_write,
    check_same_run,
    describe_error,
    env_kwargs_key,
    load_checkpoint,
    restore_rng_states,
    rng_states,
    to_numpy,
    to_tensors,
)
from egosearch.rl.train_env import make_train_env, replay_layout, train_env_kwargs
from egosearch.rl.training_aids import critic_reads_state, demonstration_settings
from egosearch.sim.observation_options import extra_dims

CURVE_COLUMNS = ("env_steps", "success_rate", "spl", "episode_return", "critic_loss", "actor_loss",
                 "curl_loss", "alpha", "entropy", "steps_per_s", "updates_per_s", "wall_s")
CURVE_EPISODE_COLUMNS = ("env_steps", "home", "height", "scenario_id", "success", "shortest_path", "path_length")
TRAIN_COLUMNS = ("env_steps", "episodes", "updates", "train_return", "train_success", "critic_loss",
                 "actor_loss", "alpha_loss", "curl_loss", "aux_loss", "bc_loss", "alpha", "entropy", "q_mean",
                 "steps_per_s", "updates_per_s", "wall_s")
EVAL_SEED_BASE = 1_000_000
"""Default evaluation: episode i is ``reset(seed=EVAL_SEED_BASE + i)``, the same at every
evaluation, for every training seed and variant."""


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


SNAPSHOT_NAME = re.compile(r"actor_\d+k?\.pt")
"""The actor snapshots' file names (``actor_snapshot_every``)."""


def snapshot_name(env_steps: int) -> str:
    """``actor_50k.pt`` for 50,000 env steps; ``actor_200.pt`` for 200, which is no whole thousand."""
    return f"actor_{env_steps // 1000}k.pt" if env_steps % 1000 == 0 else f"actor_{env_steps}.pt"


# ---- policies -----------------------------------------------------------------------------


def cloning_weight(cfg: LearnerConfig, step: int) -> float:
    """The behaviour-cloning term's weight at env step ``step``: ``bc_weight`` falling linearly over
    ``bc_decay_steps`` to ``bc_weight_floor`` (0 by default), then held there."""
    aids = demonstration_settings(cfg)
    if not aids.bc_weight:
        return 0.0
    decayed = aids.bc_weight * max(0.0, 1.0 - step / aids.bc_decay_steps)
    return max(decayed, aids.bc_weight_floor)


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


def _env_spaces(env, cfg: LearnerConfig) -> tuple[int, int, int]:
    space = env.observation_space
    try:
        depth, mask, proprio = space["depth"], space["mask"], space["proprio"]
    except (KeyError, TypeError):
        raise ValueError(f"observation space must be a Dict with depth, mask, proprio; got {space}") from None
    want = (cfg.frame_history, cfg.image_size, cfg.image_size)
    if tuple(depth.shape) != want or depth.dtype != np.uint8:
        raise ValueError(f"env depth is {tuple(depth.shape)} {depth.dtype}; config expects {want} uint8 "
                         "(frame_history, image_size)")
    # the head's pose and its last changes, then the values of the observation options the config turns on
    observed = observation_kwargs(cfg.to_dict())
    wanted = 2 * (1 + cfg.head_history) + extra_dims(observed).get("proprio", 0)
    if proprio.shape[0] != wanted:
        named = "".join(f" and {name}=True" for name in observed)
        raise ValueError(f"env proprio has {proprio.shape[0]} values; head_history={cfg.head_history}{named} "
                         f"expect {wanted}")
    act = env.action_space
    if not isinstance(act, gymnasium.spaces.Box) or len(act.shape) != 1:
        raise ValueError(f"action space must be a 1-d Box, got {act}")
    if not (np.allclose(act.low, -1) and np.allclose(act.high, 1)):
        raise ValueError("action space must be Box(-1, 1): the actor's tanh output is not rescaled")
    return int(act.shape[0]), int(mask.shape[0]), int(proprio.shape[0])


def torch_threads(requested: int = 0) -> int:
    """``requested`` or, for 0, every core this process may run on."""
    if requested:
        return requested
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


# ---- training -----------------------------------------------------------------------------

def train(env_id: str, cfg: LearnerConfig, out_dir: str | os.PathLike, env_kwargs: dict | None = None,
          evaluate_fn: Callable[[Any], dict] | None = None, *, variant: str | None = None,
          progress: bool = True, on_step: Callable[[int], None] | None = None,
          max_wall_s: float | None = None, set_overrides: dict | None = None) -> dict:
    """Train (or resume, or return at once if ``done.json`` is there) and return the summary.

    ``evaluate_fn(policy) -> dict`` with success_rate, spl, episode_return is called every
    ``cfg.eval_every`` env steps (default: :func:`default_evaluator`). ``variant`` names the run
    in the checkpoint / actor metadata (default: ``env_id``). ``on_step(env_steps)`` is called
    after every env step (tests use it to interrupt a run).

    ``max_wall_s``: stop after this many seconds of this call's wall time, at the first env step
    past it, with a checkpoint written there (a job inside a cluster's time limit, or a device
    lent for minutes); the summary then has ``"stopped": True`` and no actor is written. The next
    call resumes from that checkpoint.

    ``set_overrides``: the command line's ``--set`` fields, already in ``cfg``; recorded as ``set`` in
    config.json, the checkpoint and done.json, and compared on resume (another ``--set`` is refused).
    """
    cfg = cfg.validate()
    env_id = observed_env_id(env_id, cfg.target_memory, cfg.modular_searcher)
    env_kwargs = dict(env_kwargs or {})
    out_dir = Path(out_dir)
    variant = variant or env_id
    done, ckpt = open_run(env_id, cfg, out_dir, env_kwargs, variant, set_overrides)
    if done is not None:
        return done

    threads_before = torch.get_num_threads()
    torch.set_num_threads(torch_threads(cfg.num_threads))
    keep_freed_memory()
    envs: list = []
    try:
        for _ in range(cfg.num_envs):
            envs.append(make_train_env(env_id, train_env_kwargs(cfg, env_kwargs)))
        return _train(envs, env_id, cfg, out_dir, env_kwargs, evaluate_fn, variant, progress, on_step, ckpt,
                      max_wall_s, set_overrides)
    finally:
        for env in envs:
            env.close()
        torch.set_num_threads(threads_before)


def open_run(env_id: str, cfg: LearnerConfig, out_dir: Path, env_kwargs: dict,
             variant: str, set_overrides: dict | None = None) -> tuple[dict | None, dict | None]:
    """A run folder's state, validated before anything is written: (``done.json``'s summary of a
    finished run, None) or (None, the checkpoint to resume, or None for a fresh start)."""
    ckpt_path, done_path = out_dir / CHECKPOINT_NAME, out_dir / "done.json"
    if done_path.exists():
        try:
            done = json.loads(done_path.read_text())
        except (OSError, ValueError) as err:
            raise CheckpointError(f"cannot read {done_path} ({describe_error(err)})") from None
        check_same_run("finished run", done_path, done, variant, env_id, env_kwargs, cfg, set_overrides)
        return done, None
    ours = {CHECKPOINT_NAME.name, "actor.pt", START_ACTOR_NAME, "done.json", "config.json", "curve.csv",
            "curve_episodes.csv", "train.csv"}
    for stale in [*out_dir.glob(".tmp*"), *(out_dir / CHECKPOINT_NAME.parent).glob(".tmp*")]:
        name = stale.name.split(".", 2)[-1]
        if name in ours or SNAPSHOT_NAME.fullmatch(name):  # temp files of a killed run of ours
            stale.unlink()
    ckpt = load_checkpoint(ckpt_path) if ckpt_path.exists() else None
    if ckpt is not None:
        check_same_run("checkpoint", ckpt_path, ckpt, variant, env_id, env_kwargs, cfg, set_overrides)
        if demonstration_settings(cfg).demo_episodes:
            # the demonstrations it resumes with: the run's own, readable, before any env is built
            demos = demos_path_of(ckpt_path)
            if not demos.exists():
                raise CheckpointError(f"{ckpt_path} needs the run's demonstrations {demos}, which are gone")
            try:
                check_demonstrations(demos, wanted_summary(env_id, cfg, env_kwargs, variant))
            except DemonstrationsError as err:
                raise CheckpointError(f"{ckpt_path} cannot resume with its demonstrations: {err}") from None
    return None, ckpt


def demos_path_of(ckpt_path: Path) -> Path:
    """Where a run keeps its demonstrations: beside its checkpoint, ``ckpt/demos.replay.npz``."""
    return ckpt_path.parent / "demos.replay.npz"


def _act_batch(agent: Agent, observations: list[dict]) -> list[np.ndarray]:
    # a recurrent agent's act() is the evaluation episode's: training envs always go through act_batch
    if len(observations) == 1 and not agent.recurrent:
        return [agent.act(observations[0], deterministic=False)]
    stacked = {k: np.stack([o[k] for o in observations]) for k in observations[0]}
    return list(agent.act_batch(stacked, deterministic=False))


def _privileged_state_dim(env, env_id: str, cfg: LearnerConfig) -> int:
    """Size of the env's privileged state when the critic reads it (``critic_privileged_state``), else 0."""
    if not critic_reads_state(cfg):
        return 0
    if "state" not in env.observation_space.spaces:
        raise ValueError(f"critic_privileged_state needs an env whose observations hold a 'state' "
                         f"entry (privileged_state=True); {env_id} gives none")
    return int(env.observation_space["state"].shape[0])


def _train(envs: list, env_id: str, cfg: LearnerConfig, out_dir: Path, env_kwargs: dict, evaluate_fn, variant: str,
           progress: bool, on_step, ckpt: dict | None, max_wall_s: float | None = None,
           set_overrides: dict | None = None) -> dict:
    """The loop: act, step and store, update, then log / evaluate / checkpoint when their step comes."""
    run = LiveRun(envs, env_id, cfg, out_dir, env_kwargs, variant, ckpt, progress, set_overrides)
    own_eval = evaluate_fn is None
    evaluate_fn = evaluate_fn or default_evaluator(env_id, {**env_kwargs, **observation_kwargs(cfg.to_dict())},
                                                   cfg.eval_episodes)
    bar = run.open_progress(progress)
    run.start_clock()
    last_row = None
    try:
        if run.step == 0 and run.curve.rows() == 0:
            run.imitate()
            run.write_start_actor()
            last_row = run.evaluate(evaluate_fn)
        while run.step < cfg.total_env_steps:
            before = run.step
            live = envs[: cfg.total_env_steps - run.step]  # the last round may need fewer envs
            run.step_and_store(live, run.actions(live))
            run.update(before)
            last_row = run.log_evaluate_checkpoint(before, evaluate_fn, run.crossed(cfg.checkpoint_every, before),
                                                   bar) or last_row
            if bar is not None:
                bar.update(run.step - before)
            if on_step is not None:
                on_step(run.step)
            if max_wall_s is not None and run.step < cfg.total_env_steps \
                    and time.perf_counter() - run.t_start >= max_wall_s:
                run.save_checkpoint()
                return run.stopped()
    finally:
        if bar is not None:
            bar.close()
        if own_eval:
            evaluate_fn.close()
    return run.finish(last_row)


class LiveRun:
    """One training run's live state (agent, replay, envs, counters, CSV logs) and the steps of its
    loop, each a method, after DrQ-v2's ``Workspace``.

    Everything that draws random numbers runs in one fixed order (seeding, the agent's init, the
    replay, a checkpoint's RNG states, the envs' resets; then per round: actions, env steps,
    resets, updates), so that a resumed run equals the one that was not stopped."""

    def __init__(self, envs: list, env_id: str, cfg: LearnerConfig, out_dir: Path, env_kwargs: dict, variant: str,
                 ckpt: dict | None, progress: bool = False, set_overrides: dict | None = None):
        self.envs, self.env_id, self.cfg, self.variant = envs, env_id, cfg, variant
        self.set_overrides = dict(set_overrides or {})
        self.out_dir, self.env_kwargs = out_dir, env_kwargs
        self.ckpt_path, self.done_path = out_dir / CHECKPOINT_NAME, out_dir / "done.json"
        self.device = resolve_device(cfg.device)
        random.seed(cfg.seed)
        np.random.seed(cfg.seed)
        torch.manual_seed(cfg.seed)
        action_dim, mask_dim, proprio_dim = _env_spaces(envs[0], cfg)
        state_dim = _privileged_state_dim(envs[0], env_id, cfg)
        for i, e in enumerate(envs):
            e.action_space.seed(cfg.seed + 7 * i)
        self.agent: Agent = make_agent(cfg, action_dim, mask_dim, proprio_dim, self.device, state_dim)
        self.to_replay = self.agent.replay_obs
        self.replay = MultiReplay(cfg.num_envs, cfg.replay_capacity, self.agent.replay_image_size, cfg.frame_history,
                                  mask_dim, proprio_dim, action_dim, n_step=cfg.n_step, gamma=cfg.gamma,
                                  device=self.device, seed=cfg.seed, state_dim=state_dim,
                                  **replay_layout(cfg))
        self.curve = CsvLogger(out_dir / "curve.csv", CURVE_COLUMNS)
        self.train_log = CsvLogger(out_dir / "train.csv", TRAIN_COLUMNS)
        self.curve_episodes = CsvLogger(out_dir / "curve_episodes.csv", CURVE_EPISODE_COLUMNS)
        self.step, self.episodes, self.wall_before = 0, 0, 0.0
        self.recent: deque[tuple[float, float]] = deque(maxlen=20)  # (return, success) of train episodes
        reset_seeds = self._resume(ckpt) if ckpt is not None else self._fresh()
        self.observations = [self.reset(e, sd) for e, sd in zip(envs, reset_seeds)]
        self.stored = [self.to_replay(o) for o in self.observations]  # as the replay stores them, each computed once
        self.ep_returns = [0.0] * len(envs)
        # `set`: the fields the command line's --set gave (already in `config`), so that a reader tells them
        # from the variant's, and a resume refuses other ones
        atomic_json(out_dir / "config.json", {"variant": variant, "env_id": env_id,
                                              "env_kwargs": env_kwargs_key(env_kwargs), "config": cfg.to_dict(),
                                              "set": self.set_overrides})
        self.policy = AgentPolicy(self.agent)
        self.say = print
        self.means = {"curve": _Mean(), "train": _Mean()}
        self.demos, self.demo_summary = self._demonstrations(ckpt, progress)
        self.imitation: dict = {"dagger": []} if ckpt is None else dict(ckpt.get("imitation", {"dagger": []}))

    # ---- start ----------------------------------------------------------------------------
    def _fresh(self) -> list[int]:
        self.curve.truncate(0)
        self.train_log.truncate(0)
        self.curve_episodes.truncate(0)
        return [self.cfg.seed + 104_729 * i for i in range(len(self.envs))]

    def _resume(self, ckpt: dict) -> list[int]:
        """Load the agent, replay and RNG states; drop the CSV rows written after the checkpoint."""
        try:
            self.agent.load_state_dict(ckpt["agent"])
            self.replay.load_state_dict(to_numpy(ckpt["replay"]))
            restore_rng_states(ckpt["rng"], self.envs)
        except (AgentStateError, ValueError, KeyError, RuntimeError) as err:
            raise CheckpointError(f"checkpoint {self.ckpt_path} does not fit this run "
                                  f"({describe_error(err)})") from None
        self.step, self.episodes = int(ckpt["env_steps"]), int(ckpt["episodes"])
        self.wall_before = float(ckpt["wall_s"])
        self.recent.extend((float(r), float(s)) for r, s in ckpt["recent"])
        self.curve.truncate(int(ckpt["csv_rows"]["curve"]))
        self.train_log.truncate(int(ckpt["csv_rows"]["train"]))
        # a checkpoint from before the per-episode file: its episodes start at this resume
        self.curve_episodes.truncate(int(ckpt["csv_rows"].get("curve_episodes", 0)))
        # The run that was not stopped cut its episodes here too (see restart_episodes).
        self.replay.end_episodes()
        return self._restart_seeds()

    def _demonstrations(self, ckpt: dict | None, progress: bool) -> tuple[MultiReplay | None, dict | None]:
        """The teacher's transitions (``demo_episodes``): collected at a fresh start, read back on resume."""
        cfg, aids = self.cfg, demonstration_settings(self.cfg)
        if not aids.demo_episodes:
            return None, None
        path = self.demos_path
        if ckpt is not None and not path.exists():
            raise CheckpointError(f"{self.ckpt_path} needs the run's demonstrations {path}, which are gone")
        if ckpt is None and not self._own_demonstrations(path):  # kept when a run stopped before its checkpoint
            path.parent.mkdir(parents=True, exist_ok=True)
            self.say(f"collecting {aids.demo_episodes} demonstration episodes of {aids.demo_teacher} -> {path}")
            collect_demonstrations(self.env_id, cfg, self.env_kwargs, aids.demo_episodes, path, seed=cfg.seed,
                                   progress=progress, variant=self.variant)
        try:
            demos = load_demonstrations(path, cfg, str(self.device), self._wanted_demonstrations())
        except DemonstrationsError as err:  # on resume: an array that does not read back
            raise CheckpointError(f"{self.ckpt_path} cannot resume with its demonstrations: {err}") from None
        if ckpt is not None and "demo_rng" in ckpt:
            demos.buffers[0].rng.bit_generator.state = rng_from_plain(ckpt["demo_rng"])
        summary = json.loads(summary_path(path).read_text(encoding="utf-8"))
        self.say(f"demonstrations: {summary['episodes']} episodes of {summary.get('teacher', 'frontier')}, "
                 f"{summary['transitions']} transitions, "
                 f"teacher success {summary['teacher_success']:.2f}, {summary['cpu_s']:.0f} CPU-s")
        return demos, summary

    def _wanted_demonstrations(self) -> dict:
        """What this run's demonstrations' summary says (:func:`egosearch.rl.demos.wanted_summary`)."""
        wanted = wanted_summary(self.env_id, self.cfg, self.env_kwargs, self.variant)
        assert wanted["image_size"] == self.agent.replay_image_size, "demonstrations stored as the replay stores"
        return wanted

    def _own_demonstrations(self, path: Path) -> bool:
        """Whether ``path`` holds the demonstrations this run would collect (same teacher episodes, stored
        as this learner stores them), whole: a run killed while cloning starts again from them. A file left
        there that is not (truncated, another run's) is said in one line, and collected again."""
        if not path.exists() and not summary_path(path).exists():
            return False
        try:
            check_demonstrations(path, self._wanted_demonstrations())
        except DemonstrationsError as err:
            self.say(f"not reused: {err}")
            return False
        return True

    @property
    def demos_path(self) -> Path:
        return demos_path_of(self.ckpt_path)

    def _restart_seeds(self) -> list[int]:
        return [self.cfg.seed + 7919 * self.step + 104_729 * i for i in range(len(self.envs))]

    def open_progress(self, progress: bool):
        """The tqdm bar (None without ``progress``) and the run's first two lines."""
        cfg, bar = self.cfg, None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=cfg.total_env_steps, initial=self.step, unit="step", dynamic_ncols=True,
                       mininterval=1.0, desc=f"{self.variant} seed {cfg.seed}")
            self.say = bar.write
        self.say(f"{learner(cfg.algorithm).display_name} {self.variant} on {self.env_id} -> {self.out_dir} | device "
                 f"{self.device}, {torch.get_num_threads()} torch threads, {cfg.num_envs} env(s) | "
                 f"{'resuming at step ' + str(self.step) if self.step else 'fresh start'}")
        self.say("config: " + json.dumps(cfg.to_dict(), sort_keys=True))
        return bar

    # ---- clocks ---------------------------------------------------------------------------
    def start_clock(self) -> None:
        """Zero the run's clocks: wall_s goes on from the checkpoint's, the rates start here."""
        self.t_start = time.perf_counter()
        self.eval_time = 0.0
        self.marks = {key: (self.step, self.agent.num_updates, self.t_start, 0.0) for key in ("curve", "train")}

    def wall(self) -> float:
        return self.wall_before + time.perf_counter() - self.t_start

    def rates(self, key: str) -> tuple[float, float]:
        """Env steps and updates per second since the last row of ``key``, evaluations excluded."""
        s0, u0, t0, e0 = self.marks[key]
        dt = max(time.perf_counter() - t0 - (self.eval_time - e0), 1e-9)
        self.marks[key] = (self.step, self.agent.num_updates, time.perf_counter(), self.eval_time)
        if self.step == s0:
            return float("nan"), float("nan")
        return (self.step - s0) / dt, (self.agent.num_updates - u0) / dt

    def crossed(self, every: int, before: int) -> bool:
        return self.step // every > before // every or self.step == self.cfg.total_env_steps

    # ---- acting and storing ---------------------------------------------------------------
    def reset(self, e, seed: int | None = None) -> dict:
        radius = self.cfg.start_radius(self.step)
        return e.reset(seed=seed, options=None if radius is None else {"start_radius": radius})[0]

    def actions(self, live: list) -> list[np.ndarray]:
        """Uniform random actions during the warm-up (the cloned policy's samples after behaviour
        cloning), the agent's samples after it."""
        if self.step < self.cfg.init_steps and not demonstration_settings(self.cfg).bc_updates:
            return [e.action_space.sample() for e in live]
        return _act_batch(self.agent, self.observations[: len(live)])

    def step_and_store(self, live: list, actions: list[np.ndarray]) -> None:
        """Step each live env once, store the transitions, reset the envs whose episode ended."""
        for i, (e, action) in enumerate(zip(live, actions)):
            next_obs, reward, terminated, truncated, info = e.step(action)
            next_stored = self.to_replay(next_obs)
            self.replay.add(i, self.stored[i], action, reward, next_stored, terminated, truncated)
            self.step += 1
            self.ep_returns[i] += float(reward)
            if terminated or truncated:
                self.episodes += 1
                self.recent.append((self.ep_returns[i], float(terminated)))
                self.ep_returns[i] = 0.0
                self.observations[i] = self.reset(e)  # the curriculum radius of the step just counted
                self.reset_agent_state(i)
                self.stored[i] = self.to_replay(self.observations[i])
            else:
                self.observations[i], self.stored[i] = next_obs, next_stored

    def restart_episodes(self) -> None:
        """Cut every env's episode at a checkpoint and reset it with a seed of the step, exactly as
        a run resumed from that checkpoint does: so killing and resuming gives the same run as not
        stopping (the cut transitions count as truncated, so they still bootstrap)."""
        self.replay.end_episodes()
        for i, (e, seed) in enumerate(zip(self.envs, self._restart_seeds())):
            self.observations[i] = self.reset(e, seed)
            self.stored[i] = self.to_replay(self.observations[i])
            self.ep_returns[i] = 0.0
            self.reset_agent_state(i)

    def reset_agent_state(self, env_index: int) -> None:
        """A recurrent agent forgets env ``env_index``'s episode (a memoryless agent's hook does nothing)."""
        self.agent.reset_state(env_index)

    # ---- updating -------------------------------------------------------------------------
    def update(self, before: int) -> None:
        """The updates due for the env steps ``before`` -> ``step``: ``updates_per_step`` at every
        ``update_every``-th step from the last warm-up step on."""
        for _ in range(self.updates_due(before)):
            self.record(self.agent.update(self.sample()))

    def updates_due(self, before: int) -> int:
        """How many updates the env steps ``before`` -> ``step`` call for; sets the agent's
        ``bc_weight_now`` for them."""
        cfg = self.cfg
        if self.step < cfg.init_steps:
            return 0
        first_due = max(before, cfg.init_steps - 1)
        if demonstration_settings(cfg).bc_weight:
            self.agent.bc_weight_now = cloning_weight(cfg, self.step)
        return (self.step // cfg.update_every - first_due // cfg.update_every) * cfg.updates_per_step

    def record(self, metrics: dict[str, float]) -> None:
        """An update's metrics, into the means of the next curve.csv and train.csv rows."""
        self.means["curve"].add(metrics)
        self.means["train"].add(metrics)

    def sample(self) -> dict:
        """An update's batch, the agent's draw: transitions (a recurrent agent's sequences, PPO's rollout);
        with ``demo_batch_fraction`` that share drawn from the demonstrations (marked by ``demo``)."""
        fraction = demonstration_settings(self.cfg).demo_batch_fraction
        if self.demos is None or not fraction:
            return self.agent.sample_batch(self.replay)
        return self.agent.sample_with_demonstrations(self.replay, self.demos, fraction)

    # ---- imitating ------------------------------------------------------------------------
    def imitate(self) -> None:
        """Behaviour cloning on the demonstrations (``bc_updates`` steps), then ``dagger_rounds`` DAgger
        rounds (:mod:`egosearch.rl.imitation`), at a fresh start only."""
        cfg, aids = self.cfg, demonstration_settings(self.cfg)
        if not aids.bc_updates:
            return
        cpu0, wall0 = time.process_time(), time.perf_counter()
        optimiser = torch.optim.Adam(self.agent.clone_parameters(), lr=cfg.actor_lr,
                                     betas=(cfg.actor_beta1, cfg.actor_beta2))
        sources = [self.demos]
        loss = clone(self.agent, sources, aids.bc_updates, cfg.batch_size, optimiser, self.say)
        for r in range(aids.dagger_rounds):
            labelled, figures = dagger_round(self.agent, self.env_id, cfg, self.env_kwargs, aids.dagger_episodes, r,
                                             self.device)
            self.imitation["dagger"].append(figures)
            self.say(f"DAgger round {r + 1}/{aids.dagger_rounds}: the student succeeded in "
                     f"{figures['student_success']:.2f} of {figures['episodes']} episodes; "
                     f"{figures['transitions']} of its {figures['states_reached']} states labelled "
                     f"({aids.dagger_states}; {figures['cpu_s']:.0f} CPU-s)")
            if labelled is not None:  # "contact": a round whose student never touched anything adds nothing
                sources.append(labelled)
            loss = clone(self.agent, sources, aids.bc_updates, cfg.batch_size, optimiser, self.say,
                         f"DAgger round {r + 1}: cloning")
        # The learner's own rate (env steps per CPU-second, what the estimates scale) leaves this out.
        self.imitation.update(cpu_s=round(time.process_time() - cpu0, 1), wall_s=round(time.perf_counter() - wall0, 1),
                              bc_updates=aids.bc_updates * (1 + aids.dagger_rounds))
        self.train_log.write({"env_steps": 0, "episodes": 0, "updates": 0, "bc_loss": loss,
                              "alpha": self.agent.alpha, "wall_s": self.wall()})

    # ---- logging and evaluating -----------------------------------------------------------
    def log_evaluate_checkpoint(self, before: int, evaluate_fn, checkpoint: bool, bar=None) -> dict | None:
        """What follows the updates of the env steps ``before`` -> ``step``: a train.csv row at every
        ``log_every``-th step, an evaluation at every ``eval_every``-th (its curve row is returned, else None),
        and with ``checkpoint`` the checkpoint, then fresh episodes unless the run is done."""
        cfg, row = self.cfg, None
        if self.step // cfg.log_every > before // cfg.log_every:
            self.log_train(bar)
        if self.crossed(cfg.eval_every, before):
            row = self.evaluate(evaluate_fn)
        every = cfg.actor_snapshot_every
        if every and self.step // every > before // every:
            self.write_snapshot(self.step // every * every)
        if checkpoint:
            self.save_checkpoint()
            if self.step < cfg.total_env_steps:
                self.restart_episodes()
        return row

    def log_train(self, bar=None) -> None:
        """A row of train.csv: update metrics since the last row, the last 20 training episodes."""
        sps, ups = self.rates("train")
        m = self.means["train"].mean()
        self.means["train"] = _Mean()
        ret = float(np.mean([r for r, _ in self.recent])) if self.recent else float("nan")
        succ = float(np.mean([s for _, s in self.recent])) if self.recent else float("nan")
        self.train_log.write({"env_steps": self.step, "episodes": self.episodes, "updates": self.agent.num_updates,
                              "train_return": ret, "train_success": succ, **m, "alpha": self.agent.alpha,
                              "steps_per_s": sps, "updates_per_s": ups, "wall_s": self.wall()})
        if bar is not None:
            bar.set_postfix(success=f"{succ:.2f}", ret=f"{ret:.1f}", ups=f"{ups:.1f}", refresh=False)

    def evaluate(self, evaluate_fn) -> dict:
        """A row of curve.csv: ``evaluate_fn`` on the deterministic policy, update metrics since the
        last row. Its time is left out of the rates."""
        t0 = time.perf_counter()
        result = evaluate_fn(self.policy)
        self.eval_time += time.perf_counter() - t0
        sps, ups = self.rates("curve")
        m = self.means["curve"].mean()
        self.means["curve"] = _Mean()
        row = {"env_steps": self.step, "success_rate": result.get("success_rate", float("nan")),
               "spl": result.get("spl", float("nan")), "episode_return": result.get("episode_return", float("nan")),
               "critic_loss": m["critic_loss"], "actor_loss": m["actor_loss"], "curl_loss": m["curl_loss"],
               "alpha": self.agent.alpha, "entropy": m["entropy"], "steps_per_s": sps, "updates_per_s": ups,
               "wall_s": self.wall()}
        self.curve.write(row)
        for episode in result.get("episodes", ()):
            self.curve_episodes.write({"env_steps": self.step, **{k: episode[k] for k in CURVE_EPISODE_COLUMNS[1:]}})
        self.say(f"eval @ {self.step}: success {row['success_rate']:.3f}  return {row['episode_return']:.2f}  "
                 f"spl {row['spl']:.3f}  ({sps:.1f} steps/s, {ups:.1f} updates/s)")
        return row

    # ---- checkpointing and finishing ------------------------------------------------------
    def save_checkpoint(self) -> None:
        state = {
            "format": CHECKPOINT_FORMAT, "variant": self.variant, "env_id": self.env_id,
            "env_kwargs": env_kwargs_key(self.env_kwargs), "config": self.cfg.to_dict(), "set": self.set_overrides,
            "env_steps": self.step, "episodes": self.episodes, "wall_s": self.wall(),
            "csv_rows": {"curve": self.curve.rows(), "train": self.train_log.rows(),
                         "curve_episodes": self.curve_episodes.rows()},
            "recent": [list(x) for x in self.recent],
            "agent": self.agent.state_dict(), "replay": to_tensors(self.replay.state_dict()),
            "rng": rng_states(self.envs),
        }
        if self.demos is not None:
            state["demo_rng"] = rng_to_plain(self.demos.buffers[0].rng)
            state["imitation"] = self.imitation
        atomic_write(self.ckpt_path, lambda f: torch.save(state, f))

    def machine(self) -> dict:
        """The machine the run used: CPU and cores, and the GPU when it trained on one."""
        gpu = {"gpu": gpu_model()} if self.device.type == "cuda" else {}
        return {"cpu": cpu_model(), "vector_unit": cpu_vector_unit(), "cores": os.cpu_count(), **gpu}

    def stopped(self) -> dict:
        """The summary of a run stopped at its wall-time limit (its checkpoint is written)."""
        return {"variant": self.variant, "env_id": self.env_id, "env_kwargs": env_kwargs_key(self.env_kwargs),
                "stopped": True, "env_steps": self.step, "updates": self.agent.num_updates,
                "episodes": self.episodes, "wall_s": round(self.wall(), 3),
                "machine": self.machine(), "config": self.cfg.to_dict(), "set": self.set_overrides}

    def actor_meta(self) -> dict:
        """What an actor file of this run records besides its weights."""
        return {"variant": self.variant, "env_id": self.env_id, "env_kwargs": env_kwargs_key(self.env_kwargs),
                "config": self.cfg.to_dict(), "env_steps": self.step,
                "updates": self.agent.num_updates, "seed": self.cfg.seed, "torch": str(torch.__version__)}

    def write_start_actor(self) -> None:
        """``actor_start.pt``: the policy before RL (the clone after imitation, else the untrained net),
        the one curve.csv's step-0 row evaluates, so that what RL adds can be measured on the stored
        sets (``egosearch evaluate --actor .../actor_start.pt``). Written once, before the first
        checkpoint: a run that resumes keeps it."""
        atomic_write(self.out_dir / START_ACTOR_NAME,
                     lambda f: torch.save(self.agent.actor_state({**self.actor_meta(), "start": True}), f))

    def write_snapshot(self, at_step: int) -> None:
        """``actor_<N>k.pt``: the actor as it is at env step ``at_step`` (``actor_snapshot_every``), its metadata
        saying so; a resumed run writes again what its checkpoint had not reached."""
        atomic_write(self.out_dir / snapshot_name(at_step),
                     lambda f: torch.save(self.agent.actor_state({**self.actor_meta(), "snapshot_at": at_step}), f))

    def finish(self, last_row: dict | None) -> dict:
        """Write actor.pt, then done.json (the run is complete), then drop the checkpoint."""
        if last_row is None:  # resumed exactly at the end: the last curve row is already written
            import csv

            with open(self.curve.path) as f:
                rows = list(csv.DictReader(f))
            last_row = {k: float(v) for k, v in rows[-1].items()} if rows else {}
        cfg, agent, key = self.cfg, self.agent, env_kwargs_key(self.env_kwargs)
        meta = self.actor_meta()
        atomic_write(self.out_dir / "actor.pt", lambda f: torch.save(agent.actor_state(meta), f))
        summary = {"variant": self.variant, "env_id": self.env_id, "env_kwargs": key,
                   "env_steps": self.step, "updates": agent.num_updates,
                   "episodes": self.episodes, "wall_s": round(self.wall(), 3), "actor": "actor.pt",
                   "final_eval": {k: (None if isinstance(v, float) and math.isnan(v) else v)
                                  for k, v in last_row.items()},
                   # wall_s is core time only on the machine that ran it: the budget study shows which
                   "machine": self.machine(),
                   "config": cfg.to_dict(), "set": self.set_overrides}
        if self.demo_summary is not None:
            summary["demonstrations"] = self.demo_summary
        if self.imitation["dagger"]:
            summary["dagger"] = self.imitation["dagger"]
        if "cpu_s" in self.imitation:
            summary["imitation"] = {k: self.imitation[k] for k in ("cpu_s", "wall_s", "bc_updates")}
        atomic_json(self.done_path, summary)
        if not cfg.keep_checkpoint:
            for demos in (self.demos_path, summary_path(self.demos_path)):
                demos.unlink(missing_ok=True)
        if not cfg.keep_checkpoint and self.ckpt_path.exists():
            self.ckpt_path.unlink()
            try:
                self.ckpt_path.parent.rmdir()
            except OSError:  # not empty: leave other files alone
                pass
        return summary
