"""SAC with a DrQ-v2-style update: the cpu profile's cheaper learner (not the paper's CURL).

What it keeps from SAC + CURL (:mod:`egosearch.rl.sac_curl`): the soft actor-critic losses,
twin critics with Polyak targets, the tanh-Gaussian actor, the automatic temperature, the inputs
(K depth frames + mask feature + proprioception) and every learning rate and beta. The pieces
both learners build from (actor head, layers, crops, observation tensors, actor files) live in
:mod:`egosearch.rl.common`.

What it changes, after DrQ-v2 (Yarats et al. 2021, github.com/facebookresearch/drqv2), to make
one update several times cheaper:

- no contrastive loss, no momentum key encoder: ONE conv encoder, trained by the critic loss
  only; the actor reads its features detached. An update runs the convs twice forward (obs with
  grad, next_obs without) and once backward, against CURL's ~7 forward and 2 backward passes;
- augmentation: random shift (replicate-pad by ``aug_pad`` px and crop back to the same size)
  instead of the 100 -> 84 random crop; acting sees the whole, unshifted image;
- ``obs_downsample``: the depth frames are average-pooled (2 x 2 -> 50 x 50) before the convs,
  as navigation learners train from 64 x 64 depth (Shacklett et al., bps-nav, ICLR 2021);
- ``encoder_stride2_layers`` leading stride-2 convs (CURL: one) shrink the maps further;
- the target critic is a Polyak copy of the critic's projection and Q-heads; the online encoder
  embeds next_obs for the target (DrQ-v2), so there is no target encoder;
- n-step returns (``n_step``; DrQ-v2 uses 3) come from the replay (:class:`MultiReplay`);
- ``critic_privileged_state`` (off unless a config sets it): the Q-heads also read the env's
  hidden ``state`` vector (asymmetric actor-critic); the actor never does.
- ``encoder_aux_loss`` ("none" unless a config sets it): "reconstruction" adds SAC-AE's decoder
  of the newest frame, whose loss trains the encoder beside the critic's (a lever, not a default).

``act`` / ``act_batch`` / ``update`` / ``state_dict`` / ``actor_state`` match
:class:`egosearch.rl.sac_curl.SacCurlAgent`, so :mod:`egosearch.rl.train` drives either.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from egosearch.rl.common import (
    ActorHead,
    AgentStateError,
    Projection,
    activation,
    actor_head,
    actor_weights,
    adam,
    check_agent_state,
    crop_at,
    gaussian_entropy,
    load_actor_weights,
    metric_values,
    mlp,
    obs_to_tensors,
    resolve_device,
    squashed_sample,
    weight_init,
)
from egosearch.rl.config import LearnerConfig

AGENT_FORMAT = "egosearch-sac-drq-agent-v1"
ACTOR_FORMAT = "egosearch-sac-drq-actor-v1"


def pooled_side(image_size: int, downsample: int) -> int:
    return image_size // downsample


def conv_sides(side: int, num_layers: int, stride2_layers: int) -> list[int]:
    """Map sides after each 3x3 valid conv (stride 2 for the first ``stride2_layers``)."""
    out = []
    for i in range(num_layers):
        side = (side - 3) // (2 if i < stride2_layers else 1) + 1
        out.append(side)
    return out


class PooledConvEncoder(nn.Module):
    """uint8 (B, K, H, W) depth -> average-pooled by ``downsample`` -> 3x3 convs -> flat features.

    ``forward`` takes already pooled float pixels (0..255); :meth:`pool` does the pooling, so an
    update can shift the pooled images before the convs."""

    def __init__(self, in_channels: int, image_size: int, downsample: int, num_layers: int,
                 num_filters: int, stride2_layers: int, act: str):
        super().__init__()
        self.downsample = int(downsample)
        self.convs = nn.ModuleList()
        for i in range(num_layers):
            self.convs.append(nn.Conv2d(in_channels if i == 0 else num_filters, num_filters, 3,
                                        stride=2 if i < stride2_layers else 1))
        self.act = activation(act)
        side = conv_sides(pooled_side(image_size, downsample), num_layers, stride2_layers)[-1]
        self.out_dim = num_filters * side * side
        self.channels_last = False

    def use_channels_last(self) -> PooledConvEncoder:
        """Run the convs in channels-last memory layout: the same math in oneDNN's faster kernels
        for these few-channel convs. Weights and inputs change layout only."""
        self.channels_last = True
        return self.to(memory_format=torch.channels_last)

    def pool(self, depth_u8: torch.Tensor) -> torch.Tensor:
        """Env-size uint8 frames -> pooled float pixels, rounded exactly as :func:`pool_depth`
        rounds the frames the replay stores (so acting and updates see the same values)."""
        x = depth_u8.float()
        f = self.downsample
        if f == 1:
            return x
        sums = F.avg_pool2d(x, f, divisor_override=1)
        return torch.floor((sums + (f * f) // 2) / (f * f))

    def forward(self, pooled: torch.Tensor) -> torch.Tensor:
        h = pooled / 255.0 - 0.5
        if self.channels_last:
            h = h.contiguous(memory_format=torch.channels_last)
        for conv in self.convs:
            h = self.act(conv(h))
        return h.flatten(1)


def pool_depth(depth: np.ndarray, factor: int) -> np.ndarray:
    """uint8 frames (..., H, W) -> (..., H / factor, W / factor): block means rounded half up.
    The replay stores pooled frames (4x less memory and copying at factor 2)."""
    if factor == 1:
        return depth
    *lead, h, w = depth.shape
    blocks = depth.reshape(*lead, h // factor, factor, w // factor, factor).astype(np.uint16)
    sums = blocks.sum(axis=(-3, -1))
    return ((sums + (factor * factor) // 2) // (factor * factor)).astype(np.uint8)


def random_shift(x: torch.Tensor, pad: int) -> torch.Tensor:
    """DrQ-v2's augmentation: replicate-pad by ``pad`` and crop back at a random offset per sample
    (integer shifts; DrQ-v2 samples a bilinear grid, the same up to sub-pixel offsets)."""
    if pad <= 0:
        return x
    b, _, h, _ = x.shape
    padded = F.pad(x, (pad, pad, pad, pad), mode="replicate")
    oy = torch.randint(0, 2 * pad + 1, (b,), device=x.device)
    ox = torch.randint(0, 2 * pad + 1, (b,), device=x.device)
    return crop_at(padded, oy, ox, h)


class DrqCritic(nn.Module):
    """Projection of the conv features and twin Q-heads (the part that has a Polyak target)."""

    def __init__(self, conv_dim: int, cfg: LearnerConfig, extra_dim: int, action_dim: int):
        """``extra_dim``: the mask and proprio values, plus the privileged state's when the
        critic reads it (the caller concatenates them)."""
        super().__init__()
        self.proj = Projection(conv_dim, cfg.encoder_latent_dim, cfg.encoder_tanh)
        in_dim = cfg.encoder_latent_dim + extra_dim + action_dim
        self.q1 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)
        self.q2 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)

    def forward(self, h: torch.Tensor, extra: torch.Tensor, action: torch.Tensor):
        x = torch.cat([self.proj(h), extra, action], dim=-1)
        return self.q1(x), self.q2(x)


class FrameDecoder(nn.Module):
    """SAC-AE's auxiliary (``encoder_aux_loss: reconstruction``): conv features -> the newest pooled
    depth frame, in the encoder's input scale [-0.5, 0.5]. Fully connected, because the pooled
    frames are small (25 x 25 at the cpu profile)."""

    def __init__(self, conv_dim: int, hidden_dim: int, side: int):
        super().__init__()
        self.side = int(side)
        self.net = nn.Sequential(nn.Linear(conv_dim, hidden_dim), nn.ReLU(), nn.Linear(hidden_dim, side * side))

    def forward(self, h: torch.Tensor) -> torch.Tensor:
        return self.net(h).view(-1, self.side, self.side)


_ARCH_FIELDS = ("frame_history", "image_size", "obs_downsample", "encoder_num_layers", "encoder_num_filters",
                "encoder_stride2_layers", "encoder_latent_dim", "encoder_activation", "encoder_tanh",
                "actor_hidden_dim", "actor_num_layers", "actor_activation", "actor_log_std_min",
                "actor_log_std_max", "critic_hidden_dim", "critic_num_layers", "critic_activation")


def drq_arch(cfg: LearnerConfig, action_dim: int, mask_dim: int, proprio_dim: int, state_dim: int,
             fields: tuple[str, ...] = _ARCH_FIELDS) -> dict[str, Any]:
    """The arch dict of an agent with SAC-DrQ's actor: what its actor file records, and what a
    resumed agent state must match."""
    arch = {name: getattr(cfg, name) for name in fields}
    arch.update(action_dim=action_dim, mask_dim=mask_dim, proprio_dim=proprio_dim,
                extra_dim=mask_dim + proprio_dim, crop_size=cfg.image_size)
    if state_dim:  # only then: actor files of critics without it keep their arch
        arch["critic_state_dim"] = state_dim
    return arch


def act_with(encoder: PooledConvEncoder, actor: ActorHead, obs: dict, device: torch.device, image_size: int,
             deterministic: bool) -> np.ndarray:
    """Actions (B, A) in [-1, 1] of SAC-DrQ's actor for a stacked batch (one forward pass); acting sees
    the whole, unshifted image."""
    with torch.inference_mode():
        depth, extra = obs_to_tensors(obs, device, image_size)
        mu, log_std = actor(encoder(encoder.pool(depth)), extra)
        a = torch.tanh(mu) if deterministic else squashed_sample(mu, log_std, torch.randn_like(mu))[0]
    return a.float().cpu().numpy()


def _encoder(arch: dict[str, Any]) -> PooledConvEncoder:
    return PooledConvEncoder(arch["frame_history"], arch["image_size"], arch["obs_downsample"],
                             arch["encoder_num_layers"], arch["encoder_num_filters"],
                             arch["encoder_stride2_layers"], arch["encoder_activation"])


class DrqActorNet(nn.Module):
    """What acting needs: encoder + actor head; takes the env's uint8 depth (B, K, H, W)."""

    def __init__(self, arch: dict[str, Any]):
        super().__init__()
        self.arch = dict(arch)
        self.encoder = _encoder(arch)
        self.head = actor_head(self.encoder.out_dim, arch)

    def forward(self, depth: torch.Tensor, extra: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.encoder(self.encoder.pool(depth)), extra)


