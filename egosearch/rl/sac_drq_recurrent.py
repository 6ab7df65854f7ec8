"""Recurrent SAC-DrQ: :mod:`egosearch.rl.sac_drq` with a GRU memory in the actor and in the critic.

NOT the paper's learner, nor the cpu preset's: a lever for the searcher's ceiling. The
memoryless learners see the last ``frame_history`` depth frames and nothing older, so a search
cannot know where it has already looked. Here the actor and the critic each carry a GRU state
over the whole episode.

After Ni et al. 2022 ("Recurrent model-free RL can be a strong baseline for many POMDPs",
github.com/twni2016/pomdp-baselines): SEPARATE recurrent networks for the actor and the critic
(their most robust setting; a shared RNN trained by both losses was unstable there), and after
R2D2 (Kapturowski et al. 2019): replay of contiguous sequences, whose first ``burn_in`` steps
only warm the hidden state up (no gradient) before the ``sequence_length`` steps that carry the
losses, with zero initial states (R2D2's "zero start state" plus burn-in).

What it keeps from SAC-DrQ: ONE conv encoder (:class:`egosearch.rl.pooled.PooledConvEncoder`) trained by the critic
loss only, read detached by the actor; random-shift augmentation (one shift per sequence, so
that the memory sees a steady camera); pooled uint8 frames in the replay; n-step returns;
twin Q-heads with a Polyak target (here the target also holds a copy of the critic's GRU);
the optional privileged critic (the state enters the Q-heads, not the GRU). Its set-up, actor and
temperature step, Polyak step and agent state are SAC-DrQ's (:class:`egosearch.rl.sac_drq.SacDrqBase`).

Per step, a network's GRU reads [projected conv features, mask, proprio] and its head reads
[GRU output, projected conv features, mask, proprio] (the current observation stays one layer
away from the output, as in the memoryless learner, and as pomdp-baselines' recommended
architecture keeps a branch for the current observation). Unlike Ni et al., the GRUs do not read
the previous action and reward (the observation's proprio already holds the last head motion);
feeding them is a further option, not tried here.

Sequences (:func:`sample_sequences`) are windows of ``burn_in + sequence_length`` consecutive
transitions of one env's ring (:class:`egosearch.rl.replay.MultiReplay` is reused unchanged, so
checkpoints hold the same replay), plus the last transition's next observation. A window may
span episode boundaries: the hidden state is zeroed at every episode's first step (``first``),
exactly as acting zeroes it when an env resets, and an n-step target never bootstraps from an
observation of another episode (a truncated step whose next observation is not in the window is
left out of the critic loss: ``loss_mask``).

It learns from the classical searcher as SAC-DrQ does (:mod:`egosearch.rl.training_aids`), in sequences:
behaviour cloning of the encoder and the actor's GRU and head on the teacher's sequences (the burn-in
warming the memory only), DAgger rounds whose student starts each episode with an empty memory, the
critic's warm-up (the cloned encoder and actor frozen), a share of each update's sequences drawn from the
demonstrations and TD3+BC's term on their loss steps. The ``head_on_recurrent_imitation`` lever: the GRU
student through imitation, then fine-tuning.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from egosearch.rl.common import (
    Projection,
    check_agent_state,
    crop_at,
    gaussian_entropy,
    load_actor_weights,
    mlp,
    obs_to_tensors,
    squashed_sample,
)
from egosearch.rl.config import LearnerConfig
from egosearch.rl.learner import demo_column
from egosearch.rl.pooled import DRQ_ARCH_FIELDS, pooled_encoder
from egosearch.rl.replay import MultiReplay, ReplayBuffer, proportional_counts
from egosearch.rl.sac_drq import SacDrqBase
from egosearch.rl.training_aids import demonstration_settings

AGENT_FORMAT = "egosearch-sac-drq-recurrent-agent-v1"
ACTOR_FORMAT = "egosearch-sac-drq-recurrent-actor-v1"
ARCH_FIELDS = (*DRQ_ARCH_FIELDS, "recurrent_hidden_dim")
"""The config fields in the arch dict: SAC-DrQ's and the GRUs' size."""


def sequences_per_batch(cfg: LearnerConfig) -> int:
    """Sequences per update: ``batch_size`` counts the steps that carry a loss, as the memoryless
    learners' batch does, so an update costs about as many conv passes as theirs."""
    return max(1, cfg.batch_size // cfg.sequence_length)


# ---- recurrent cores ------------------------------------------------------------------------

def run_gru(cell: nn.GRUCell, x: torch.Tensor, first: torch.Tensor, h: torch.Tensor | None = None) -> torch.Tensor:
    """``cell`` over (B, T, D) inputs from state ``h`` (zeros if None), zeroing the state before
    every step whose ``first`` (B, T) is 1 (an episode's first step). Returns (B, T, H): the state
    after each step."""
    b, t = x.shape[:2]
    if h is None:
        h = x.new_zeros(b, cell.hidden_size)
    keep = (1.0 - first).unsqueeze(-1)
    out = []
    for i in range(t):
        h = cell(x[:, i], h * keep[:, i])
        out.append(h)
    return torch.stack(out, dim=1)


class RecurrentActorHead(nn.Module):
    """Projection -> GRU over [embedding, mask, proprio] -> MLP on [GRU, embedding, mask, proprio]
    -> (mu, log_std) with CURL's log-std squashing."""

    def __init__(self, conv_dim: int, arch: dict[str, Any]):
        super().__init__()
        latent, extra, hidden = arch["encoder_latent_dim"], arch["extra_dim"], arch["recurrent_hidden_dim"]
        self.proj = Projection(conv_dim, latent, arch["encoder_tanh"])
        self.gru = nn.GRUCell(latent + extra, hidden)
        self.trunk = mlp(hidden + latent + extra, arch["actor_hidden_dim"], 2 * arch["action_dim"],
                         arch["actor_num_layers"], arch["actor_activation"])
        self.log_std_min, self.log_std_max = float(arch["actor_log_std_min"]), float(arch["actor_log_std_max"])

    def inputs(self, feats: torch.Tensor, extra: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.proj(feats), extra], dim=-1)

    def out(self, mem: torch.Tensor, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        mu, log_std = self.trunk(torch.cat([mem, x], dim=-1)).chunk(2, dim=-1)
        log_std = torch.tanh(log_std)
        return mu, self.log_std_min + 0.5 * (self.log_std_max - self.log_std_min) * (log_std + 1)

    def step(self, feats: torch.Tensor, extra: torch.Tensor, h: torch.Tensor | None):
        """One acting step: (mu, log_std, new state) for (B, F) features and a (B, H) state."""
        x = self.inputs(feats, extra)
        h = self.gru(x, h if h is not None else x.new_zeros(x.shape[0], self.gru.hidden_size))
        mu, log_std = self.out(h, x)
        return mu, log_std, h


class RecurrentCritic(nn.Module):
    """Projection -> GRU over [embedding, mask, proprio] -> twin Q-heads on [GRU, embedding, mask,
    proprio, (privileged state), action]. Its Polyak copy is the target critic, GRU included."""

    def __init__(self, conv_dim: int, cfg: LearnerConfig, extra_dim: int, state_dim: int, action_dim: int):
        super().__init__()
        latent, hidden = cfg.encoder_latent_dim, cfg.recurrent_hidden_dim
        self.proj = Projection(conv_dim, latent, cfg.encoder_tanh)
        self.gru = nn.GRUCell(latent + extra_dim, hidden)
        in_dim = hidden + latent + extra_dim + state_dim + action_dim
        self.q1 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)
        self.q2 = mlp(in_dim, cfg.critic_hidden_dim, 1, cfg.critic_num_layers, cfg.critic_activation)

    def inputs(self, feats: torch.Tensor, extra: torch.Tensor) -> torch.Tensor:
        return torch.cat([self.proj(feats), extra], dim=-1)

    def q(self, mem: torch.Tensor, x: torch.Tensor, state: torch.Tensor | None, action: torch.Tensor):
        parts = [mem, x] + ([state] if state is not None else []) + [action]
        z = torch.cat(parts, dim=-1)
        return self.q1(z), self.q2(z)


