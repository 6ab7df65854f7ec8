"""PPO on SAC-DrQ's actor: a learner that spends cheap env steps (not the paper's, nor a preset's).

A lever for the searcher's ceiling: SAC replays each transition many times (the cpu preset:
16 sampled transitions per env step), PPO (Schulman et al. 2017) uses each one a few times
(``ppo_epochs``) and then drops it, so the same core-hours buy several times the env steps, as
habitat-baselines trains PointNav / ObjectNav (DD-PPO, Wijmans et al. 2020). An on-policy
learner CHANGES THE ALGORITHM (the paper's is SAC + CURL).

- The actor is SAC-DrQ's, unchanged (:class:`egosearch.rl.pooled.PooledAgent`):
  :class:`egosearch.rl.pooled.PooledConvEncoder` on the pooled depth + the common
  :class:`egosearch.rl.common.ActorHead` (mu, log_std) and its tanh-squashed Gaussian. Its actor
  file IS a SAC-DrQ actor file (same format, arch and keys), so evaluation runs it as tanh(mu)
  with no change.
- The value network has its own encoder (an actor-critic with shared features would let the
  value loss move the policy's features); with ``critic_privileged_state`` it also reads the env's
  hidden ``state`` (asymmetric actor-critic, Pinto et al. 2018); the actor never does.
- Data: the training loop stores transitions in its replay as for SAC and calls ``update`` every
  ``update_every`` env steps; :meth:`PpoAgent.sample_batch` hands the update the newest
  ``update_every / num_envs`` transitions of each env's ring in time order, i.e. exactly the
  rollout collected since the last update by the current networks. So the update recomputes the
  behaviour log-probabilities and values with the networks as they are before it (nothing
  changed them since those actions were taken) instead of storing them.
- GAE(lambda) advantages (:func:`gae`), the clipped surrogate (:func:`clipped_surrogate`), a value
  loss, an entropy bonus, per-minibatch advantage normalisation and gradient-norm clipping, as in
  habitat-baselines and CleanRL. No augmentation: a random shift would make the ratio compare
  probabilities of different images (DrAC, Raileanu et al. 2021).
- ``update`` returns the shared metric keys: ``critic_loss`` = value loss, ``actor_loss`` =
  clipped surrogate loss, ``entropy`` = the Gaussian's entropy before the tanh (as SAC logs it),
  ``q_mean`` = mean value of the rollout's observations, ``alpha`` = ``entropy_coef``.
  ``num_updates`` counts minibatch steps (``ppo_epochs * ppo_minibatches`` per rollout), the
  counterpart of SAC's gradient updates.
"""

from __future__ import annotations

import math
from typing import Any

import torch
import torch.nn.functional as F
from torch import nn

from egosearch.rl.common import (
    LOG_2PI,
    Projection,
    actor_head,
    adam,
    check_agent_state,
    gaussian_entropy,
    metric_values,
    mlp,
    squashed_sample,
    weight_init,
)
from egosearch.rl.config import LearnerConfig
from egosearch.rl.pooled import PooledAgent, pooled_encoder
from egosearch.rl.replay import MultiReplay

AGENT_FORMAT = "egosearch-ppo-agent-v1"
ACTION_LIMIT = 1.0 - 1e-6
"""Stored actions are clamped to this before the atanh: a float32 tanh rounds to exactly +-1."""


