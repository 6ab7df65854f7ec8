"""The training envs: what a training (:mod:`egosearch.rl.train`) and its demonstrations
(:mod:`egosearch.rl.demos`) step, built from the variant's env and the learner config's training aids."""

from __future__ import annotations

import gymnasium

from egosearch.envs import observation_kwargs
from egosearch.rl.config import LearnerConfig
from egosearch.rl.training_aids import critic_reads_state
from egosearch.scene.layouts import LAYOUT_NAMES
from egosearch.sim.body import AgentSpec
from egosearch.sim.home_pool import HomePoolEnv
from egosearch.sim.observation_options import byte_valued_tail, frame_offsets


def stack_offsets(cfg: LearnerConfig) -> tuple[int, ...]:
    """The frames of the depth stacks the env gives under ``cfg``'s observation options (steps back, oldest
    first): what every replay of the run (its own, its demonstrations, a DAgger round's) rebuilds."""
    return frame_offsets(observation_kwargs(cfg.to_dict()), cfg.frame_history)


def replay_layout(cfg: LearnerConfig) -> dict:
    """What every replay of a run under ``cfg`` is built with besides its sizes: the depth stacks' frames
    (:func:`stack_offsets`) and how many of mask's last values are an image it stores as bytes."""
    return {"frame_offsets": stack_offsets(cfg), "mask_bytes": byte_valued_tail(observation_kwargs(cfg.to_dict()))}


def make_train_env(env_id: str, env_kwargs: dict):
    """One training env: a pool of homes for ``layout`` "generated" or "paper_homes", else ``env_id`` itself."""
    if env_kwargs.get("layout") in ("generated", "paper_homes"):  # several homes (egosearch.sim.home_pool)
        if env_kwargs["layout"] == "paper_homes":
            return HomePoolEnv(env_id, home_names=LAYOUT_NAMES, **env_kwargs)
        return HomePoolEnv(env_id, **env_kwargs)
    return gymnasium.make(env_id, **env_kwargs)


def train_env_kwargs(cfg: LearnerConfig, env_kwargs: dict) -> dict:
    """The training envs' keyword arguments: the variant's, with r_d's form
    (``train_distance_reward``) and the training heights (``train_height_min``) from the learner
    config unless the variant sets ``distance_reward`` / ``train_heights`` itself, and the
    privileged state when the critic reads it (``critic_privileged_state``), and the observation options
    the config turns on (``contact_signal``: the policy observes them at evaluation too). The paper's values
    are the env's defaults, so they are not passed (envs without the options still train)."""
    aids: dict = dict(observation_kwargs(cfg.to_dict()))
    if cfg.train_distance_reward != "distance":
        aids["distance_reward"] = cfg.train_distance_reward
    paper_low, paper_high = AgentSpec().train_height_range
    if cfg.train_height_min != paper_low:
        aids["train_heights"] = (cfg.train_height_min, paper_high)
    if critic_reads_state(cfg):
        aids["privileged_state"] = True
    return {**aids, **env_kwargs}
