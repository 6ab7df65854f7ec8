"""Imitation before RL: behaviour cloning on the teacher's demonstrations (PIRLNav's first phase), then
DAgger rounds (Ross, Gordon & Bagnell 2011) in which the student drives and the teacher labels.

The teacher is the classical frontier searcher of ``demo_teacher`` (by default
:class:`egosearch.searchers.frontier.FrontierPolicy`, untuned; see :data:`egosearch.rl.demos.TEACHERS`). Its
map updates from whatever it sees, so it can label a trajectory it did not drive: at every state the student
reaches it is shown the observation and says what it would do there. Those labels train the student only by
cloning: the stored action is the teacher's, not the one taken, so the transitions are no RL data and never
join the batches of ``demo_batch_fraction``.

:func:`clone` is the cloning loop over any number of sources (the demonstrations, each DAgger round's
labelled states), drawing from each in proportion to its size. :func:`dagger_round` runs one round.
:mod:`egosearch.rl.train` runs both before the first env step of a fresh training.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

import numpy as np
import torch

from egosearch.rl.config import LearnerConfig
from egosearch.rl.demos import new_teacher, stored_observation
from egosearch.rl.replay import MultiReplay, proportional_counts  # noqa: F401 (read here by the tests)
from egosearch.rl.train_env import make_train_env, replay_layout, train_env_kwargs
from egosearch.rl.training_aids import critic_reads_state, demonstration_settings
from egosearch.sim.scenarios import MAX_STEPS

DAGGER_SEED_BASE = 8_000_000
"""Episode i of DAgger round r of a training with seed s resets with seed
DAGGER_SEED_BASE + 100_000 s + 10_000 r + i: apart from the demonstrations' (``rl.demos.DEMO_SEED_BASE``)
and the training curve's evaluation episodes."""
MAX_DAGGER_EPISODES = 10_000
"""A round's episodes stay below the next round's seeds."""
CONTACT_WINDOW = 5
"""With ``dagger_states: contact``, a state is kept when a step at most this many steps before or after
it ran the body into something: the approach the teacher would have turned from, and the push."""


def near_contact(collided: list[bool], window: int = CONTACT_WINDOW) -> list[bool]:
    """For each step t of an episode (``collided[t]``: the step taken from state t ran into something),
    whether some step within ``window`` steps of t, before or after, did."""
    hits = np.flatnonzero(np.asarray(collided, dtype=bool))
    keep = np.zeros(len(collided), dtype=bool)
    for t in hits:
        keep[max(0, t - window):t + window + 1] = True
    return keep.tolist()


def clone(agent, sources: list[MultiReplay], steps: int, batch_size: int, optimiser: torch.optim.Optimizer,
          say: Callable[[str], None] = print, what: str = "behaviour cloning") -> float:
    """``steps`` behaviour-cloning steps of ``agent`` (``clone_update``) on batches drawn from ``sources``
    in proportion to their sizes; returns the mean squared error of the last 100 steps."""
    t0, losses = time.perf_counter(), deque(maxlen=100)
    for i in range(steps):
        losses.append(agent.clone_update(agent.cloning_batch(sources, batch_size), optimiser)["bc_loss"])
        if (i + 1) % max(steps // 10, 1) == 0 or i + 1 == steps:
            say(f"{what} {i + 1}/{steps}: squared error {np.mean(losses):.3f} ({time.perf_counter() - t0:.0f} s)")
    return float(np.mean(losses))


def dagger_round(agent, env_id: str, cfg: LearnerConfig, env_kwargs: dict, episodes: int, round_index: int,
                 device: torch.device | str = "cpu") -> tuple[MultiReplay | None, dict]:
    """One DAgger round: the student (``agent``'s mean action) drives ``episodes`` training-side episodes
    of ``env_id`` under ``cfg``'s training env settings; at every state the teacher says what it would
    do. Returns the labelled states that ``dagger_states`` keeps (one ring, actions = the teacher's labels;
    None if it kept none) and the round's figures: the student's success, the mean squared difference of
    its actions from the labels, the states kept, CPU seconds."""
    if not 1 <= episodes <= MAX_DAGGER_EPISODES:
        raise ValueError(f"episodes={episodes}; allowed: 1..{MAX_DAGGER_EPISODES}")
    only_contact = demonstration_settings(cfg).dagger_states == "contact"
    env = make_train_env(env_id, train_env_kwargs(cfg, env_kwargs))
    cpu0 = time.process_time()
    labelled = None
    successes, differences, reached = [], [], 0
    try:
        for episode in range(episodes):
            obs, _ = env.reset(seed=DAGGER_SEED_BASE + 100_000 * cfg.seed + 10_000 * round_index + episode)
            if labelled is None:
                state_dim = int(np.asarray(obs["state"]).shape[0]) if critic_reads_state(cfg) else 0
                # "contact" writes each kept run's depth stack before it: up to twice the frames per state
                capacity = episodes * MAX_STEPS * (2 if only_contact else 1)
                labelled = MultiReplay(1, capacity, agent.replay_image_size, cfg.frame_history,
                                       int(np.asarray(obs["mask"]).shape[0]), int(np.asarray(obs["proprio"]).shape[0]),
                                       int(env.action_space.shape[0]), device=device, seed=cfg.seed,
                                       state_dim=state_dim, **replay_layout(cfg))
            teacher = new_teacher(env, demonstration_settings(cfg).demo_teacher)
            agent.reset_policy_state()  # a student with a memory starts each episode afresh
            stored = stored_observation(obs, cfg)
            steps, collided = [], []
            terminated = truncated = False
            while not (terminated or truncated):
                label = teacher.act(obs)
                action = agent.act(obs, deterministic=True)
                differences.append(float(np.sum((action - label) ** 2)))
                obs, reward, terminated, truncated, info = env.step(action)
                next_stored = stored_observation(obs, cfg)
                steps.append((stored, label, float(reward), next_stored, terminated, truncated))
                collided.append(bool(info.get("collided", False)))
                stored = next_stored
            reached += len(steps)
            keep = near_contact(collided) if only_contact else [True] * len(steps)
            for t, (step, kept) in enumerate(zip(steps, keep)):
                if not kept:
                    continue
                if t > 0 and not keep[t - 1]:  # a run that starts inside the episode: its own stored episode
                    labelled.end_episodes()
                    labelled.begin_mid_episode(0, step[0])
                labelled.add(0, *step)
            labelled.end_episodes()  # a run may stop before the episode does
            successes.append(bool(terminated))
    finally:
        env.close()
    kept = len(labelled) if labelled is not None else 0
    if labelled is not None and kept != labelled.buffers[0].n_added:
        raise RuntimeError(f"DAgger round: {labelled.buffers[0].n_added - kept} labelled states overwritten")
    figures = {"round": round_index + 1, "episodes": episodes, "transitions": kept, "states_reached": reached,
               "student_success": round(float(np.mean(successes)), 4),
               "squared_difference_from_teacher": round(float(np.mean(differences)), 4),
               "cpu_s": round(time.process_time() - cpu0, 1)}
    return (labelled if kept else None), figures

