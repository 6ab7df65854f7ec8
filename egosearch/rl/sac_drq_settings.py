"""SAC-DrQ's own settings (the cpu preset's learner, :mod:`egosearch.rl.sac_drq`): its pooled input and
random shift, and the two changes of its critic and encoder a lever may make; beside them the networks
and SAC's settings of :mod:`egosearch.rl.network_settings` and the training aids of
:mod:`egosearch.rl.training_aids`. Registered with the learner in
:mod:`egosearch.rl.learner_registry`."""

from __future__ import annotations

from dataclasses import dataclass

from egosearch.rl.network_settings import RandomShiftSettings, SacSettings
from egosearch.rl.run_settings import Complaint
from egosearch.rl.training_aids import DemonstrationSettings, PrivilegedCriticSettings

ENCODER_AUX_LOSSES = ("none", "reconstruction")
"""Auxiliary losses on the "sac_drq" encoder (see ``LearnerConfig.encoder_aux_loss``)."""


@dataclass
class SacDrqSettings(PrivilegedCriticSettings, DemonstrationSettings, SacSettings, RandomShiftSettings):
    """The settings SAC-DrQ reads beyond the run settings: a privileged critic and the demonstrations
    (:mod:`egosearch.rl.training_aids`), the networks, SAC's and the pooled, shifted input's settings, and its
    own."""

    critic_layer_norm: bool = False
    """Paper: False (Table 2's Q-functions are plain MLPs). True ("sac_drq" only): a LayerNorm after
    every hidden Linear layer of each Q-function MLP, before its activation, as RLPD (Ball et al. 2023,
    *Efficient online reinforcement learning with offline data*) found needed to keep a critic that
    learns from demonstrations in every batch from extrapolating wildly. A change of the critic's
    architecture: the ``head_on_imitation_finetune_critic_ln`` lever, no preset's default."""

    encoder_aux_loss: str = "none"
    """Paper: "none" for "sac_drq" (the paper's encoder has CURL's contrastive loss beside the
    critic's; "sac_drq" drops it, so only the critic trains its encoder). "reconstruction"
    ("sac_drq" only): SAC-AE's auxiliary loss (Yarats et al. 2019, *Improving sample efficiency in
    model-free reinforcement learning from images*): a decoder rebuilds the newest depth frame,
    pooled and shifted as the encoder saw it, from the conv features, and its squared error trains
    the encoder beside the critic's loss, so the features the actor reads keep the free space a
    critic with the privileged state may not need. A loss the paper's learner does not have: it
    CHANGES THE ALGORITHM; the ``head_on_encoder_aux`` lever, no preset's default. TRAINING ONLY:
    the decoder is not part of the actor file."""
    encoder_aux_weight: float = 1.0
    """SAC-AE (Yarats et al. 2019): 1 on pixels in [-0.5, 0.5]: the weight of
    ``encoder_aux_loss`` against the critic's loss; read only when that loss is on."""

    def own_checks(self, bad: Complaint) -> None:
        if self.encoder_aux_loss not in ENCODER_AUX_LOSSES:
            bad("encoder_aux_loss", ", ".join(ENCODER_AUX_LOSSES))
        if self.encoder_aux_weight < 0:
            bad("encoder_aux_weight", ">= 0")