def squashed_log_prob(mu: torch.Tensor, log_std: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
    """log pi(action) (B, 1) of the tanh-squashed Gaussian for an action already squashed, with
    the same tanh correction as :func:`egosearch.rl.common.squashed_sample` (which it inverts).
    In a probability ratio of two policies the correction cancels; it is kept so that the values
    are the policy's log-densities."""
    action = action.clamp(-ACTION_LIMIT, ACTION_LIMIT)
    noise = (torch.atanh(action) - mu) / log_std.exp()
    log_pi = (-0.5 * noise.pow(2) - log_std).sum(-1, keepdim=True) - 0.5 * LOG_2PI * noise.size(-1)
    return log_pi - torch.log(F.relu(1 - action.pow(2)) + 1e-6).sum(-1, keepdim=True)


def gae(reward: torch.Tensor, value: torch.Tensor, next_value: torch.Tensor, terminated: torch.Tensor,
        ended: torch.Tensor, gamma: float, lam: float) -> tuple[torch.Tensor, torch.Tensor]:
    """GAE(lambda) advantages and returns (Schulman et al. 2016) of (N envs, T steps) rollouts.

    ``next_value[:, t]`` is the value of step t's own next observation, so a step bootstraps at a
    truncation and at the rollout's end alike, and not at a termination (``terminated``); the
    advantage's sum stops at every episode end (``ended`` = terminated or truncated)."""
    advantages = torch.zeros_like(reward)
    running = torch.zeros_like(reward[:, 0])
    for t in reversed(range(reward.shape[1])):
        delta = reward[:, t] + gamma * (1.0 - terminated[:, t]) * next_value[:, t] - value[:, t]
        running = delta + gamma * lam * (1.0 - ended[:, t]) * running
        advantages[:, t] = running
    return advantages, advantages + value


def clipped_surrogate(log_pi: torch.Tensor, old_log_pi: torch.Tensor, advantage: torch.Tensor,
                      clip: float) -> torch.Tensor:
    """PPO's clipped surrogate as a loss to minimise (Schulman et al. 2017, eq. 7, negated)."""
    ratio = (log_pi - old_log_pi).exp()
    return -torch.min(ratio * advantage, ratio.clamp(1.0 - clip, 1.0 + clip) * advantage).mean()


class ValueNet(nn.Module):
    """Own encoder + projection + MLP -> V(s); ``extra`` holds mask, proprio (and the state)."""

    def __init__(self, arch: dict[str, Any], extra_dim: int):
        super().__init__()
        self.encoder = pooled_encoder(arch)
        self.proj = Projection(self.encoder.out_dim, arch["encoder_latent_dim"], arch["encoder_tanh"])
        self.head = mlp(arch["encoder_latent_dim"] + extra_dim, arch["critic_hidden_dim"], 1,
                        arch["critic_num_layers"], arch["critic_activation"])

    def forward(self, pooled: torch.Tensor, extra: torch.Tensor) -> torch.Tensor:
        return self.head(torch.cat([self.proj(self.encoder(pooled)), extra], dim=-1)).squeeze(-1)


class PpoAgent(PooledAgent):
    """PPO with SAC-DrQ's actor and a separate value network (module docstring). Driven by
    :mod:`egosearch.rl.train` like the SAC learners; ``sample_batch`` picks its rollout. Its actor
    file is SAC-DrQ's (:data:`egosearch.rl.pooled.DRQ_ACTOR_FORMAT`): evaluation loads it as any other."""

    agent_format = AGENT_FORMAT
    MODULES = ("encoder", "actor", "value")
    """The networks in the agent state, in its order."""

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30, proprio_dim: int = 4,
                 device: str | torch.device | None = None, state_dim: int = 0):
        self.cfg = cfg.validate()
        if cfg.algorithm != "ppo":
            raise ValueError(f"PpoAgent needs algorithm ppo, not {cfg.algorithm!r}")
        self.set_inputs(device, action_dim, mask_dim, proprio_dim, state_dim)
        arch = self.arch()
        self.encoder = pooled_encoder(arch)
        self.actor = actor_head(self.encoder.out_dim, arch)
        self.value = ValueNet(arch, arch["extra_dim"] + self.state_dim)
        for net in (self.encoder, self.actor, self.value):
            net.apply(weight_init)
        self._start_wide(cfg.ppo_init_std)
        for net in (self.encoder, self.actor, self.value):
            net.to(self.device)
        if cfg.channels_last:
            self.encoder.use_channels_last()
            self.value.encoder.use_channels_last()
        self.num_updates = 0
        self.actor_params = [*self.encoder.parameters(), *self.actor.parameters()]
        self.optimisers = {"actor": adam(self.actor_params, cfg.actor_lr, (cfg.actor_beta1, cfg.actor_beta2)),
                           "value": adam(self.value.parameters(), cfg.critic_lr, (cfg.critic_beta1, cfg.critic_beta2))}

    def _start_wide(self, std: float) -> None:
        """Andrychowicz et al. 2021: the last policy layer x 0.01, so that the first actions hardly
        depend on the observation, and the log-std output's bias set so that std starts at ``std``
        (through the head's tanh rescaling into [log_std_min, log_std_max])."""
        last = self.actor.trunk[-1]
        lo, hi = self.actor.log_std_min, self.actor.log_std_max
        with torch.no_grad():
            last.weight.mul_(0.01)
            last.bias[self.action_dim:] = math.atanh(2.0 * (math.log(std) - lo) / (hi - lo) - 1.0)

    @property
    def alpha(self) -> float:
        """The entropy bonus's weight: SAC's temperature's counterpart in the logs."""
        return float(self.cfg.entropy_coef)

    # ---- updating ------------------------------------------------------------------------
    def sample_batch(self, replay: MultiReplay) -> dict[str, torch.Tensor]:
        """The rollout: each env ring's newest ``update_every / num_envs`` transitions in time order,
        stacked as (N envs, T steps, ...)."""
        steps = self.cfg.update_every // self.cfg.num_envs
        rings = [replay.latest(i, steps) for i in range(len(replay.buffers))]
        return {k: torch.stack([r[k] for r in rings]) for k in rings[0]}

    def _value_extra(self, batch: dict[str, torch.Tensor], prefix: str = "") -> torch.Tensor:
        parts = [batch[prefix + "mask"], batch[prefix + "proprio"]]
        if self.state_dim:
            parts.append(batch[prefix + "state"])
        return torch.cat(parts, dim=-1)

    def _advantages(self, batch: dict[str, torch.Tensor], obs: torch.Tensor, value_extra: torch.Tensor):
        """(behaviour log pi, advantages, returns, values) of the flattened rollout, from the networks
        as they were while it was collected."""
        n, t = batch["reward"].shape[:2]
        terminated = 1.0 - batch["not_done"].reshape(n, t)
        ended = torch.clamp(terminated + batch["truncated"].reshape(n, t), max=1.0)
        with torch.no_grad():
            mu, log_std = self.actor(self.encoder(obs), torch.cat([batch["mask"], batch["proprio"]], -1).flatten(0, 1))
            old_log_pi = squashed_log_prob(mu, log_std, batch["action"].flatten(0, 1))
            value = self.value(obs, value_extra).reshape(n, t)
            # next_obs of a step inside an episode is the obs of the step after it: only the steps
            # that end an episode or the rollout need their next observation's value computed
            next_value = torch.cat([value[:, 1:], torch.zeros_like(value[:, :1])], dim=1)
            need = ended.bool().clone()
            need[:, -1] = True
            if need.any():
                nxt = batch["next_obs_depth"][need].float()
                next_value[need] = self.value(nxt, self._value_extra(batch, "next_")[need])
            advantages, returns = gae(batch["reward"].reshape(n, t), value, next_value, terminated, ended,
                                      self.cfg.gamma, self.cfg.gae_lambda)
        return old_log_pi, advantages.flatten(), returns.flatten(), value

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        """``ppo_epochs`` passes of ``ppo_minibatches`` minibatch steps over the rollout ``batch``
        (:meth:`sample_batch`); the metrics are means over its minibatch steps."""
        cfg = self.cfg
        obs = batch["obs_depth"].flatten(0, 1).float()  # pooled frames, as the replay holds them
        extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1).flatten(0, 1)
        value_extra = self._value_extra(batch).flatten(0, 1)
        action = batch["action"].flatten(0, 1)
        old_log_pi, advantages, returns, value = self._advantages(batch, obs, value_extra)
        size = obs.shape[0]
        sums: dict[str, torch.Tensor] = {}
        steps = 0
        for _ in range(cfg.ppo_epochs):
            for mb in torch.randperm(size, device=self.device).tensor_split(cfg.ppo_minibatches):
                mu, log_std = self.actor(self.encoder(obs[mb]), extra[mb])
                log_pi = squashed_log_prob(mu, log_std, action[mb])
                adv = advantages[mb]
                adv = (adv - adv.mean()) / (adv.std(unbiased=False) + 1e-8)
                policy_loss = clipped_surrogate(log_pi, old_log_pi[mb], adv[:, None], cfg.ppo_clip)
                entropy = -squashed_sample(mu, log_std, torch.randn_like(mu))[1].mean()  # of the squashed policy
                value_loss = 0.5 * (self.value(obs[mb], value_extra[mb]) - returns[mb]).pow(2).mean()
                for opt in self.optimisers.values():
                    opt.zero_grad(set_to_none=True)
                (policy_loss - cfg.entropy_coef * entropy + cfg.value_coef * value_loss).backward()
                nn.utils.clip_grad_norm_(self.actor_params, cfg.max_grad_norm)
                nn.utils.clip_grad_norm_(self.value.parameters(), cfg.max_grad_norm)
                for opt in self.optimisers.values():
                    opt.step()
                steps += 1
                for key, v in (("critic_loss", value_loss), ("actor_loss", policy_loss),
                               ("entropy", gaussian_entropy(log_std))):
                    sums[key] = sums.get(key, 0.0) + v.detach()
        self.num_updates += steps
        out = {k: v / steps for k, v in sums.items()}
        out["q_mean"] = value.mean()
        out["alpha"] = torch.tensor(cfg.entropy_coef, device=self.device)
        return metric_values(out, self.device)

    # ---- persistence -----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        return self.agent_state(self.MODULES)

    def load_state_dict(self, state: dict[str, Any]) -> None:
        check_agent_state(state, AGENT_FORMAT, "PPO", self.arch())
        self.restore(state, self.MODULES)
