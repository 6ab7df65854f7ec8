"""SAC with a DrQ-v2-style update: the cpu preset's cheaper learner (not the paper's CURL).

What it keeps from SAC + CURL (:mod:`egosearch.rl.sac_curl`): the soft actor-critic losses,
twin critics with Polyak targets, the tanh-Gaussian actor, the automatic temperature, the inputs
(K depth frames + mask feature + proprioception) and every learning rate and beta. The pooled
encoder and the actor and its file, which the recurrent form and PPO share, live in :mod:`egosearch.rl.pooled`;
layers, crops and the actor head in :mod:`egosearch.rl.common`. SAC's set-up around them and the Polyak step
(:class:`SacDrqBase`, here) are SAC-DrQ's own, which its recurrent form builds on.

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
- learning from demonstrations (off unless a config sets it; the training loop holds them):
  :meth:`SacDrqAgent.clone_update` is a behaviour-cloning step of the encoder and actor (PIRLNav's
  first phase); the first ``critic_warmup_updates`` updates train only the critic's head (PIRLNav);
  a batch's ``demo`` rows (RLPD's half batches) add ``bc_weight_now`` x a behaviour-cloning term to
  the actor's loss (TD3+BC's form), the training loop decaying ``bc_weight_now``.

It is an :class:`egosearch.rl.learner.Agent`, so :mod:`egosearch.rl.train` drives it as any other
learner (registered as "sac_drq" in :mod:`egosearch.rl.learner_registry`).
"""

from __future__ import annotations

import copy
import math
from abc import abstractmethod
from typing import Any, ClassVar

import torch
import torch.nn.functional as F
from torch import nn

from egosearch.rl.common import (
    AgentStateError,
    MapReader,
    ModuleNets,
    Projection,
    actor_head,
    adam,
    check_agent_state,
    crop_at,
    gaussian_entropy,
    map_reader,
    metric_values,
    mlp,
    squashed_sample,
    weight_init,
)
from egosearch.rl.config import LearnerConfig
from egosearch.rl.pooled import DRQ_ACTOR_FORMAT, PooledAgent, SacMixin, pooled_encoder
from egosearch.sim.observation_options import extra_dims, mask_images


def map_arch(cfg: LearnerConfig, mask_dim: int) -> dict[str, Any]:
    """``{"map_image": shape, "map_offset": where its values start}`` when an image option is on (SAC-DrQ reads it
    with a :class:`MapReader` in its actor and its critic), else ``{}`` (the arch of every run before it)."""
    on = {name: True for name, value in cfg.to_dict().items() if value is True}
    images = mask_images(on)
    if not images:
        return {}
    if len(images) > 1:
        raise ValueError("SAC-DrQ reads one image inside mask; more than one image option is on")
    before, shape = images[0]
    options_start = mask_dim - extra_dims(on).get("mask", 0)
    return {"map_image": list(shape), "map_offset": options_start + before}

AGENT_FORMAT = "egosearch-sac-drq-agent-v1"
ACTOR_FORMAT = DRQ_ACTOR_FORMAT


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


# ---- the update's arithmetic, written once ----------------------------------------------------
# One learner's losses from ``nets`` (a callable ``nets("critic", *inputs)``): SacDrqAgent.update passes its
# own modules (egosearch.rl.common.ModuleNets), the stacked update (egosearch.rl.stacked) each seed's slice of
# the stacked parameters under vmap. The random numbers come in as arguments, drawn by the caller in one order.

def drq_inputs(batch: dict[str, torch.Tensor], state_dim: int, gamma: float):
    """(extra, next_extra, critic_extra, next_critic_extra, discount) of a (plain or stacked) batch: the
    actor's inputs besides the frames (mask, proprio), the critic's (the same plus the privileged ``state``
    when it reads one) and the n-step discount column (gamma when the batch has none)."""
    extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1)
    next_extra = torch.cat([batch["next_mask"], batch["next_proprio"]], dim=-1)
    critic_extra, next_critic_extra = extra, next_extra
    if state_dim:
        critic_extra = torch.cat([extra, batch["state"]], dim=-1)
        next_critic_extra = torch.cat([next_extra, batch["next_state"]], dim=-1)
    discount = batch.get("discount")
    if discount is None:
        discount = torch.full_like(batch["reward"], gamma)
    return extra, next_extra, critic_extra, next_critic_extra, discount


