"""Recurrent SAC-DrQ's own settings (:mod:`egosearch.rl.sac_drq_recurrent`, a lever): SAC-DrQ's input,
networks and SAC settings, and its GRUs and replayed sequences. Registered with the learner in
:mod:`egosearch.rl.learner_registry`."""

from __future__ import annotations

from dataclasses import dataclass

from egosearch.rl.network_settings import RandomShiftSettings, SacSettings
from egosearch.rl.run_settings import Complaint
from egosearch.rl.training_aids import DemonstrationSettings, PrivilegedCriticSettings


@dataclass
class SacDrqRecurrentSettings(PrivilegedCriticSettings, DemonstrationSettings, SacSettings, RandomShiftSettings):
    """The settings recurrent SAC-DrQ reads beyond the run settings: a privileged critic and the demonstrations
    (imitation on sequences, then fine-tuning, as SAC-DrQ's), SAC's and the shifted input's, and its own."""

    recurrent_hidden_dim: int = 128
    """Ni et al. 2022 (a separate GRU for the actor and for the critic; 128 units is ours),
    "sac_drq_recurrent" only; the paper has no recurrent policy: units of the GRU state of the
    actor and, separately, of the critic. A
    recurrent policy CHANGES THE ALGORITHM (the paper's actor is memoryless given K frames)."""
    sequence_length: int = 8
    """Kapturowski et al. 2019 (R2D2: replayed sequences), "sac_drq_recurrent" only; the paper
    replays single transitions: steps of each replayed sequence that carry the losses. An update
    draws ``batch_size // sequence_length`` sequences, so ``batch_size`` still counts the steps a
    loss is taken on. Training on sequences CHANGES THE ALGORITHM (a recurrent policy is not the
    paper's)."""
    burn_in: int = 8
    """Kapturowski et al. 2019 (R2D2's burn-in; Ni et al. 2022 replay whole episodes instead),
    "sac_drq_recurrent" only; the paper has none: steps before each replayed sequence that only
    warm its hidden state up from zero (no gradient, no loss). Part of a recurrent learner, which
    CHANGES THE ALGORITHM."""

    def own_checks(self, bad: Complaint) -> None:
        if self.recurrent_hidden_dim < 1 or self.sequence_length < 1:
            bad("recurrent_hidden_dim" if self.recurrent_hidden_dim < 1 else "sequence_length", "an integer >= 1")
        if self.burn_in < 0:
            bad("burn_in", "an integer >= 0")
        window = self.burn_in + self.sequence_length
        if self.init_steps // self.num_envs < window:
            # each env ring must hold a whole window when the first update samples one
            bad("init_steps", f">= num_envs * (burn_in + sequence_length) = {self.num_envs * window}")
