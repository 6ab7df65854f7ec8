"""SAC + CURL (Srinivas et al. 2020) for the egocentric search task (paper 4.2, Table 2).

Networks (CURL's reference code, github.com/MishaLaskin/curl, with the paper's sizes):

- pixel encoder: the K = 5 depth frames as channels, float / 255, ``encoder_num_layers`` 3x3
  convs with ``encoder_num_filters`` channels (first stride 2, then stride 1) and ReLU, then a
  Linear to ``encoder_latent_dim`` = 128 and a LayerNorm (no tanh: CURL builds the encoder with
  ``output_logits=True``);
- the embedding is concatenated with the 30-d mask feature and the 4-d proprioception
  (paper 4.2) and fed to the MLPs;
- actor: MLP -> (mean, log-std), log-std squashed into [-10, 2] by a rescaled tanh, tanh-squashed
  Gaussian policy;
- twin critics Q1, Q2 on (features, action) with Polyak target copies (Q-heads at ``critic_tau``,
  the whole encoder at ``encoder_tau``);
- the actor shares the critic's conv layers but has its own Linear + LayerNorm projection, and
  its loss does not reach the convs (conv features are detached), as in CURL;
- automatic temperature with target entropy -|A|;
- CURL: two random 100 -> 84 crops of the same observations (anchor and positive), query = the
  online encoder on the anchor, key = the target (momentum) encoder on the positive, logits
  q W k^T minus the row max, cross-entropy with labels = arange(B) (in-batch negatives).

Two implementations of one update, selected by ``SacCurlAgent(impl=...)``:

- ``"fast"`` (default): CURL's numbers with every redundant pass removed: crops on the uint8
  tensor (strided copies on the CPU, one gather on a GPU), channels-last convs, fused Adam
  (CURL's two identical encoder optimisers folded into one step at 2 x lr),
  ``torch._foreach_lerp_`` Polyak updates, one post-critic-step conv forward of the anchor
  shared by the actor and the CURL query, the target encoder run once on [next_obs; positive]
  when no Polyak step lies between them. Optionally
  (``cfg.share_encoder_forward``, off by default) one more conv forward is saved by reusing the
  pre-step anchor features, at the price of a one-update lag in the actor and CURL losses;
- ``"reference"``: CURL's ``CurlSacAgent.update`` transcribed line by line (per-sample crops,
  separate forward passes, per-parameter Adam, CURL's two encoder optimisers). It is the
  correctness oracle (tests/test_rl_sac.py: same losses and parameters as the fast path) and
  the speed baseline (``egosearch.rl.bench_learner``).
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
    ModuleNets,
    Projection,
    activation,
    actor_head,
    actor_weights,
    adam,
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
from egosearch.rl.cuda_graph import GraphedUpdate
from egosearch.rl.learner import AgentBase
from egosearch.rl.pooled import SacMixin

AGENT_FORMAT = "egosearch-sac-curl-agent-v1"
ACTOR_FORMAT = "egosearch-sac-curl-actor-v1"


def conv_out_side(crop_size: int, num_layers: int) -> int:
    """Side of the last conv map: 3x3 kernels, stride 2 then 1 (84 -> 41 -> 39 -> 37 -> 35)."""
    return (crop_size - 3) // 2 + 1 - 2 * (num_layers - 1)


def crop_offsets(batch: int, image_size: int, crop_size: int,
                 device: torch.device) -> tuple[torch.Tensor, torch.Tensor]:
    """Uniform top-left corners in [0, image_size - crop_size] (torch's RNG on ``device``)."""
    hi = image_size - crop_size + 1
    oy = torch.randint(0, hi, (batch,), device=device)
    ox = torch.randint(0, hi, (batch,), device=device)
    return oy, ox


# ---- networks -----------------------------------------------------------------------------

# ---- the fast update's arithmetic, written once ------------------------------------------------
# One learner's losses from ``nets`` (a callable ``nets("critic.convs", x)``, with ``nets.tensor("W")``):
# SacCurlAgent._update_fast passes its own modules (egosearch.rl.common.ModuleNets), the stacked update
# (egosearch.rl.stacked) each seed's slice of the stacked parameters under vmap. The random numbers (crops,
# the policy's noise) come in as arguments, drawn by the caller in CURL's order.

def curl_key(nets, x: torch.Tensor) -> torch.Tensor:
    """The key (momentum) encoder's embedding: the target critic's convs and projection."""
    return nets("critic_target.proj", nets("critic_target.convs", x))


def curl_target(nets, nxt, pos, next_extra, reward, not_done, noise, alpha, *, gamma: float, early_key: bool):
    """(the critic's target, the positives' key embedding or None). The actor samples on next_obs through
    the online convs; with ``early_key`` the key encoder embeds [next_obs; positive] in one pass (its
    weights are the same for both). The caller runs it without autograd."""
    mu, log_std = nets("actor", nets("critic.convs", nxt), next_extra)
    next_pi, next_log_pi = squashed_sample(mu, log_std, noise)
    z_pos = None
    if early_key:
        z = curl_key(nets, torch.cat([nxt, pos]))
        z_next, z_pos = z[: nxt.shape[0]], z[nxt.shape[0]:]
    else:
        z_next = curl_key(nets, nxt)
    x = torch.cat([torch.cat([z_next, next_extra], dim=-1), next_pi], dim=-1)
    tq1, tq2 = nets("critic_target.q1", x), nets("critic_target.q2", x)
    return reward + not_done * gamma * (torch.min(tq1, tq2) - alpha * next_log_pi), z_pos


def curl_critic_loss(nets, anchor, extra, action, target_q):
    """(critic loss, mean Q1, the anchor's conv features, their projection)."""
    h = nets("critic.convs", anchor)
    z = nets("critic.proj", h)
    x = torch.cat([torch.cat([z, extra], dim=-1), action], dim=-1)
    q1, q2 = nets("critic.q1", x), nets("critic.q2", x)
    return F.mse_loss(q1, target_q) + F.mse_loss(q2, target_q), q1.mean(), h, z


def curl_features(nets, anchor):
    """The anchor's conv features and their projection (after the critic step: CURL's order)."""
    h = nets("critic.convs", anchor)
    return h, nets("critic.proj", h)


def curl_actor_loss(nets, h_post, z_post, extra, noise, alpha, *, z_given: bool):
    """(SAC's actor loss, log pi, the entropy) on the detached features ``h_post``. The critic's state is
    ``z_post`` when ``z_given`` (CURL's projection, just computed), else the projection of ``h_post``."""
    h_actor = h_post.detach()
    with torch.no_grad():
        z_state = z_post.detach() if z_given else nets("critic.proj", h_actor)
        state = torch.cat([z_state, extra], dim=-1)
    mu, log_std = nets("actor", h_actor, extra)
    pi, log_pi = squashed_sample(mu, log_std, noise)
    x = torch.cat([state, pi], dim=-1)
    aq1, aq2 = nets("critic.q1", x), nets("critic.q2", x)
    return (alpha * log_pi - torch.min(aq1, aq2)).mean(), log_pi, gaussian_entropy(log_std)


def curl_contrastive_loss(nets, z_anchor, z_pos) -> torch.Tensor:
    """CURL's InfoNCE with the bilinear ``W``: logits q W k^T (B, B), the diagonal the positives."""
    logits = z_anchor @ (nets.tensor("W") @ z_pos.T)
    logits = logits - logits.max(dim=1, keepdim=True)[0]
    return F.cross_entropy(logits, torch.arange(logits.shape[0], device=logits.device))


class ConvEncoder(nn.Module):
    """The conv layers of CURL's pixel encoder: uint8 or float pixels -> flat features."""

    def __init__(self, in_channels: int, num_layers: int, num_filters: int, act: str,
                 crop_size: int):
        super().__init__()
        self.convs = nn.ModuleList([nn.Conv2d(in_channels, num_filters, 3, stride=2)])
        for _ in range(num_layers - 1):
            self.convs.append(nn.Conv2d(num_filters, num_filters, 3, stride=1))
        self.act = activation(act)
        self.out_dim = num_filters * conv_out_side(crop_size, num_layers) ** 2

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        h = obs / 255.0
        for conv in self.convs:
            h = self.act(conv(h))
        return h.flatten(1)  # (C, H, W) order whatever the memory layout


class Critic(nn.Module):
    """Pixel encoder (convs + projection) and twin Q-functions on [embedding, mask, proprio, a]."""

    def __init__(self, cfg: LearnerConfig, extra_dim: int, action_dim: int):
        super().__init__()
        self.convs = ConvEncoder(cfg.frame_history, cfg.encoder_num_layers, cfg.encoder_num_filters,
                                 cfg.encoder_activation, cfg.crop_size)
        self.proj = Projection(self.convs.out_dim, cfg.encoder_latent_dim, cfg.encoder_tanh)
        in_dim = cfg.encoder_latent_dim + extra_dim + action_dim
        self.q1 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)
        self.q2 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)

    def encoder_parameters(self) -> list[nn.Parameter]:
        return list(self.convs.parameters()) + list(self.proj.parameters())

    def q_parameters(self) -> list[nn.Parameter]:
        return list(self.q1.parameters()) + list(self.q2.parameters())

    def state(self, h: torch.Tensor, extra: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.proj(h), extra], dim=-1)

    def q(self, state: torch.Tensor, action: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = torch.cat([state, action], dim=-1)
        return self.q1(x), self.q2(x)


class ActorNet(nn.Module):
    """What acting needs: the conv layers + the actor head (loaded by ``ActorPolicy``)."""

    def __init__(self, arch: dict[str, Any]):
        super().__init__()
        self.arch = dict(arch)
        self.convs = ConvEncoder(arch["frame_history"], arch["encoder_num_layers"],
                                 arch["encoder_num_filters"], arch["encoder_activation"],
                                 arch["crop_size"])
        self.head = actor_head(self.convs.out_dim, arch)

    def forward(self, depth: torch.Tensor, extra: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.convs(depth), extra)


_ARCH_FIELDS = ("frame_history", "image_size", "crop_size", "encoder_num_layers",
                "encoder_num_filters", "encoder_latent_dim", "encoder_activation", "encoder_tanh",
                "actor_hidden_dim", "actor_num_layers", "actor_activation", "actor_log_std_min",
                "actor_log_std_max", "critic_hidden_dim", "critic_num_layers", "critic_activation",
                "curl_latent")


# ---- the agent ----------------------------------------------------------------------------

class SacCurlAgent(SacMixin, AgentBase):
    """SAC + CURL learner, an :class:`egosearch.rl.learner.Agent`: ``act`` for one observation (a batch
    of them acts one by one), ``update`` for one batch of transitions (the replay stores the env's
    observations as they are)."""

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30,
                 proprio_dim: int = 4, impl: str = "fast", device: str | torch.device | None = None):
        if impl not in ("fast", "reference"):
            raise ValueError(f"impl={impl!r}; allowed: fast, reference")
        self.cfg = cfg.validate()
        self.impl = impl
        self.device = resolve_device(cfg.device) if device is None else torch.device(device)
        self.action_dim, self.mask_dim, self.proprio_dim = int(action_dim), int(mask_dim), int(proprio_dim)
        self.critic = Critic(cfg, self.mask_dim + self.proprio_dim, self.action_dim)
        self.critic.apply(weight_init)
        self.actor: ActorHead = actor_head(self.critic.convs.out_dim, self.arch())
        self.actor.apply(weight_init)
        self.critic.to(self.device)
        self.actor.to(self.device)
        self.channels_last = impl == "fast" and cfg.channels_last
        if self.channels_last:
            self.critic.convs.to(memory_format=torch.channels_last)
        self.critic_target = copy.deepcopy(self.critic)
        for p in self.critic_target.parameters():
            p.requires_grad_(False)
        self.W = nn.Parameter(torch.rand(cfg.curl_latent, cfg.curl_latent, device=self.device))
        self.log_alpha = torch.tensor(math.log(cfg.init_temperature), device=self.device,
                                      requires_grad=True)
        self.target_entropy = -float(self.action_dim)
        self.num_updates = 0
        # a recorded update needs fast-path kernels on a GPU, uncompiled, and Adam steps it can record
        self.graphed = (GraphedUpdate(self._update_fast) if cfg.cuda_graph and impl == "fast" and not cfg.compile
                        and self.device.type == "cuda" else None)
        self._build_optimisers()
        self._compiled = False
        if cfg.compile and impl == "fast":
            self._compile()

    # ---- optimisers ----------------------------------------------------------------------
    def _adam(self, params, lr: float, betas: tuple[float, float]) -> torch.optim.Adam:
        if self.impl == "reference":
            return torch.optim.Adam(params, lr=lr, betas=betas, foreach=False)
        return adam(params, lr, betas, capturable=self.graphed is not None)

    def _build_optimisers(self) -> None:
        cfg = self.cfg
        self.critic_opt = self._adam(self.critic.parameters(), cfg.critic_lr, (cfg.critic_beta1, cfg.critic_beta2))
        self.actor_opt = self._adam(self.actor.parameters(), cfg.actor_lr, (cfg.actor_beta1, cfg.actor_beta2))
        self.alpha_opt = self._adam([self.log_alpha], cfg.alpha_lr, (cfg.alpha_beta1, cfg.alpha_beta2))
        enc_betas = (cfg.encoder_beta1, cfg.encoder_beta2)
        enc_params = self.critic.encoder_parameters()
        if self.impl == "reference":
            # CURL: encoder_optimizer(critic.encoder) + cpc_optimizer(CURL = encoder, target, W)
            self.encoder_opt = self._adam(enc_params, cfg.encoder_lr, enc_betas)
            cpc = (enc_params if cfg.curl_double_encoder_step else []) + [self.W]
            self.cpc_opt = self._adam(cpc, cfg.encoder_lr, enc_betas)
            self.optimisers = {"critic": self.critic_opt, "actor": self.actor_opt,
                               "alpha": self.alpha_opt, "encoder": self.encoder_opt, "cpc": self.cpc_opt}
        else:
            scale = 2.0 if cfg.curl_double_encoder_step else 1.0
            self.curl_opt = self._adam([{"params": enc_params, "lr": scale * cfg.encoder_lr},
                                        {"params": [self.W], "lr": cfg.encoder_lr}],
                                       cfg.encoder_lr, enc_betas)
            self.optimisers = {"critic": self.critic_opt, "actor": self.actor_opt,
                               "alpha": self.alpha_opt, "curl": self.curl_opt}

    def _compile(self) -> None:
        import torch._functorch.config as functorch_config

        # the shared-forward update backpropagates twice through one graph (retain_graph)
        functorch_config.donated_buffer = False
        for module in (self.critic.convs, self.critic_target.convs, self.critic.proj,
                       self.critic_target.proj, self.actor, self.critic.q1, self.critic.q2,
                       self.critic_target.q1, self.critic_target.q2):
            module.compile()
        self._compiled = True

    # ---- acting --------------------------------------------------------------------------
    def _to_float(self, depth_u8: torch.Tensor) -> torch.Tensor:
        if self.channels_last:
            return depth_u8.to(torch.float32, memory_format=torch.channels_last)
        return depth_u8.float()

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """Action in [-1, 1]^A for ONE env observation (centre crop, as CURL does at act time)."""
        with torch.inference_mode():
            depth, extra = obs_to_tensors(obs, self.device, self.cfg.crop_size)
            mu, log_std = self.actor(self.critic.convs(self._to_float(depth)), extra)
            if deterministic:
                a = torch.tanh(mu)
            else:
                a, _ = squashed_sample(mu, log_std, torch.randn_like(mu))
        return a[0].float().cpu().numpy()

    # ---- updating ------------------------------------------------------------------------
    def _crops(self, batch: dict) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """(anchor, next, positive) uint8 crops; offsets drawn in CURL's order."""
        obs, nxt = batch["obs_depth"], batch["next_obs_depth"]
        b, s, size = obs.shape[0], self.cfg.image_size, self.cfg.crop_size
        offsets = [crop_offsets(b, s, size, obs.device) for _ in range(3)]
        if self.impl == "reference":  # per-sample slicing, as CURL's numpy random_crop
            def crop(x, oy, ox):
                x, oy, ox = x.cpu().numpy(), oy.cpu().numpy(), ox.cpu().numpy()
                out = np.empty(x.shape[:2] + (size, size), x.dtype)
                for i in range(x.shape[0]):
                    out[i] = x[i, :, oy[i]:oy[i] + size, ox[i]:ox[i] + size]
                return torch.as_tensor(out, device=self.device)
        else:
            def crop(x, oy, ox):
                return crop_at(x, oy, ox, size)
        return crop(obs, *offsets[0]), crop(nxt, *offsets[1]), crop(obs, *offsets[2])

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        """One SAC + CURL gradient update on a replay batch (see ``ReplayBuffer.sample``).

        Returns the metrics of ``METRIC_KEYS``; losses not computed this update (actor and
        temperature every ``actor_update_freq`` updates, CURL every ``curl_update_freq``) are NaN.
        """
        self.num_updates += 1
        if self.impl == "reference":
            out = self._update_reference(batch)
        elif self.graphed is not None:
            cfg, step = self.cfg, self.num_updates
            steps_taken = (step % cfg.curl_update_freq == 0, step % cfg.actor_update_freq == 0,
                           step % cfg.critic_target_update_freq == 0)
            out = self.graphed(steps_taken, batch)
        else:
            out = self._update_fast(batch)
        return metric_values(out, self.device)

    def _batch_parts(self, batch):
        extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1)
        next_extra = torch.cat([batch["next_mask"], batch["next_proprio"]], dim=-1)
        return extra, next_extra, batch["action"], batch["reward"], batch["not_done"]

    def _update_fast(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """CURL's update with every redundant pass removed.

        Exact merges (CURL's numbers): the conv features of the anchor crop AFTER the critic
        step are computed once and used by both the actor (detached) and the CURL query
        (the actor step and the Polyak step do not touch the online encoder); the critic's
        projection of them doubles as the actor's critic state; the key encoder runs once on
        [next_obs; positive] whenever no Polyak step happens in between.
        ``share_encoder_forward`` additionally reuses the PRE-step anchor features (one conv
        forward less; the actor and CURL losses then lag the critic step by one update).
        """
        cfg, step, nets = self.cfg, self.num_updates, ModuleNets(self)
        share = cfg.share_encoder_forward
        do_curl = step % cfg.curl_update_freq == 0
        do_actor = step % cfg.actor_update_freq == 0
        do_polyak = step % cfg.critic_target_update_freq == 0
        early_key = do_curl and (share or not do_polyak)  # key encoder weights = those of the target pass
        extra, next_extra, action, reward, not_done = self._batch_parts(batch)
        anchor_u8, next_u8, pos_u8 = self._crops(batch)
        anchor, nxt = self._to_float(anchor_u8), self._to_float(next_u8)
        pos = self._to_float(pos_u8) if do_curl else None  # only CURL's key reads the positives
        noise_next = torch.randn((anchor.shape[0], self.action_dim), device=self.device)
        alpha = self.log_alpha.detach().exp()
        out: dict[str, torch.Tensor] = {}

        # -- critic target (no grad): actor on next_obs (online convs), target critic ----------
        with torch.no_grad():
            target_q, z_pos = curl_target(nets, nxt, pos, next_extra, reward, not_done, noise_next, alpha,
                                          gamma=cfg.gamma, early_key=early_key)

        # -- critic ------------------------------------------------------------------------------
        critic_loss, out["q_mean"], h, z_anchor = curl_critic_loss(nets, anchor, extra, action, target_q)
        out["critic_loss"] = critic_loss
        critic_params = [p for g in self.critic_opt.param_groups for p in g["params"]]
        curl_params = [p for g in self.curl_opt.param_groups for p in g["params"]]
        curl_grads = None
        if share and do_curl:
            curl_loss = curl_contrastive_loss(nets, z_anchor, z_pos)
            out["curl_loss"] = curl_loss
            grads = torch.autograd.grad(critic_loss, critic_params, retain_graph=True)
            curl_grads = torch.autograd.grad(curl_loss, curl_params)
        else:
            grads = torch.autograd.grad(critic_loss, critic_params)
        for p, g in zip(critic_params, grads):
            p.grad = g
        self.critic_opt.step()
        del grads

        # -- anchor features after the critic step (CURL's order), shared by actor and CURL -----
        z_post = None
        if share:
            h_post = h.detach()
        elif do_curl:
            h_post, z_post = curl_features(nets, anchor)
        elif do_actor:
            with torch.no_grad():
                h_post = nets("critic.convs", anchor)

        # -- actor and temperature (conv features detached: the actor never trains the convs) --
        if do_actor:
            noise_pi = torch.randn((anchor.shape[0], self.action_dim), device=self.device)
            actor_loss, log_pi, out["entropy"] = curl_actor_loss(
                nets, h_post, h_post if z_post is None else z_post, extra, noise_pi, alpha, z_given=z_post is not None)
            self.actor_and_alpha_steps_on(actor_loss, log_pi, out)
            out["actor_loss"] = actor_loss

        # -- Polyak averaging of the target critic and key encoder --------------------------
        if do_polyak:
            self._polyak()

        # -- CURL --------------------------------------------------------------------------------
        if do_curl:
            if curl_grads is None:
                if not early_key:  # the key encoder just moved: CURL uses the new one
                    with torch.no_grad():
                        z_pos = curl_key(nets, pos)
                curl_loss = curl_contrastive_loss(nets, z_post, z_pos)
                out["curl_loss"] = curl_loss
                curl_grads = torch.autograd.grad(curl_loss, curl_params)
            for p, g in zip(curl_params, curl_grads):
                p.grad = g
            self.curl_opt.step()
        out["alpha"] = self.log_alpha.detach().exp()
        return out

    def _curl_loss(self, z_anchor: torch.Tensor, z_pos: torch.Tensor) -> torch.Tensor:
        return curl_contrastive_loss(ModuleNets(self), z_anchor, z_pos)

    def curl_update(self, anchor_u8: torch.Tensor, pos_u8: torch.Tensor) -> float:
        """One contrastive step alone on given (B, K, S, S) uint8 crops: query = online
        encoder on ``anchor_u8``, key = target encoder on ``pos_u8``. Returns the loss before
        the step (for tests and diagnostics; ``update`` does this as part of SAC + CURL)."""
        with torch.no_grad():
            z_pos = self.critic_target.proj(self.critic_target.convs(self._to_float(pos_u8)))
        loss = self._curl_loss(self.critic.proj(self.critic.convs(self._to_float(anchor_u8))), z_pos)
        opts = [self.encoder_opt, self.cpc_opt] if self.impl == "reference" else [self.curl_opt]
        for opt in opts:
            opt.zero_grad()
        loss.backward()
        for opt in opts:
            opt.step()
        return float(loss.detach())

    @torch.no_grad()
    def _polyak(self) -> None:
        c, t = self.critic, self.critic_target
        if self.impl == "reference":  # CURL's utils.soft_update_params
            for net, tnet, tau in ((c.q1, t.q1, self.cfg.critic_tau), (c.q2, t.q2, self.cfg.critic_tau),
                                   (c.convs, t.convs, self.cfg.encoder_tau), (c.proj, t.proj, self.cfg.encoder_tau)):
                for p, tp in zip(net.parameters(), tnet.parameters()):
                    tp.data.copy_(tau * p.data + (1 - tau) * tp.data)
            return
        torch._foreach_lerp_(t.q_parameters(), c.q_parameters(), self.cfg.critic_tau)
        torch._foreach_lerp_(t.encoder_parameters(), c.encoder_parameters(), self.cfg.encoder_tau)

    def _update_reference(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """CURL's ``CurlSacAgent.update`` (curl_sac.py), transcribed."""
        cfg, critic, target, step = self.cfg, self.critic, self.critic_target, self.num_updates
        extra, next_extra, action, reward, not_done = self._batch_parts(batch)
        obs_u8, next_u8, pos_u8 = self._crops(batch)
        obs, next_obs, pos = obs_u8.float(), next_u8.float(), pos_u8.float()
        out: dict[str, torch.Tensor] = {}

        def actor_forward(x, ex, detach_encoder=False):  # CURL's Actor.forward (tied convs)
            h = critic.convs(x)
            if detach_encoder:
                h = h.detach()
            mu, log_std = self.actor(h, ex)
            pi, log_pi = squashed_sample(mu, log_std, torch.randn_like(mu))
            return pi, log_pi, log_std

        def critic_forward(net, x, ex, a, detach_encoder=False):  # CURL's Critic.forward
            h = net.convs(x)
            if detach_encoder:
                h = h.detach()
            return net.q(net.state(h, ex), a)

        # update_critic
        with torch.no_grad():
            policy_action, log_pi, _ = actor_forward(next_obs, next_extra)
            tq1, tq2 = critic_forward(target, next_obs, next_extra, policy_action)
            target_v = torch.min(tq1, tq2) - self.log_alpha.exp().detach() * log_pi
            target_q = reward + not_done * cfg.gamma * target_v
        q1, q2 = critic_forward(critic, obs, extra, action)
        critic_loss = F.mse_loss(q1, target_q) + F.mse_loss(q2, target_q)
        self.critic_opt.zero_grad()
        critic_loss.backward()
        self.critic_opt.step()
        out["critic_loss"], out["q_mean"] = critic_loss, q1.mean()

        # update_actor_and_alpha
        if step % cfg.actor_update_freq == 0:
            pi, log_pi, log_std = actor_forward(obs, extra, detach_encoder=True)
            aq1, aq2 = critic_forward(critic, obs, extra, pi, detach_encoder=True)
            actor_loss = (self.log_alpha.exp().detach() * log_pi - torch.min(aq1, aq2)).mean()
            self.actor_opt.zero_grad()
            actor_loss.backward()
            self.actor_opt.step()
            self.alpha_opt.zero_grad()
            alpha_loss = (self.log_alpha.exp() * (-log_pi - self.target_entropy).detach()).mean()
            alpha_loss.backward()
            self.alpha_opt.step()
            out["actor_loss"], out["alpha_loss"] = actor_loss, alpha_loss
            out["entropy"] = gaussian_entropy(log_std)

        if step % cfg.critic_target_update_freq == 0:
            self._polyak()

        # update_cpc
        if step % cfg.curl_update_freq == 0:
            z_a = critic.proj(critic.convs(obs))
            with torch.no_grad():
                z_pos = target.proj(target.convs(pos))
            curl_loss = self._curl_loss(z_a, z_pos)
            self.encoder_opt.zero_grad()
            self.cpc_opt.zero_grad()
            curl_loss.backward()
            self.encoder_opt.step()
            self.cpc_opt.step()
            out["curl_loss"] = curl_loss
        out["alpha"] = self.log_alpha.detach().exp()
        return out

    # ---- persistence -----------------------------------------------------------------------
    def arch(self) -> dict[str, Any]:
        """Everything that fixes tensor shapes (plain python types)."""
        arch = {name: getattr(self.cfg, name) for name in _ARCH_FIELDS}
        arch.update(action_dim=self.action_dim, mask_dim=self.mask_dim, proprio_dim=self.proprio_dim,
                    extra_dim=self.mask_dim + self.proprio_dim)
        return arch

    def state_dict(self) -> dict[str, Any]:
        """The full agent: networks, targets, W, temperature, optimisers, update counter."""
        return {
            "format": AGENT_FORMAT,
            "impl": self.impl,
            "arch": self.arch(),
            "critic": self.critic.state_dict(),
            "critic_target": self.critic_target.state_dict(),
            "actor": self.actor.state_dict(),
            "W": self.W.detach().clone(),
            "log_alpha": self.log_alpha.detach().clone(),
            "optimisers": {k: opt.state_dict() for k, opt in self.optimisers.items()},
            "num_updates": self.num_updates,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        if not isinstance(state, dict) or state.get("format") != AGENT_FORMAT:
            raise AgentStateError("not a SAC+CURL agent state "
                                  f"(format={state.get('format') if isinstance(state, dict) else None!r})")
        if state.get("impl") != self.impl:
            raise AgentStateError(f"agent state is for impl={state.get('impl')!r}, this agent is {self.impl!r}")
        diff = sorted(k for k, v in self.arch().items() if state["arch"].get(k) != v)
        if diff:
            raise AgentStateError("agent state has a different architecture: "
                                  + ", ".join(f"{k}={state['arch'].get(k)!r} (here {self.arch()[k]!r})" for k in diff))
        self.critic.load_state_dict(state["critic"])
        self.critic_target.load_state_dict(state["critic_target"])
        self.actor.load_state_dict(state["actor"])
        with torch.no_grad():
            self.W.copy_(state["W"])
            self.log_alpha.copy_(state["log_alpha"])
        for k, opt in self.optimisers.items():
            opt.load_state_dict(state["optimisers"][k])
            for group in opt.param_groups:  # saved by a run with or without graphs: this agent's choice holds
                group["capturable"] = self.graphed is not None
        self.num_updates = int(state["num_updates"])
        if self.graphed is not None:  # the graphs point at the optimiser state just replaced
            self.graphed.reset()

    def actor_state(self, metadata: dict[str, Any] | None = None,
                    storage_dtype: torch.dtype = torch.float16) -> dict[str, Any]:
        """Actor-only weights (conv layers + actor projection + actor MLP) with ``arch`` and
        ``metadata``: tensors and plain python types only, so ``torch.load(weights_only=True)``
        reads it. ``ActorNet(arch)`` loads ``state_dict`` (casting back to float32).

        Floating weights are stored as ``storage_dtype``: float16 halves the file (the conv-to-128
        projection alone is 2.5M weights at the cpu preset), keeping a committed actor under
        10 MB; actions then differ from the live agent's by ~1e-3. :func:`load_actor_net` rounds
        through float16 whatever the storage, so every reported number is of the float16 actor."""
        weights = actor_weights({"convs": self.critic.convs, "head": self.actor}, storage_dtype)
        return {"format": ACTOR_FORMAT, "arch": self.arch(), "state_dict": weights,
                "metadata": dict(metadata or {})}


def load_actor_net(state: dict[str, Any], device: str | torch.device = "cpu") -> ActorNet:
    """Rebuild an :class:`ActorNet` from :meth:`SacCurlAgent.actor_state`."""
    if not isinstance(state, dict) or state.get("format") != ACTOR_FORMAT:
        raise AgentStateError("not an actor file (format="
                              f"{state.get('format') if isinstance(state, dict) else None!r})")
    return load_actor_weights(ActorNet(state["arch"]), state, device)