def drq_target(nets, nxt, next_extra, next_critic_extra, reward, not_done, discount, noise, alpha) -> torch.Tensor:
    """The critic's target: the online encoder on next_obs (DrQ-v2), the actor's sample there (``noise``),
    the target critic's smaller Q less the entropy term. The caller runs it without autograd."""
    h_next = nets("encoder", nxt)
    mu, log_std = nets("actor", h_next, next_extra)
    next_pi, next_log_pi = squashed_sample(mu, log_std, noise)
    tq1, tq2 = nets("critic_target", h_next, next_critic_extra, next_pi)
    return reward + not_done * discount * (torch.min(tq1, tq2) - alpha * next_log_pi)


def drq_critic_loss(nets, obs, critic_extra, action, target_q, *, warming_up: bool):
    """(critic loss, mean Q1, the conv features of ``obs``). During the critic warm-up the encoder gets no
    gradient (PIRLNav: the cloned encoder stays as it is)."""
    with torch.set_grad_enabled(not warming_up and torch.is_grad_enabled()):
        h = nets("encoder", obs)
    q1, q2 = nets("critic", h, critic_extra, action)
    return F.mse_loss(q1, target_q) + F.mse_loss(q2, target_q), q1.mean(), h


def drq_actor_loss(nets, h, extra, critic_extra, action, demo, noise, alpha, *, bc_weight: float):
    """(the actor's whole loss, SAC's part of it, log pi, the entropy, the cloning loss) on the detached
    features ``h``. With ``bc_weight`` > 0, TD3+BC's term on the ``demo`` rows (a (B, 1) 0/1 column): the
    squared error to the batch's action, scaled by the critic's magnitude; the cloning loss is 0 without."""
    h_actor = h.detach()
    mu, log_std = nets("actor", h_actor, extra)
    pi, log_pi = squashed_sample(mu, log_std, noise)
    aq1, aq2 = nets("critic", h_actor, critic_extra, pi)
    actor_loss = (alpha * log_pi - torch.min(aq1, aq2)).mean()
    total, bc_loss = actor_loss, torch.zeros_like(actor_loss)
    if bc_weight > 0:
        error = ((torch.tanh(mu) - action).pow(2).sum(-1, keepdim=True) * demo).sum()
        bc_loss = error / demo.sum().clamp(min=1.0)
        total = actor_loss + bc_weight * torch.min(aq1, aq2).abs().mean().detach() * bc_loss
    return total, actor_loss, log_pi, gaussian_entropy(log_std), bc_loss


class DrqCritic(nn.Module):
    """Projection of the conv features and twin Q-heads (the part that has a Polyak target)."""

    def __init__(self, conv_dim: int, cfg: LearnerConfig, extra_dim: int, action_dim: int,
                 map_reader: MapReader | None = None):
        """``extra_dim``: the mask and proprio values, plus the privileged state's when the
        critic reads it (the caller concatenates them); ``map_reader``: the critic's own reader of an image
        inside mask (``map_image``)."""
        super().__init__()
        self.proj = Projection(conv_dim, cfg.encoder_latent_dim, cfg.encoder_tanh)
        if map_reader is not None:  # a submodule only then: states without a map keep their keys
            self.map_reader = map_reader
            extra_dim = map_reader.extra_dim(extra_dim)
        in_dim = cfg.encoder_latent_dim + extra_dim + action_dim
        self.q1 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation,
                      cfg.critic_layer_norm)
        self.q2 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation,
                      cfg.critic_layer_norm)

    def forward(self, h: torch.Tensor, extra: torch.Tensor, action: torch.Tensor):
        if hasattr(self, "map_reader"):
            extra = self.map_reader(extra)
        x = torch.cat([self.proj(h), extra, action], dim=-1)
        return self.q1(x), self.q2(x)


