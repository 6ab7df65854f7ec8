"""What the pooled-depth learners build from: SAC-DrQ (:mod:`egosearch.rl.sac_drq`), its recurrent form
(:mod:`egosearch.rl.sac_drq_recurrent`) and PPO (:mod:`egosearch.rl.ppo`).

- the pooled depth: :func:`pool_depth` (the replay's frames), :class:`PooledConvEncoder` and
  :func:`pooled_encoder` (the conv encoder an arch dict describes), :func:`conv_sides`;
- SAC-DrQ's actor: :data:`DRQ_ARCH_FIELDS` and :func:`drq_arch` (its arch dict), :func:`act_with`
  (acting), :class:`DrqActorNet`, :data:`DRQ_ACTOR_FORMAT` and :func:`load_drq_actor_net` (its
  actor file, which SAC-DrQ and PPO both write);
- :class:`PooledAgent`: an :class:`egosearch.rl.learner.AgentBase` whose replay holds pooled depth and
  whose actor is SAC-DrQ's (input sizes, acting, arch, agent state and actor file);
- :class:`SacMixin`: SAC's temperature and its actor + temperature step (SAC + CURL uses it too).

SAC-DrQ's own set-up and Polyak step (:class:`egosearch.rl.sac_drq.SacDrqBase`) are in its module.

Lower-level pieces (layers, crops, the actor head, metrics, actor weights) are in
:mod:`egosearch.rl.common`. The module and attribute names here are part of the agent states'
and actor files' keys (``encoder.convs.0.weight``, ``head.trunk.0.bias``...): renaming one breaks
stored runs.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from egosearch.rl.common import (
    ActorHead,
    activation,
    actor_head,
    actor_weights,
    load_actor_weights,
    obs_to_tensors,
    resolve_device,
    squashed_sample,
)
from egosearch.rl.config import LearnerConfig
from egosearch.rl.learner import AgentBase
from egosearch.rl.training_aids import critic_reads_state

DRQ_ACTOR_FORMAT = "egosearch-sac-drq-actor-v1"
"""The actor file of SAC-DrQ's actor (pooled conv encoder + :class:`ActorHead`): SAC-DrQ's and PPO's."""
DRQ_ARCH_FIELDS = ("frame_history", "image_size", "obs_downsample", "encoder_num_layers", "encoder_num_filters",
                   "encoder_stride2_layers", "encoder_latent_dim", "encoder_activation", "encoder_tanh",
                   "actor_hidden_dim", "actor_num_layers", "actor_activation", "actor_log_std_min",
                   "actor_log_std_max", "critic_hidden_dim", "critic_num_layers", "critic_activation")
"""The config fields in SAC-DrQ's arch dict (:func:`drq_arch`)."""


# ---- the pooled depth ---------------------------------------------------------------------

def pooled_side(image_size: int, downsample: int) -> int:
    return image_size // downsample


def conv_sides(side: int, num_layers: int, stride2_layers: int) -> list[int]:
    """Map sides after each 3x3 valid conv (stride 2 for the first ``stride2_layers``)."""
    out = []
    for i in range(num_layers):
        side = (side - 3) // (2 if i < stride2_layers else 1) + 1
        out.append(side)
    return out