def _sequence_memory(x: torch.Tensor, first: torch.Tensor, gru: nn.GRUCell, burn_in: int) -> torch.Tensor:
    """GRU states over a whole window; the first ``burn_in`` steps run without autograd, so no
    gradient reaches them (R2D2's burn-in) and their backward pass costs nothing."""
    if burn_in <= 0:
        return run_gru(gru, x, first)
    with torch.no_grad():
        warm = run_gru(gru, x[:, :burn_in], first[:, :burn_in])
    rest = run_gru(gru, x[:, burn_in:], first[:, burn_in:], warm[:, -1])
    return torch.cat([warm, rest], dim=1)


class RecurrentDrqActorNet(nn.Module):
    """What acting needs: encoder + recurrent actor head. ``forward(depth, extra, h)`` takes the
    env's uint8 depth (B, K, H, W) and the state (None at an episode's start) and returns
    (mu, log_std, new state)."""

    recurrent = True

    def __init__(self, arch: dict[str, Any]):
        super().__init__()
        self.arch = dict(arch)
        self.encoder = pooled_encoder(arch)
        self.head = RecurrentActorHead(self.encoder.out_dim, arch)

    def forward(self, depth: torch.Tensor, extra: torch.Tensor, h: torch.Tensor | None = None):
        return self.head.step(self.encoder(self.encoder.pool(depth)), extra, h)