class FrameDecoder(nn.Module):
    """SAC-AE's auxiliary (``encoder_aux_loss: reconstruction``): conv features -> the newest pooled
    depth frame, in the encoder's input scale [-0.5, 0.5]. Fully connected, because the pooled
    frames are small (25 x 25 at the cpu preset)."""

    def __init__(self, conv_dim: int, hidden_dim: int, side: int):
        super().__init__()
        self.side = int(side)
        self.net = nn.Sequential(nn.Linear(conv_dim, hidden_dim), nn.ReLU(), nn.Linear(hidden_dim, side * side))

    def forward(self, h: torch.Tensor) -> torch.Tensor:
        return self.net(h).view(-1, self.side, self.side)


class SacDrqBase(SacMixin, PooledAgent):
    """The SAC-DrQ learners' common part: one conv ``encoder`` trained by the critic, a ``critic``
    with a Polyak copy ``critic_target``, an ``actor``, the temperature ``log_alpha`` with target
    entropy -|A|, and the optimisers ``critic`` (critic + encoder), ``actor`` and ``alpha``. A
    subclass builds its critic and actor (:meth:`make_critic`, :meth:`make_actor`)."""

    SAC_MODULES: ClassVar[tuple[str, ...]] = ("encoder", "critic", "critic_target", "actor")
    """The networks in the agent state, in its order (``log_alpha`` follows them)."""
    critic: nn.Module
    critic_target: nn.Module
    critic_opt: torch.optim.Adam

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30, proprio_dim: int = 4,
                 device: str | torch.device | None = None, state_dim: int = 0):
        self.cfg = cfg.validate()
        self.set_inputs(device, action_dim, mask_dim, proprio_dim, state_dim)
        arch = self.arch()
        self.encoder = pooled_encoder(arch)
        self.critic = self.make_critic(arch)
        self.actor = self.make_actor(arch)
        self.build_sac()

    @abstractmethod
    def make_critic(self, arch: dict[str, Any]) -> nn.Module:
        """The critic, on the features of ``encoder`` (built just before)."""

    @abstractmethod
    def make_actor(self, arch: dict[str, Any]) -> nn.Module:
        """The actor head, on the features of ``encoder`` (built after the critic)."""

    def build_sac(self) -> None:
        """SAC's set-up around the ``encoder``, ``critic`` and ``actor`` just built: CURL's init, the
        device, the target critic, the temperature, the optimisers."""
        cfg = self.cfg
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

    # ---- updating ------------------------------------------------------------------------
    def finish_update(self, out: dict[str, torch.Tensor]) -> dict[str, float]:
        """The Polyak step when due (every ``critic_target_update_freq`` updates), then the update's
        metrics."""
        cfg = self.cfg
        if self.num_updates % cfg.critic_target_update_freq == 0:
            with torch.no_grad():
                torch._foreach_lerp_(list(self.critic_target.parameters()), list(self.critic.parameters()),
                                     cfg.critic_tau)
        out["alpha"] = self.log_alpha.detach().exp()
        return metric_values(out, self.device)

    # ---- persistence -----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        return self.agent_state(self.SAC_MODULES, ("log_alpha",))


