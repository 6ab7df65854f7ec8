"""The settings the learners build from: the networks every learner here has (actor, critic, encoder),
SAC's temperature and target networks, and the pooled depth input of the SAC-DrQ family.

Each learner's own settings class (:mod:`egosearch.rl.sac_curl_settings` and its siblings) is a
dataclass made of these, as its agent class is made of :mod:`egosearch.rl.pooled`'s pieces; a learner has
exactly the fields it reads. Each class's :meth:`own_checks` checks its own fields' ranges (and their
rules with the run settings), and ``LearnerConfig.validate`` calls those of every class a config is made of.
"""

from __future__ import annotations

from dataclasses import dataclass

from egosearch.rl.run_settings import Complaint

ACTIVATIONS = ("relu", "elu", "leaky_relu", "gelu", "tanh")
"""Activation names the networks understand (Table 2 uses ReLU everywhere)."""


@dataclass
class NetworkSettings:
    """Table 2's actor, critic and encoder, as far as every learner here has them (PPO's critic is its
    value network)."""

    # ---- Table 2: actor -----------------------------------------------------------------
    actor_lr: float = 1e-3
    """Table 2 "Actor: learning rate"."""
    actor_beta1: float = 0.9
    """Table 2 "Actor: optimizer beta1"."""
    actor_beta2: float = 0.999
    """Table 2 "Actor: optimizer beta2"."""
    actor_num_layers: int = 4
    """Table 2 "Actor: Number of layers" = 4. A *layer* here is one fully connected (Linear)
    layer of the actor's MLP that follows the image embedding, COUNTING THE OUTPUT LAYER and
    not counting the encoder: 4 = three hidden layers of ``actor_hidden_dim`` units + the
    output layer (mean and log-std). This reading also matches the text of 4.2 ("3 fully
    connected layers with 1024 neurons to obtain the final action output"); we follow Table 2.
    Note: CURL's reference code has 2 hidden layers (3 Linear layers) and its ``--num_layers 4``
    is the encoder's conv depth, which is probably where Table 2's "4" comes from; set 3 here
    to get CURL's exact MLP."""
    actor_hidden_dim: int = 1024
    """Table 2 "Actor: Hidden dim": units of every hidden layer of the actor MLP."""
    actor_activation: str = "relu"
    """Table 2 "Actor: Activation function"."""
    actor_log_std_min: float = -10.0
    """CURL: lower bound of the actor's log-std (tanh-rescaled into [min, max])."""
    actor_log_std_max: float = 2.0
    """CURL: upper bound of the actor's log-std."""

    # ---- Table 2: critic ----------------------------------------------------------------
    critic_lr: float = 1e-3
    """Table 2 "Critic: learning rate" (also trains the encoder through the critic loss)."""
    critic_beta1: float = 0.9
    """Table 2 "Critic: optimizer beta1"."""
    critic_beta2: float = 0.999
    """Table 2 "Critic: optimizer beta2"."""
    critic_num_layers: int = 4
    """Table 2 "Critic: Number of layers": Linear layers of EACH Q-function MLP, counting the
    output layer (4 = three hidden layers of ``critic_hidden_dim`` + the scalar output). Same
    counting rule as ``actor_num_layers``; CURL's code has 3."""
    critic_hidden_dim: int = 1024
    """Table 2 "Critic: Hidden dim"."""
    critic_activation: str = "relu"
    """Table 2 "Critic: Activation function"."""

    # ---- Table 2: encoder ---------------------------------------------------------------
    encoder_num_layers: int = 4
    """Table 2 "Encoder (CNN): Number of layers": 3x3 conv layers, the first with stride 2 and
    the rest with stride 1 (CURL's pixel encoder); 84x84 -> 41 -> 39 -> 37 -> 35."""
    encoder_num_filters: int = 32
    """Table 2 "Encoder (CNN): Number of filters": channels of every conv layer."""
    encoder_latent_dim: int = 128
    """Table 2 "Encoder (CNN): Latent dimension" (paper 4.2: "an embedding of 128 dimensions"):
    output of the linear projection + LayerNorm that follows the convs."""
    encoder_activation: str = "relu"
    """Table 2 "Encoder (CNN): Activation function"."""
    encoder_tanh: bool = False
    """CURL: no tanh after the LayerNorm. CURL's ``PixelEncoder`` only applies tanh when
    ``output_logits=False``, and its actor and critic build it with ``output_logits=True``."""

    def own_checks(self, bad: Complaint) -> None:
        for name in ("actor_hidden_dim", "critic_hidden_dim", "encoder_num_filters", "encoder_latent_dim"):
            if getattr(self, name) < 1:
                bad(name, "an integer >= 1")
        for name in ("actor_num_layers", "critic_num_layers"):
            if getattr(self, name) < 2:
                bad(name, "an integer >= 2 (Linear layers incl. the output layer)")
        if self.encoder_num_layers < 1:
            bad("encoder_num_layers", "an integer >= 1")
        for name in ("actor_lr", "critic_lr"):
            if getattr(self, name) <= 0:
                bad(name, "> 0")
        for name in ("actor_beta1", "critic_beta1", "actor_beta2", "critic_beta2"):
            if not 0.0 <= getattr(self, name) < 1.0:
                bad(name, "[0, 1)")
        if self.actor_log_std_min >= self.actor_log_std_max:
            bad("actor_log_std_min", f"< actor_log_std_max={self.actor_log_std_max}")
        for name in ("actor_activation", "critic_activation", "encoder_activation"):
            if getattr(self, name) not in ACTIVATIONS:
                bad(name, ", ".join(ACTIVATIONS))


