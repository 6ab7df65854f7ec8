"""PPO's own settings (:mod:`egosearch.rl.ppo`, a lever): SAC-DrQ's pooled input and actor, a value
network where SAC has its critic (the critic's fields size it), and the on-policy update's settings.
Registered with the learner in :mod:`egosearch.rl.learner_registry`."""

from __future__ import annotations

import math
from dataclasses import dataclass

from egosearch.rl.network_settings import NetworkSettings, PooledSettings
from egosearch.rl.run_settings import Complaint
from egosearch.rl.training_aids import PrivilegedCriticSettings


@dataclass
class PpoSettings(PrivilegedCriticSettings, NetworkSettings, PooledSettings):
    """The settings PPO reads beyond the run settings (a privileged value network, not demonstrations)."""

    # "ppo" only: PPO is a CHANGE OF ALGORITHM (the paper's learner is SAC + CURL) and no preset uses it.
    # A rollout is the last ``update_every`` env steps (``update_every / num_envs`` per env); an update
    # is ``ppo_epochs`` passes over it in ``ppo_minibatches`` minibatches (each an Adam step of the actor,
    # at ``actor_lr``, and of the value network, at ``critic_lr``).
    ppo_epochs: int = 4
    """habitat-baselines' PointNav PPO configs (``ppo_epoch`` 2 to 4 across its versions; Schulman
    et al. 2017: 3 to 10), "ppo"
    only; the paper's learner is SAC + CURL: passes over each rollout per update."""
    ppo_minibatches: int = 2
    """habitat-baselines' PointNav PPO configs (``num_mini_batch`` 2 to 4 across its versions), "ppo"
    only: minibatches each
    rollout is cut into per pass (a random split each pass)."""
    ppo_clip: float = 0.2
    """Schulman et al. 2017 (PPO's epsilon 0.2; habitat-baselines' ``clip_param`` 0.1 to 0.2), "ppo" only: the
    probability ratio is clipped to [1 - this, 1 + this] in the surrogate loss."""
    gae_lambda: float = 0.95
    """Schulman et al. 2016 (GAE; habitat-baselines' ``tau`` 0.95), "ppo" only: lambda of the
    advantages, which bootstrap from the value of the next observation at a truncation and at the
    rollout's end, never at a termination."""
    value_coef: float = 0.5
    """habitat-baselines' ``value_loss_coef`` 0.5, "ppo" only: weight of the value network's loss
    0.5 (V - R)^2 (the value network shares no weights with the actor, so it only scales its
    gradient before the norm clipping)."""
    entropy_coef: float = 0.01
    """habitat-baselines' ``entropy_coef`` 0.01, "ppo" only: weight of the entropy bonus (a
    one-sample estimate of the tanh-squashed policy's entropy). train.csv's ``alpha`` column
    shows it, the role SAC's temperature plays."""
    max_grad_norm: float = 0.5
    """habitat-baselines' ``max_grad_norm`` 0.5 (Andrychowicz et al. 2021, "What matters in
    on-policy RL": 0.5), "ppo" only: the gradient norm of the actor and, separately, of the value
    network is clipped to this before each step."""
    ppo_init_std: float = 0.5
    """Andrychowicz et al. 2021 (a smaller initial action std than 1 learned better; last policy
    layer scaled by 0.01), "ppo" only: the actor starts with this std of the Gaussian before the
    tanh, whatever the observation. SAC's actor starts near std e^-4 and its temperature widens it;
    PPO has no such force, so it must start wide."""

    def own_checks(self, bad: Complaint) -> None:
        """The rules of an on-policy update on the rollout the loop leaves in the replay."""
        for name in ("ppo_epochs", "ppo_minibatches"):
            if getattr(self, name) < 1:
                bad(name, "an integer >= 1")
        if self.n_step != 1:
            bad("n_step", "1 for algorithm ppo (GAE takes one-step transitions)")
        if self.init_steps != 0:
            bad("init_steps", "0 for algorithm ppo (a warm-up's random actions would be trained on as the policy's)")
        if self.updates_per_step != 1:
            bad("updates_per_step", "1 for algorithm ppo (a second update would take the updated policy's "
                "probabilities for the behaviour's; passes over a rollout are ppo_epochs)")
        if self.update_every % self.num_envs:
            bad("update_every", f"a multiple of num_envs={self.num_envs} for algorithm ppo (the rollout: "
                "the same number of steps of every env)")
        if self.update_every < self.ppo_minibatches:
            bad("ppo_minibatches", f"1..update_every={self.update_every} (the rollout's transitions)")
        if self.replay_capacity < 2 * self.update_every:
            bad("replay_capacity", f">= 2 * update_every = {2 * self.update_every} for algorithm ppo (each env "
                "ring keeps two rollouts, so that a rollout's frames are never overwritten)")
        for name in ("ppo_clip", "max_grad_norm", "ppo_init_std"):
            if getattr(self, name) <= 0:
                bad(name, "> 0")
        if not self.actor_log_std_min < math.log(self.ppo_init_std) < self.actor_log_std_max:
            bad("ppo_init_std", f"(e^{self.actor_log_std_min}, e^{self.actor_log_std_max}) "
                "(actor_log_std_min, actor_log_std_max)")
        if not 0.0 <= self.gae_lambda <= 1.0:
            bad("gae_lambda", "[0, 1]")
        for name in ("value_coef", "entropy_coef"):
            if getattr(self, name) < 0:
                bad(name, ">= 0")