# ---- sequence replay --------------------------------------------------------------------------

def sample_ring_sequences(buf: ReplayBuffer, starts: np.ndarray, burn_in: int, length: int, n_step: int,
                          gamma: float) -> dict[str, np.ndarray]:
    """Windows of ``burn_in + length`` transitions of ring ``buf`` starting at absolute indices
    ``starts`` (B,), as numpy arrays (see :func:`sample_sequences` for the keys)."""
    w = burn_in + length
    idx = np.asarray(starts, np.int64)[:, None] + np.arange(w)[None, :]  # (B, W)
    b = idx.shape[0]
    i = idx % buf.capacity
    fn = buf.frame_numbers(idx.reshape(-1)).reshape(b, w, buf.k + 1)
    frame_no = np.concatenate([fn[:, :, :-1], fn[:, -1:, 1:]], axis=1)  # (B, W+1, K): obs..., last next_obs
    depth = buf.frames[frame_no % buf.n_frames]
    last = i[:, -1]
    extra = np.concatenate([np.concatenate([buf.masks(i), buf.proprio[i]], -1),
                            np.concatenate([buf.masks(last, nxt=True), buf.next_proprio[last]], -1)[:, None]], axis=1)
    first = np.zeros((b, w + 1), np.float32)
    first[:, :w] = buf.t_in_ep[i] == 0
    term, trunc, reward = buf.terminated[i], buf.truncated[i], buf.reward[i].astype(np.float64)
    # n-step targets of the positions that carry a loss, all at once: (B, L) arrays
    pos = burn_in + np.arange(length)
    ret = np.zeros((b, length))
    disc = np.ones((b, length))
    m = np.zeros((b, length), np.int64)
    not_done = np.ones((b, length), np.float32)
    loss_mask = np.ones((b, length), np.float32)
    open_ = np.ones((b, length), bool)
    for j in range(n_step):
        q = pos + j
        qc = np.minimum(q, w - 1)
        te, tr = term[:, qc], trunc[:, qc]
        # a truncated step's next observation is in the window only as its last one (o_W):
        # elsewhere o_{q+1} is the next episode's reset observation, so the return stops before
        # that step, or, when it is the position's own step, the position carries no critic loss
        cut = tr & ~te & (q < w - 1)[None, :]
        if j == 0:
            loss_mask[cut] = 0.0
        else:
            open_ &= ~cut
        open_ &= (q < w)[None, :]
        ret += np.where(open_, disc * reward[:, qc], 0.0)
        disc = np.where(open_, disc * gamma, disc)
        m += open_
        not_done[open_ & te] = 0.0
        open_ &= ~(te | tr)
    boot = pos[None, :] + m
    out = {"depth": depth, "extra": extra, "first": first, "action": buf.action[i],
           "reward": ret.astype(np.float32), "discount": disc.astype(np.float32), "boot": boot,
           "not_done": not_done, "loss_mask": loss_mask, "index": idx}
    if buf.state_dim:
        out["state"] = np.concatenate([buf.state[i], buf.next_state[last][:, None]], axis=1)
    return out