class SacDrqAgent(SacDrqBase):
    """SAC with the DrQ-v2-style update (module docstring). ``update`` takes a batch with an
    optional ``discount`` (B, 1) column (gamma^n of n-step returns; default gamma)."""

    agent_format = AGENT_FORMAT
    bc_weight_now: float = 0.0
    """The behaviour-cloning term's weight at this update (``bc_weight``, decayed by the training loop)."""

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30, proprio_dim: int = 4,
                 device: str | torch.device | None = None, state_dim: int = 0):
        super().__init__(cfg, action_dim, mask_dim, proprio_dim, device, state_dim)
        self.decoder: FrameDecoder | None = None
        if cfg.encoder_aux_loss == "reconstruction":
            self.decoder = FrameDecoder(self.encoder.out_dim, cfg.encoder_latent_dim, self.replay_image_size)
            self.decoder.apply(weight_init)
            self.decoder.to(self.device)
            # its own optimiser, so that agent states without a decoder keep their format
            self.optimisers["decoder"] = adam(self.decoder.parameters(), cfg.critic_lr,
                                              (cfg.critic_beta1, cfg.critic_beta2))

    def arch(self) -> dict[str, Any]:
        arch = super().arch()
        if self.cfg.critic_layer_norm:  # recorded only when on, so that states and actors before it still match
            arch["critic_layer_norm"] = True
        arch.update(map_arch(self.cfg, self.mask_dim))
        return arch

    def make_critic(self, arch: dict[str, Any]) -> DrqCritic:
        return DrqCritic(self.encoder.out_dim, self.cfg, arch["extra_dim"] + self.state_dim, self.action_dim,
                         map_reader(arch))

    def make_actor(self, arch: dict[str, Any]) -> nn.Module:
        return actor_head(self.encoder.out_dim, arch)

    # ---- updating ------------------------------------------------------------------------
    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        cfg = self.cfg
        self.num_updates += 1
        nets = ModuleNets(self)
        extra, next_extra, critic_extra, next_critic_extra, discount = drq_inputs(batch, self.state_dim, cfg.gamma)
        # the replay holds pooled frames (see ``replay_obs``); the draws in the stacked update's order
        obs = random_shift(batch["obs_depth"].float(), cfg.aug_pad)
        nxt = random_shift(batch["next_obs_depth"].float(), cfg.aug_pad)
        noise_next = torch.randn((obs.shape[0], self.action_dim), device=self.device)
        alpha = self.log_alpha.detach().exp()
        out: dict[str, torch.Tensor] = {}
        # PIRLNav's critic warm-up: the cloned encoder and actor stay as they are
        warming_up = self.num_updates <= cfg.critic_warmup_updates

        with torch.no_grad():
            target_q = drq_target(nets, nxt, next_extra, next_critic_extra, batch["reward"], batch["not_done"],
                                  discount, noise_next, alpha)
        critic_loss, out["q_mean"], h = drq_critic_loss(nets, obs, critic_extra, batch["action"], target_q,
                                                        warming_up=warming_up)
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
        out["critic_loss"] = critic_loss

        if self.num_updates % cfg.actor_update_freq == 0 and not warming_up:
            noise_pi = torch.randn((obs.shape[0], self.action_dim), device=self.device)
            bc_weight = self.bc_weight_now if "demo" in batch else 0.0
            demo = batch["demo"] if bc_weight > 0 else torch.zeros_like(batch["reward"])
            total, out["actor_loss"], log_pi, out["entropy"], bc_loss = drq_actor_loss(
                nets, h, extra, critic_extra, batch["action"], demo, noise_pi, alpha, bc_weight=bc_weight)
            if bc_weight > 0:
                out["bc_loss"] = bc_loss
            self.actor_and_alpha_steps_on(total, log_pi, out)

        return self.finish_update(out)

    def clone_update(self, batch: dict[str, torch.Tensor], optimiser: torch.optim.Optimizer) -> dict[str, float]:
        """A behaviour-cloning step (PIRLNav's first phase) of the encoder and the actor, with ``optimiser``
        over their parameters: the squared error between the actor's mean action (after its tanh) and the
        batch's, summed over the action's values, on shifted frames as in :meth:`update`. Returns
        ``bc_loss``. (The log-likelihood of the teacher's actions, tried first, fitted the mean far
        worse: the teacher's actions sit at +-1 half of the time, where the tanh's inverse blows up.)"""
        extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1)
        h = self.encoder(random_shift(batch["obs_depth"].float(), self.cfg.aug_pad))
        mu, _ = self.actor(h, extra)
        loss = (torch.tanh(mu) - batch["action"]).pow(2).sum(-1).mean()
        optimiser.zero_grad(set_to_none=True)
        loss.backward()
        optimiser.step()
        return {"bc_loss": float(loss.detach())}

    def clone_parameters(self) -> list[torch.nn.Parameter]:
        """What behaviour cloning trains: the encoder and the actor."""
        return [*self.encoder.parameters(), *self.actor.parameters()]

    # ---- persistence -----------------------------------------------------------------------
    def state_dict(self) -> dict[str, Any]:
        state = super().state_dict()
        if self.decoder is not None:
            state["decoder"] = self.decoder.state_dict()
        return state

    def load_state_dict(self, state: dict[str, Any]) -> None:
        check_agent_state(state, AGENT_FORMAT, "SAC-DrQ", self.arch())
        if (self.decoder is None) != ("decoder" not in state):
            raise AgentStateError("agent state has a different encoder_aux_loss (a decoder in one of them only)")
        self.restore(state, self.SAC_MODULES + (("decoder",) if self.decoder is not None else ()), ("log_alpha",))