@dataclass
class SacSettings(NetworkSettings):
    """SAC's temperature, its critic's target and the schedule of its actor and target steps (SAC + CURL
    and the SAC-DrQ learners)."""

    # ---- Table 2: temperature -----------------------------------------------------------
    init_temperature: float = 0.1
    """Table 2 "Alpha (SAC): initial temperature"."""
    alpha_lr: float = 1e-4
    """Table 2 "Alpha (SAC): learning rate" (Adam on log alpha)."""
    alpha_beta1: float = 0.5
    """Table 2 "Alpha (SAC): optimizer beta1"."""
    alpha_beta2: float = 0.999
    """Table 2 "Alpha (SAC): optimizer beta2"."""

    # ---- Table 2: critic target and encoder step ----------------------------------------
    critic_tau: float = 0.01
    """Table 2 "Critic: tau (polyak averaging)": target Q-heads move by this fraction."""
    encoder_lr: float = 1e-3
    """Table 2 "Encoder (CNN): learning rate". SAC+CURL: Adam step of the CURL (contrastive) loss on the
    encoder and on the bilinear matrix W. SAC-DrQ, its recurrent form and PPO's actor: the encoder's own
    learning rate inside the critic's optimiser (the critic's loss trains the encoder; no contrastive loss)."""

    # ---- CURL's schedule (not in Table 2) -----------------------------------------------
    actor_update_freq: int = 2
    """CURL: the actor and temperature are updated every this many gradient updates."""
    critic_target_update_freq: int = 2
    """CURL: the target critic and key encoder are Polyak-averaged every this many updates."""

    def own_checks(self, bad: Complaint) -> None:
        for name in ("actor_update_freq", "critic_target_update_freq"):
            if getattr(self, name) < 1:
                bad(name, "an integer >= 1")
        for name in ("alpha_lr", "encoder_lr", "init_temperature"):
            if getattr(self, name) <= 0:
                bad(name, "> 0")
        if not 0.0 < self.critic_tau <= 1.0:
            bad("critic_tau", "(0, 1]")
        for name in ("alpha_beta1", "alpha_beta2"):
            if not 0.0 <= getattr(self, name) < 1.0:
                bad(name, "[0, 1)")


@dataclass
class PooledSettings:
    """The pooled depth input of the SAC-DrQ family (``egosearch.rl.pooled.PooledConvEncoder``): depth
    average-pooled, then convs of which the first few have stride 2."""

    obs_downsample: int = 1
    """Ours (the pooled learners, every one with these settings: sac_drq, sac_drq_recurrent, ppo; the paper: 1):
    the 100 x 100 depth frames are average-pooled by this
    factor before the encoder (2 -> 50 x 50), as PointNav learners train from 64 x 64 depth
    (Shacklett et al., bps-nav, ICLR 2021). The env, its mask and success test stay at 100 x 100.
    The ``cpu`` preset sets 2 (see :func:`cpu_preset`)."""
    encoder_stride2_layers: int = 1
    """CURL: 1 (the first conv has stride 2, the rest stride 1). The pooled learners (sac_drq,
    sac_drq_recurrent, ppo): the first this many convs have stride 2 (smaller maps, far fewer FLOPs)."""

    def own_checks(self, bad: Complaint) -> None:
        if self.obs_downsample < 1:
            bad("obs_downsample", "an integer >= 1")
        if not 0 <= self.encoder_stride2_layers <= self.encoder_num_layers:
            bad("encoder_stride2_layers", f"0..encoder_num_layers={self.encoder_num_layers}")
        side = self.image_size // self.obs_downsample
        for i in range(self.encoder_num_layers):
            side = (side - 3) // (2 if i < self.encoder_stride2_layers else 1) + 1
        if side < 1:
            bad("encoder_num_layers", f"fewer layers or stride-2 layers for image_size={self.image_size} "
                f"and obs_downsample={self.obs_downsample} (the conv output would be empty)")


@dataclass
class RandomShiftSettings(PooledSettings):
    """DrQ-v2's random shift of the pooled frames in SAC-DrQ's updates."""

    aug_pad: int = 4
    """DrQ-v2: 4 (the SAC-DrQ learners: sac_drq, sac_drq_recurrent): the random shift pads by this many
    pixels (replicating the border) and crops back to the pooled size. "sac_curl" uses Table 2's random
    crop instead."""

    def own_checks(self, bad: Complaint) -> None:
        if self.aug_pad < 0:
            bad("aug_pad", "an integer >= 0")