def sample_sequences(replay: MultiReplay, num_sequences: int, burn_in: int, length: int, n_step: int,
                     gamma: float, device: torch.device | str = "cpu") -> dict[str, torch.Tensor]:
    """``num_sequences`` windows spread evenly over the env rings (as :meth:`MultiReplay.sample`
    spreads transitions), each drawn uniformly from its ring's stored windows with the ring's RNG.

    Keys (B sequences, W = burn_in + length windows, T = W + 1 observations):
    ``depth`` (B, T, K, H, W) uint8, ``extra`` (B, T, mask + proprio), ``first`` (B, T) 1 at an
    episode's first step, ``action`` (B, W, A), ``state`` (B, T, S) with a privileged critic;
    for the last ``length`` positions: ``reward`` (n-step sum), ``discount`` (gamma^m), ``boot``
    (index 0..W of the observation the target bootstraps from), ``not_done``, ``loss_mask``;
    ``index`` (B, W) absolute transition numbers."""
    w = burn_in + length
    n = len(replay.buffers)
    sizes = [num_sequences // n + (1 if i < num_sequences % n else 0) for i in range(n)]
    parts = []
    for buf, size in zip(replay.buffers, sizes):
        lo, hi = buf._first_valid(), buf.n_added - w  # hi: the last start whose window is stored
        if size == 0 or hi < lo:
            continue
        parts.append(sample_ring_sequences(buf, buf.rng.integers(lo, hi + 1, size=size), burn_in, length,
                                           n_step, gamma))
    if not parts:
        raise ValueError(f"no env ring holds a window of {w} transitions (burn_in + sequence_length) yet")
    dev = torch.device(device)
    return {k: torch.from_numpy(np.ascontiguousarray(np.concatenate([p[k] for p in parts]))).to(dev)
            for k in parts[0]}


def shift_sequences(x: torch.Tensor, pad: int) -> torch.Tensor:
    """DrQ-v2's random shift with ONE offset per sequence: (B, T, C, H, W) float."""
    if pad <= 0:
        return x
    b, t, c, h, w = x.shape
    oy = torch.randint(0, 2 * pad + 1, (b,), device=x.device).repeat_interleave(t)
    ox = torch.randint(0, 2 * pad + 1, (b,), device=x.device).repeat_interleave(t)
    padded = F.pad(x.reshape(b * t, c, h, w), (pad, pad, pad, pad), mode="replicate")
    return crop_at(padded, oy, ox, h).reshape(b, t, c, h, w)


# ---- the agent ------------------------------------------------------------------------------

class SacDrqRecurrentAgent(SacDrqBase):
    """Recurrent SAC-DrQ (module docstring). An :class:`egosearch.rl.learner.Agent` with a memory
    (``recurrent``): ``sample_batch(replay)`` draws sequences instead of transitions,
    ``reset_state(env_index)`` forgets an env's ended episode and ``reset_policy_state()`` the
    evaluation episode's."""

    recurrent = True
    agent_format = AGENT_FORMAT
    actor_format = ACTOR_FORMAT
    arch_fields = ARCH_FIELDS

    def __init__(self, cfg: LearnerConfig, action_dim: int, mask_dim: int = 30, proprio_dim: int = 4,
                 device: str | torch.device | None = None, state_dim: int = 0):
        super().__init__(cfg, action_dim, mask_dim, proprio_dim, device, state_dim)
        # acting states, never checkpointed: train.py cuts every episode at a checkpoint
        self._h: torch.Tensor | None = None  # (num envs, H) of the training envs
        self._eval_h: torch.Tensor | None = None  # the single evaluation episode's

    def make_critic(self, arch: dict[str, Any]) -> RecurrentCritic:
        return RecurrentCritic(self.encoder.out_dim, self.cfg, arch["extra_dim"], self.state_dim, self.action_dim)

    def make_actor(self, arch: dict[str, Any]) -> RecurrentActorHead:
        return RecurrentActorHead(self.encoder.out_dim, arch)

    # ---- acting --------------------------------------------------------------------------
    def reset_state(self, env_index: int | None = None) -> None:
        """Zero the hidden state of training env ``env_index`` (all of them for None)."""
        if self._h is None:
            return
        if env_index is None:
            self._h = None
        else:
            self._h[env_index] = 0.0

    def reset_policy_state(self) -> None:
        """Zero the evaluation policy's hidden state (:class:`egosearch.rl.actor.AgentPolicy`)."""
        self._eval_h = None

    def _step(self, obs: dict, h: torch.Tensor | None, deterministic: bool):
        with torch.inference_mode():
            depth, extra = obs_to_tensors(obs, self.device, self.cfg.image_size)
            mu, log_std, h = self.actor.step(self.encoder(self.encoder.pool(depth)), extra, h)
            a = torch.tanh(mu) if deterministic else squashed_sample(mu, log_std, torch.randn_like(mu))[0]
        return a.float().cpu().numpy(), h

    def act_batch(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """Actions (B, A) of the first B training envs (a stacked batch), carrying their states."""
        b = np.asarray(obs["mask"]).reshape(-1, self.mask_dim).shape[0]
        if self._h is None or self._h.shape[0] < b:
            grown = torch.zeros(max(b, self.cfg.num_envs), self.cfg.recurrent_hidden_dim, device=self.device)
            if self._h is not None:
                grown[: self._h.shape[0]] = self._h
            self._h = grown
        a, h = self._step(obs, self._h[:b], deterministic)
        self._h[:b] = h
        return a

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        """One observation of the EVALUATION episode (its own state; see ``reset_policy_state``)."""
        a, self._eval_h = self._step(obs, self._eval_h, deterministic)
        return a[0]

    # ---- updating ------------------------------------------------------------------------
    def sample_batch(self, replay: MultiReplay) -> dict[str, torch.Tensor]:
        return self._sequences([replay], [sequences_per_batch(self.cfg)])

    def _sequences(self, sources: list[MultiReplay], counts: list[int]) -> dict[str, torch.Tensor]:
        """``counts[i]`` sequences of ``sources[i]`` each, concatenated in that order."""
        cfg = self.cfg
        parts = [sample_sequences(source, n, cfg.burn_in, cfg.sequence_length, cfg.n_step, cfg.gamma, self.device)
                 for source, n in zip(sources, counts) if n > 0]
        if len(parts) == 1:  # an update's plain draw: no copy
            return parts[0]
        return {k: torch.cat([p[k] for p in parts]) for k in parts[0]}

    def sample_with_demonstrations(self, replay: MultiReplay, demos: MultiReplay,
                                   fraction: float) -> dict[str, torch.Tensor]:
        """RLPD's batch in sequences: ``fraction`` of an update's sequences drawn from the demonstrations
        (the last ones, marked 1 in the (B, 1) ``demo`` column), the rest from the online replay."""
        size = sequences_per_batch(self.cfg)
        from_demos = round(size * fraction)
        batch = self._sequences([replay, demos], [size - from_demos, from_demos])
        batch["demo"] = demo_column(size, from_demos, self.device)
        return batch

    def cloning_batch(self, sources: list[MultiReplay], batch_size: int) -> dict[str, torch.Tensor]:
        """Behaviour cloning's batch in sequences (as an update's: ``batch_size // sequence_length`` of them,
        burn-in before each), drawn from ``sources`` in proportion to their sizes."""
        size = max(1, batch_size // self.cfg.sequence_length)
        return self._sequences(sources, proportional_counts([len(s) for s in sources], size))

    def clone_parameters(self) -> list[torch.nn.Parameter]:
        """What behaviour cloning trains: the encoder and the actor (its GRU and head)."""
        return [*self.encoder.parameters(), *self.actor.parameters()]

    def clone_update(self, batch: dict[str, torch.Tensor], optimiser: torch.optim.Optimizer) -> dict[str, float]:
        """A behaviour-cloning step on sequences (SAC-DrQ's, :meth:`SacDrqAgent.clone_update`, through the
        actor's memory): the squared error between the actor's mean action (after its tanh) and the
        teacher's at every loss step of each sequence, the burn-in warming the GRU only."""
        cfg = self.cfg
        train = slice(cfg.burn_in, cfg.burn_in + cfg.sequence_length)
        feats = self._features(shift_sequences(batch["depth"].float(), cfg.aug_pad))
        xa = self.actor.inputs(feats, batch["extra"])
        mem = _sequence_memory(xa, batch["first"], self.actor.gru, cfg.burn_in)
        mu, _ = self.actor.out(mem[:, train], xa[:, train])
        loss = (torch.tanh(mu) - batch["action"][:, train]).pow(2).sum(-1).mean()
        optimiser.zero_grad(set_to_none=True)
        loss.backward()
        optimiser.step()
        return {"bc_loss": float(loss.detach())}

    def _features(self, depth: torch.Tensor) -> torch.Tensor:
        """Conv features (B, T, F) of shifted pooled frames; burn-in frames without autograd."""
        b, t = depth.shape[:2]
        burn = self.cfg.burn_in

        def enc(x: torch.Tensor) -> torch.Tensor:
            return self.encoder(x.reshape(-1, *x.shape[2:])).reshape(x.shape[0], x.shape[1], -1)

        if burn <= 0:
            return enc(depth)
        with torch.no_grad():
            warm = enc(depth[:, :burn])
        return torch.cat([warm, enc(depth[:, burn:])], dim=1)

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        cfg = self.cfg
        self.num_updates += 1
        burn, length = cfg.burn_in, cfg.sequence_length
        depth = shift_sequences(batch["depth"].float(), cfg.aug_pad)
        extra, first = batch["extra"], batch["first"]
        state = batch.get("state") if self.state_dim else None
        train = slice(burn, burn + length)
        boot = batch["boot"]
        mask = batch["loss_mask"]
        alpha = self.log_alpha.detach().exp()
        out: dict[str, torch.Tensor] = {}
        # PIRLNav's critic warm-up, as SAC-DrQ's: the cloned encoder and actor stay as they are (the critic's
        # GRU and Q-heads learn)
        warming_up = self.num_updates <= demonstration_settings(cfg).critic_warmup_updates

        feats = self._features(depth)  # grad only after the burn-in
        feats_d = feats.detach()

        def at(x: torch.Tensor, index: torch.Tensor) -> torch.Tensor:  # x (B, T, D), index (B, L)
            return x.gather(1, index.unsqueeze(-1).expand(-1, -1, x.shape[-1]))

        with torch.no_grad():
            xa = self.actor.inputs(feats_d, extra)
            mem_a = run_gru(self.actor.gru, xa, first)
            xa_b = at(xa, boot)
            mu, log_std = self.actor.out(at(mem_a, boot), xa_b)
            next_pi, next_log_pi = squashed_sample(mu, log_std, torch.randn_like(mu))
            xt = self.critic_target.inputs(feats_d, extra)
            mem_t = run_gru(self.critic_target.gru, xt, first)
            tq1, tq2 = self.critic_target.q(at(mem_t, boot), at(xt, boot),
                                            at(state, boot) if state is not None else None, next_pi)
            bootstrap = (batch["not_done"] * batch["discount"]).unsqueeze(-1)
            target_q = batch["reward"].unsqueeze(-1) + bootstrap * (torch.min(tq1, tq2) - alpha * next_log_pi)

        xc = self.critic.inputs(feats_d if warming_up else feats, extra)
        mem_c = _sequence_memory(xc, first, self.critic.gru, burn)
        st = state[:, train] if state is not None else None
        q1, q2 = self.critic.q(mem_c[:, train], xc[:, train], st, batch["action"][:, train])
        weight = mask.unsqueeze(-1) / mask.sum().clamp(min=1.0)
        critic_loss = (weight * ((q1 - target_q) ** 2 + (q2 - target_q) ** 2)).sum()
        self.critic_opt.zero_grad(set_to_none=True)
        critic_loss.backward()
        self.critic_opt.step()
        out["critic_loss"], out["q_mean"] = critic_loss, (q1 * weight).sum()

        if self.num_updates % cfg.actor_update_freq == 0 and not warming_up:
            xa = self.actor.inputs(feats_d, extra)
            mem = _sequence_memory(xa, first, self.actor.gru, burn)
            mu, log_std = self.actor.out(mem[:, train], xa[:, train])
            pi, log_pi = squashed_sample(mu, log_std, torch.randn_like(mu))
            # the critic's memory as it was before its step (not recomputed: a GRU pass saved);
            # its Q-heads and projection are the stepped ones
            xc_now = self.critic.inputs(feats_d[:, train], extra[:, train])
            aq1, aq2 = self.critic.q(mem_c[:, train].detach(), xc_now, st, pi)
            penalty = None
            bc_weight = self.bc_weight_now if "demo" in batch else 0.0
            if bc_weight > 0:
                # TD3+BC's term on the demonstration sequences' loss steps, as SAC-DrQ's (drq_actor_loss)
                rows = batch["demo"].unsqueeze(-1)  # (B, 1, 1)
                error = (torch.tanh(mu) - batch["action"][:, train]).pow(2).sum(-1, keepdim=True)
                bc_loss = (rows * error).sum() / (rows.sum() * error.shape[1]).clamp(min=1.0)
                penalty = bc_weight * torch.min(aq1, aq2).abs().mean().detach() * bc_loss
                out["bc_loss"] = bc_loss
            self.actor_and_alpha_step(alpha, log_pi, aq1, aq2, out, penalty)
            out["entropy"] = gaussian_entropy(log_std.reshape(-1, log_std.shape[-1]))

        return self.finish_update(out)

    # ---- persistence -----------------------------------------------------------------------
    def load_state_dict(self, state: dict[str, Any]) -> None:
        check_agent_state(state, AGENT_FORMAT, "recurrent SAC-DrQ", self.arch())
        self.restore(state, self.SAC_MODULES, ("log_alpha",))
        self._h = self._eval_h = None


def load_recurrent_actor_net(state: dict[str, Any], device: str | torch.device = "cpu") -> RecurrentDrqActorNet:
    return load_actor_weights(RecurrentDrqActorNet(state["arch"]), state, device)
