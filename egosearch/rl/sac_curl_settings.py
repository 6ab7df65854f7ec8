"""SAC + CURL's own settings (the paper's learner, :mod:`egosearch.rl.sac_curl`): Table 2's random crop,
the key encoder's Polyak step and optimiser, and CURL's contrastive loss; beside them the networks and
SAC's settings of :mod:`egosearch.rl.network_settings`. Registered with the learner in
:mod:`egosearch.rl.learner_registry`."""

from __future__ import annotations

from dataclasses import dataclass

from egosearch.rl.network_settings import SacSettings
from egosearch.rl.run_settings import Complaint


@dataclass
class SacCurlSettings(SacSettings):
    """The settings SAC + CURL reads beyond the run settings (paper 4.2, Table 2, CURL's reference code)."""

    # ---- Table 2: augmentation and the key encoder ----------------------------------------
    crop_size: int = 84
    """Table 2 "Augmentation: Random Crop (84x84)": side of the random crop fed to the encoder
    during updates (a centre crop when acting)."""
    encoder_tau: float = 0.05
    """Table 2 "Encoder (CNN): tau (polyak averaging)": the key / target encoder moves by this
    fraction (conv layers, linear projection and LayerNorm)."""
    encoder_beta1: float = 0.9
    """CURL (not in Table 2): beta1 of the encoder / CURL optimiser (PyTorch's Adam default)."""
    encoder_beta2: float = 0.999
    """CURL (not in Table 2): beta2 of the encoder / CURL optimiser (PyTorch's Adam default)."""

    # ---- CURL (not in Table 2) ----------------------------------------------------------
    curl_latent: int = 128
    """CURL: side of the bilinear matrix W (logits = q W k^T). It acts on the encoder
    embedding, so it must equal ``encoder_latent_dim`` (CURL builds W from the encoder's
    feature dim; its ``curl_latent_dim`` argument is unused)."""
    curl_double_encoder_step: bool = True
    """CURL: its reference code registers the critic's encoder in BOTH ``encoder_optimizer``
    and ``cpc_optimizer`` (both Adam at ``encoder_lr``), so every contrastive gradient is applied
    twice. The two Adam states see identical gradients, so this equals one Adam step at
    2 x ``encoder_lr`` on the encoder (W keeps 1 x). True reproduces that; False applies the
    contrastive step once."""
    curl_update_freq: int = 1
    """CURL (``cpc_update_freq``): the contrastive loss is applied every this many updates."""

    # ---- implementation (ours) ----------------------------------------------------------
    share_encoder_forward: bool = False
    """Ours, OFF by default: compute the anchor crop's conv features once per update, BEFORE
    the critic's optimiser step, and reuse them for the CURL query and (detached) the actor.
    That saves one conv forward (~8-10% of an update) but is not CURL's math: CURL computes the
    CURL and actor losses after the critic step, so with True they lag the critic step by one
    update (lr-sized). False (default) reproduces CURL's numbers exactly; the optimised update
    still shares every pass that CURL's order allows (see ``SacCurlAgent._update_fast``)."""

    def own_checks(self, bad: Complaint) -> None:
        for name in ("crop_size", "curl_latent", "curl_update_freq"):
            if getattr(self, name) < 1:
                bad(name, "an integer >= 1")
        if self.crop_size > self.image_size:
            bad("crop_size", f"1..image_size={self.image_size}")
        # 3x3 convs: first stride 2, then stride 1; the last map must keep at least 1 pixel.
        if (self.crop_size - 3) // 2 + 1 - 2 * (self.encoder_num_layers - 1) < 1:
            bad("encoder_num_layers", f"1..{((self.crop_size - 3) // 2 + 1 - 1) // 2 + 1} "
                f"for crop_size={self.crop_size} (the conv output would be empty)")
        if not 0.0 < self.encoder_tau <= 1.0:
            bad("encoder_tau", "(0, 1]")
        for name in ("encoder_beta1", "encoder_beta2"):
            if not 0.0 <= getattr(self, name) < 1.0:
                bad(name, "[0, 1)")
        if self.curl_latent != self.encoder_latent_dim:
            bad("curl_latent", f"equal to encoder_latent_dim={self.encoder_latent_dim}")