class PooledReplay:
    """What the trainer asks of a learner whose replay holds depth pooled by ``obs_downsample``:
    the stored frames' side and the observation as stored. Shared by SAC-DrQ, its recurrent form
    and PPO."""

    cfg: LearnerConfig

    @property
    def replay_image_size(self) -> int:
        return pooled_side(self.cfg.image_size, self.cfg.obs_downsample)

    def replay_obs(self, obs: dict) -> dict:
        return {**obs, "depth": pool_depth(np.asarray(obs["depth"]), self.cfg.obs_downsample)}


class SacDrqAgent(PooledReplay):
    """SAC with the DrQ-v2-style update (module docstring). ``update`` takes a batch with an
    optional ``discount`` (B, 1) column (gamma^n of n-step returns; default gamma)."""

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30, proprio_dim: int = 4,
                 device: str | torch.device | None = None, state_dim: int = 0):
        self.cfg = cfg.validate()
        self.device = resolve_device(cfg.device) if device is None else torch.device(device)
        self.action_dim, self.mask_dim, self.proprio_dim = int(action_dim), int(mask_dim), int(proprio_dim)
        if cfg.critic_privileged_state and state_dim < 1:
            raise ValueError("critic_privileged_state needs the env's privileged state (state_dim >= 1)")
        self.state_dim = int(state_dim) if cfg.critic_privileged_state else 0
        arch = self.arch()
        self.encoder = _encoder(arch)
        self.critic = DrqCritic(self.encoder.out_dim, cfg, arch["extra_dim"] + self.state_dim, self.action_dim)
        self.actor: ActorHead = actor_head(self.encoder.out_dim, arch)
        for net in (self.encoder, self.critic, self.actor):
            net.apply(weight_init)
            net.to(self.device)
        if cfg.channels_last:
            self.encoder.use_channels_last()
        self.critic_target = copy.deepcopy(self.critic)
        for p in self.critic_target.parameters():
            p.requires_grad_(False)
        self.log_alpha = torch.tensor(math.log(cfg.init_temperature), device=self.device, requires_grad=True)
        self.target_entropy = -float(self.action_dim)
        self.num_updates = 0
        self.critic_opt = adam([{"params": self.critic.parameters(), "lr": cfg.critic_lr},
                                      {"params": self.encoder.parameters(), "lr": cfg.encoder_lr}],
                                     cfg.critic_lr, (cfg.critic_beta1, cfg.critic_beta2))
        self.actor_opt = adam(self.actor.parameters(), cfg.actor_lr, (cfg.actor_beta1, cfg.actor_beta2))
        self.alpha_opt = adam([self.log_alpha], cfg.alpha_lr, (cfg.alpha_beta1, cfg.alpha_beta2))
        self.optimisers = {"critic": self.critic_opt, "actor": self.actor_opt, "alpha": self.alpha_opt}
        self.decoder: FrameDecoder | None = None
        if cfg.encoder_aux_loss == "reconstruction":
            self.decoder = FrameDecoder(self.encoder.out_dim, cfg.encoder_latent_dim, self.replay_image_size)
            self.decoder.apply(weight_init)
            self.decoder.to(self.device)
            # its own optimiser, so that agent states without a decoder keep their format
            self.optimisers["decoder"] = adam(self.decoder.parameters(), cfg.critic_lr,
                                              (cfg.critic_beta1, cfg.critic_beta2))

    @property
    def alpha(self) -> float:
        return float(self.log_alpha.detach().exp())

    # ---- acting --------------------------------------------------------------------------
    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """Actions (B, A) in [-1, 1] for a stacked batch of observations (one forward pass)."""
        return act_with(self.encoder, self.actor, obs, self.device, self.cfg.image_size, deterministic)

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        return self.act_batch(obs, deterministic)[0]

    # ---- updating ------------------------------------------------------------------------
    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        cfg = self.cfg
        self.num_updates += 1
        extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1)
        next_extra = torch.cat([batch["next_mask"], batch["next_proprio"]], dim=-1)
        # what the critic reads besides the conv features: the actor's inputs, plus the state
        critic_extra, next_critic_extra = extra, next_extra
        if self.state_dim:
            critic_extra = torch.cat([extra, batch["state"]], dim=-1)
            next_critic_extra = torch.cat([next_extra, batch["next_state"]], dim=-1)
        discount = batch.get("discount")
        if discount is None:
            discount = torch.full_like(batch["reward"], cfg.gamma)
        # the replay holds pooled frames (see ``replay_obs``)
        obs = random_shift(batch["obs_depth"].float(), cfg.aug_pad)
        nxt = random_shift(batch["next_obs_depth"].float(), cfg.aug_pad)
        alpha = self.log_alpha.detach().exp()
        out: dict[str, torch.Tensor] = {}

        with torch.no_grad():
            h_next = self.encoder(nxt)
            mu, log_std = self.actor(h_next, next_extra)
            next_pi, next_log_pi = squashed_sample(mu, log_std, torch.randn_like(mu))
            tq1, tq2 = self.critic_target(h_next, next_critic_extra, next_pi)
            target_q = batch["reward"] + batch["not_done"] * discount * (torch.min(tq1, tq2) - alpha * next_log_pi)

        h = self.encoder(obs)
        q1, q2 = self.critic(h, critic_extra, batch["action"])
        critic_loss = F.mse_loss(q1, target_q) + F.mse_loss(q2, target_q)
        loss = critic_loss
        if self.decoder is not None:
            # the newest frame as the encoder saw it (pooled, shifted), in its input scale
            aux_loss = F.mse_loss(self.decoder(h), obs[:, -1] / 255.0 - 0.5)
            loss = critic_loss + cfg.encoder_aux_weight * aux_loss
            self.optimisers["decoder"].zero_grad(set_to_none=True)
            out["aux_loss"] = aux_loss
        self.critic_opt.zero_grad(set_to_none=True)
        loss.backward()
        self.critic_opt.step()
        if self.decoder is not None:
            self.optimisers["decoder"].step()
        out["critic_loss"], out["q_mean"] = critic_loss, q1.mean()

        if self.num_updates % cfg.actor_update_freq == 0:
            h_actor = h.detach()
            mu, log_std = self.actor(h_actor, extra)
            pi, log_pi = squashed_sample(mu, log_std, torch.randn_like(mu))
            aq1, aq2 = self.critic(h_actor, critic_extra, pi)
            actor_loss = (alpha * log_pi - torch.min(aq1, aq2)).mean()
            self.actor_opt.zero_grad(set_to_none=True)
            actor_params = list(self.actor.parameters())
            for p, g in zip(actor_params, torch.autograd.grad(actor_loss, actor_params)):
                p.grad = g
            self.actor_opt.step()
            alpha_loss = (self.log_alpha.exp() * (-log_pi - self.target_entropy).detach()).mean()
            self.log_alpha.grad = torch.autograd.grad(alpha_loss, [self.log_alpha])[0]
            self.alpha_opt.step()
            out["actor_loss"], out["alpha_loss"] = actor_loss, alpha_loss
            out["entropy"] = gaussian_entropy(log_std)

        if self.num_updates % cfg.critic_target_update_freq == 0:
            with torch.no_grad():
                torch._foreach_lerp_(list(self.critic_target.parameters()), list(self.critic.parameters()),
                                     cfg.critic_tau)
        out["alpha"] = self.log_alpha.detach().exp()
        return metric_values(out, self.device)

    # ---- persistence -----------------------------------------------------------------------
    def arch(self) -> dict[str, Any]:
        return drq_arch(self.cfg, self.action_dim, self.mask_dim, self.proprio_dim, self.state_dim)

    def state_dict(self) -> dict[str, Any]:
        return {"format": AGENT_FORMAT, "arch": self.arch(), "encoder": self.encoder.state_dict(),
                "critic": self.critic.state_dict(), "critic_target": self.critic_target.state_dict(),
                "actor": self.actor.state_dict(), "log_alpha": self.log_alpha.detach().clone(),
                "optimisers": {k: opt.state_dict() for k, opt in self.optimisers.items()},
                "num_updates": self.num_updates,
                **({"decoder": self.decoder.state_dict()} if self.decoder is not None else {})}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        check_agent_state(state, AGENT_FORMAT, "SAC-DrQ", self.arch())
        if (self.decoder is None) != ("decoder" not in state):
            raise AgentStateError("agent state has a different encoder_aux_loss (a decoder in one of them only)")
        parts = ("encoder", "critic", "critic_target", "actor") + (("decoder",) if self.decoder is not None else ())
        for name in parts:
            getattr(self, name).load_state_dict(state[name])
        with torch.no_grad():
            self.log_alpha.copy_(state["log_alpha"])
        for k, opt in self.optimisers.items():
            opt.load_state_dict(state["optimisers"][k])
        self.num_updates = int(state["num_updates"])

    def actor_state(self, metadata: dict[str, Any] | None = None,
                    storage_dtype: torch.dtype = torch.float16) -> dict[str, Any]:
        """Actor-only weights (encoder + actor head), float16 like SAC+CURL's actor files."""
        weights = actor_weights({"encoder": self.encoder, "head": self.actor}, storage_dtype)
        return {"format": ACTOR_FORMAT, "arch": self.arch(), "state_dict": weights, "metadata": dict(metadata or {})}


def load_drq_actor_net(state: dict[str, Any], device: str | torch.device = "cpu") -> DrqActorNet:
    return load_actor_weights(DrqActorNet(state["arch"]), state, device)