def pool_depth(depth: np.ndarray, factor: int) -> np.ndarray:
    """uint8 frames (..., H, W) -> (..., H / factor, W / factor): block means rounded half up.
    The replay stores pooled frames (4x less memory and copying at factor 2)."""
    if factor == 1:
        return depth
    *lead, h, w = depth.shape
    blocks = depth.reshape(*lead, h // factor, factor, w // factor, factor).astype(np.uint16)
    sums = blocks.sum(axis=(-3, -1))
    return ((sums + (factor * factor) // 2) // (factor * factor)).astype(np.uint8)


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


def pooled_encoder(arch: dict[str, Any]) -> PooledConvEncoder:
    """The :class:`PooledConvEncoder` an arch dict (:func:`drq_arch`) describes."""
    return PooledConvEncoder(arch["frame_history"], arch["image_size"], arch["obs_downsample"],
                             arch["encoder_num_layers"], arch["encoder_num_filters"],
                             arch["encoder_stride2_layers"], arch["encoder_activation"])


# ---- SAC-DrQ's actor ------------------------------------------------------------------------

def drq_arch(cfg: LearnerConfig, action_dim: int, mask_dim: int, proprio_dim: int, state_dim: int,
             fields: tuple[str, ...] = DRQ_ARCH_FIELDS) -> dict[str, Any]:
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


class DrqActorNet(nn.Module):
    """What acting needs: encoder + actor head; takes the env's uint8 depth (B, K, H, W)."""

    def __init__(self, arch: dict[str, Any]):
        super().__init__()
        self.arch = dict(arch)
        self.encoder = pooled_encoder(arch)
        self.head = actor_head(self.encoder.out_dim, arch)

    def forward(self, depth: torch.Tensor, extra: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.encoder(self.encoder.pool(depth)), extra)


def load_drq_actor_net(state: dict[str, Any], device: str | torch.device = "cpu") -> DrqActorNet:
    """The network of a :data:`DRQ_ACTOR_FORMAT` actor file."""
    return load_actor_weights(DrqActorNet(state["arch"]), state, device)


# ---- the agents -----------------------------------------------------------------------------

class PooledAgent(AgentBase):
    """A learner whose replay holds depth pooled by ``obs_downsample`` and whose actor is SAC-DrQ's
    (``encoder`` + ``actor``): SAC-DrQ, its recurrent form (which acts with its own) and PPO.

    A subclass sets ``cfg`` (validated), calls :meth:`set_inputs`, builds its networks and
    optimisers (``optimisers``) and names its formats (``agent_format``, ``actor_format``)."""

    agent_format: ClassVar[str]
    actor_format: ClassVar[str] = DRQ_ACTOR_FORMAT
    arch_fields: ClassVar[tuple[str, ...]] = DRQ_ARCH_FIELDS
    cfg: LearnerConfig
    device: torch.device
    action_dim: int
    mask_dim: int
    proprio_dim: int
    state_dim: int
    encoder: PooledConvEncoder
    actor: nn.Module
    optimisers: dict[str, torch.optim.Optimizer]

    def set_inputs(self, device: str | torch.device | None, action_dim: int, mask_dim: int, proprio_dim: int,
                   state_dim: int) -> None:
        """The device and the sizes of the action, the mask, the proprioception and (for a privileged
        critic, ``critic_privileged_state``) the env's privileged state; 0 without."""
        cfg = self.cfg
        self.device = resolve_device(cfg.device) if device is None else torch.device(device)
        self.action_dim, self.mask_dim, self.proprio_dim = int(action_dim), int(mask_dim), int(proprio_dim)
        if critic_reads_state(cfg) and state_dim < 1:
            raise ValueError("critic_privileged_state needs the env's privileged state (state_dim >= 1)")
        self.state_dim = int(state_dim) if critic_reads_state(cfg) else 0

    # ---- replay --------------------------------------------------------------------------
    @property
    def replay_image_size(self) -> int:
        return pooled_side(self.cfg.image_size, self.cfg.obs_downsample)

    def replay_obs(self, obs: dict) -> dict:
        return {**obs, "depth": pool_depth(np.asarray(obs["depth"]), self.cfg.obs_downsample)}

    # ---- acting --------------------------------------------------------------------------
    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """Actions (B, A) in [-1, 1] for a stacked batch of observations (one forward pass)."""
        return act_with(self.encoder, self.actor, obs, self.device, self.cfg.image_size, deterministic)

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        return self.act_batch(obs, deterministic)[0]

    # ---- persistence -----------------------------------------------------------------------
    def arch(self) -> dict[str, Any]:
        return drq_arch(self.cfg, self.action_dim, self.mask_dim, self.proprio_dim, self.state_dim, self.arch_fields)

    def agent_state(self, modules: tuple[str, ...], tensors: tuple[str, ...] = ()) -> dict[str, Any]:
        """The agent state: format, arch, the ``modules``' state dicts and copies of the ``tensors``
        (attribute names), the optimisers and the update counter."""
        return {"format": self.agent_format, "arch": self.arch(),
                **{name: getattr(self, name).state_dict() for name in modules},
                **{name: getattr(self, name).detach().clone() for name in tensors},
                "optimisers": {k: opt.state_dict() for k, opt in self.optimisers.items()},
                "num_updates": self.num_updates}

    def restore(self, state: dict[str, Any], modules: tuple[str, ...], tensors: tuple[str, ...] = ()) -> None:
        """Load what :meth:`agent_state` saved (the caller has checked its format and arch)."""
        for name in modules:
            getattr(self, name).load_state_dict(state[name])
        with torch.no_grad():
            for name in tensors:
                getattr(self, name).copy_(state[name])
        for k, opt in self.optimisers.items():
            opt.load_state_dict(state["optimisers"][k])
        self.num_updates = int(state["num_updates"])

    def actor_state(self, metadata: dict[str, Any] | None = None,
                    storage_dtype: torch.dtype = torch.float16) -> dict[str, Any]:
        """Actor-only weights (encoder + actor head), float16 like SAC+CURL's actor files."""
        weights = actor_weights({"encoder": self.encoder, "head": self.actor}, storage_dtype)
        return {"format": self.actor_format, "arch": self.arch(), "state_dict": weights,
                "metadata": dict(metadata or {})}


class SacMixin:
    """SAC's temperature and actor step, shared by SAC + CURL and the SAC-DrQ learners: for an agent
    with an ``actor`` and its ``actor_opt``, the temperature ``log_alpha`` and its ``alpha_opt``, and
    ``target_entropy``."""

    actor: nn.Module
    actor_opt: torch.optim.Optimizer
    log_alpha: torch.Tensor
    alpha_opt: torch.optim.Optimizer
    target_entropy: float

    @property
    def alpha(self) -> float:
        return float(self.log_alpha.detach().exp())

    def actor_and_alpha_step(self, alpha: torch.Tensor, log_pi: torch.Tensor, aq1: torch.Tensor,
                             aq2: torch.Tensor, out: dict[str, torch.Tensor],
                             penalty: torch.Tensor | None = None) -> None:
        """SAC's actor step (gradients to the actor's parameters only) on log pi and the critic's Q of
        the sampled actions, plus ``penalty`` when given (a behaviour-cloning term), then the
        temperature's step; the losses go into ``out`` (``actor_loss`` is SAC's alone)."""
        actor_loss = (alpha * log_pi - torch.min(aq1, aq2)).mean()
        total = actor_loss if penalty is None else actor_loss + penalty
        self.actor_and_alpha_steps_on(total, log_pi, out)
        out["actor_loss"] = actor_loss

    def actor_and_alpha_steps_on(self, total: torch.Tensor, log_pi: torch.Tensor,
                                 out: dict[str, torch.Tensor]) -> None:
        """SAC's actor step on the loss ``total`` already computed (gradients to the actor's parameters
        only), then the temperature's step on ``log_pi``; ``alpha_loss`` goes into ``out``."""
        self.actor_opt.zero_grad(set_to_none=True)
        actor_params = [p for g in self.actor_opt.param_groups for p in g["params"]]
        for p, g in zip(actor_params, torch.autograd.grad(total, actor_params)):
            p.grad = g
        self.actor_opt.step()
        alpha_loss = (self.log_alpha.exp() * (-log_pi - self.target_entropy).detach()).mean()
        self.log_alpha.grad = torch.autograd.grad(alpha_loss, [self.log_alpha])[0]
        self.alpha_opt.step()
        out["alpha_loss"] = alpha_loss
