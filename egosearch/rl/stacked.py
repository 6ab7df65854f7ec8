"""Seeds stacked: the updates of N trainings of one variant (seeds) done as one stacked model
(issue 47, item 4).

A Table 2 update at batch 32 launches hundreds of small kernels; on a GPU most of the chip sits idle
while one seed's kernels run. Stacking N seeds' parameters along a new leading dimension makes each
kernel do the work of all N: the networks run under ``torch.func.vmap`` with
``torch.func.functional_call`` (a conv becomes one grouped convolution, a Linear one batched
matmul), and the gradients come from ordinary autograd through the vmapped forward.

Why this equals N separate updates (the test, ``tests/test_rl_stacked.py``, checks it to float
rounding, parameters, optimiser states and metrics alike):

- every loss is computed per seed (vmap), and the stacked gradient is that of their SUM: a seed's
  parameters reach no other seed's loss, so each slice of the gradient is its seed's own;
- Adam is elementwise and every seed steps at the same update, so one Adam over the stacked tensors
  (the members' own hyper-parameters and groups) is N Adams; so is the Polyak step;
- the random numbers (crop or shift offsets, the policy's noise) are drawn per seed, in the order
  the learner's own ``update`` draws them, from that seed's own generator state
  (:class:`SeedStreams`), BEFORE the stacked arithmetic, which then draws nothing (so it can also be
  recorded as one CUDA graph, with the draws as its inputs).

The member agents stay ordinary learners (:class:`egosearch.rl.sac_curl.SacCurlAgent`,
:class:`egosearch.rl.sac_drq.SacDrqAgent`): their parameters are made views of the stacked tensors,
so they act, write their actor files and their agent states exactly as separate runs do (after
:meth:`StackedAgents.sync_members`, which copies the stacked optimiser states back into theirs).
The arithmetic of each learner's update is written once, in the learner's module, as functions of
a ``nets`` callable (:func:`egosearch.rl.sac_drq.drq_critic_loss`, :func:`egosearch.rl.sac_curl.curl_target`...):
the learner's plain update calls them on its own modules (:class:`egosearch.rl.common.ModuleNets`),
this module vmaps them over the stacked parameters (:class:`Nets`). What is left here is the order of
the steps, the stacked optimisers and the draws.

What is stacked: SAC + CURL's fast update (not ``share_encoder_forward``, not ``compile``) and
SAC-DrQ's update (its privileged critic, n-step discounts, critic warm-up and behaviour-cloning term
included; not the reconstruction decoder). Imitation before RL, acting and evaluation run per seed.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import random
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial
from typing import Any, ClassVar

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn
from torch.func import functional_call, vmap

from egosearch.rl.common import METRIC_KEYS, crop_at, submodule
from egosearch.rl.cuda_graph import GraphedUpdate
from egosearch.rl.learner_registry import learner, stacked_algorithms
from egosearch.rl.network_settings import NetworkSettings, SacSettings
from egosearch.rl.run_settings import RunSettings
from egosearch.rl.sac_curl import (
    SacCurlAgent,
    crop_offsets,
    curl_actor_loss,
    curl_contrastive_loss,
    curl_critic_loss,
    curl_features,
    curl_key,
    curl_target,
)
from egosearch.rl.sac_drq import SacDrqAgent, drq_actor_loss, drq_critic_loss, drq_inputs, drq_target


class StackingError(ValueError):
    """The agents cannot be stacked (different learners or architectures, an option not stacked)."""


# ---- each seed's random numbers ------------------------------------------------------------

@dataclass
class SeedState:
    """One seed's generator states, as a separate run's process would hold them."""

    torch_cpu: torch.Tensor
    """torch's CPU generator (weights' init, the CPU's crops and noise)."""
    torch_cuda: torch.Tensor | None
    """torch's CUDA generator of the device (crops and noise on a GPU); None on a CPU."""
    numpy_state: tuple
    """numpy's global generator (``np.random.get_state()``)."""
    python_state: tuple
    """python's ``random`` (``random.getstate()``)."""


class SeedStreams:
    """Every seed's own random-number streams in one process: the global generators (torch's CPU and
    CUDA ones, numpy's, python's) are swapped to seed ``k``'s state for everything seed ``k`` draws
    (:meth:`stream`), so each seed consumes the same numbers in the same order as its separate run."""

    def __init__(self, device: torch.device):
        self.device = torch.device(device)
        self.states: list[SeedState] = []

    def _now(self) -> SeedState:
        cuda = torch.cuda.get_rng_state(self.device) if self.device.type == "cuda" else None
        return SeedState(torch.get_rng_state(), cuda, np.random.get_state(), random.getstate())

    def _set(self, state: SeedState) -> None:
        torch.set_rng_state(state.torch_cpu)
        if state.torch_cuda is not None:
            torch.cuda.set_rng_state(state.torch_cuda, self.device)
        np.random.set_state(state.numpy_state)
        random.setstate(state.python_state)

    def capture(self) -> int:
        """Store the generators' present state as the next seed's stream; returns its index."""
        self.states.append(self._now())
        return len(self.states) - 1

    @contextlib.contextmanager
    def stream(self, k: int) -> Iterator[None]:
        """Draw from seed ``k``'s stream inside the block; the process's own state is put back after."""
        outside = self._now()
        self._set(self.states[k])
        try:
            yield
        finally:
            self.states[k] = self._now()
            self._set(outside)


# ---- what can be stacked ------------------------------------------------------------------

def check_stackable(cfg: Any) -> None:
    """Raise :class:`StackingError` (one line) for a learner config whose update is not stacked (the learner
    registry's ``stacked`` entries: the SAC learners without memory); the stacked training asks before it
    writes anything."""
    stackable = stacked_algorithms()
    if cfg.algorithm not in stackable:
        raise StackingError(f"algorithm {cfg.algorithm} is not stacked; stacked: {', '.join(stackable)}")
    kind = STACKED.get(learner(cfg.algorithm).agent_factory())
    if kind is None:
        raise StackingError(f"algorithm {cfg.algorithm} is registered as stacked but has no stacked update here")
    refusal = kind.refusal(cfg)
    if refusal:
        raise StackingError(refusal)


def update_fields(cfg: Any) -> list[dataclasses.Field]:
    """The fields of a learner config that its update may read: all but the run settings (the training loop's:
    steps, envs, evaluation, checkpoints) and the algorithm's name."""
    run = {f.name for f in dataclasses.fields(RunSettings)}
    return [f for f in dataclasses.fields(cfg) if f.name not in run and f.name != "algorithm"]


NETWORK_FIELDS = frozenset(f.name for f in dataclasses.fields(NetworkSettings))
SAC_FIELDS = frozenset(f.name for f in dataclasses.fields(SacSettings))


# ---- stacked parameters -------------------------------------------------------------------

@dataclass(frozen=True)
class StackedParts:
    """What of a learner is stacked: its networks and its loose tensors, by attribute name."""

    modules: tuple[str, ...]
    """The agent's ``nn.Module`` attributes (their parameters are stacked, names ``module.param``)."""
    tensors: tuple[str, ...]
    """The agent's tensor attributes that are parameters too (the temperature, CURL's W)."""


def member_tensors(agent: Any, parts: StackedParts) -> dict[str, torch.Tensor]:
    """An agent's parameters by stacked name (``critic.q1.0.weight``, ``log_alpha``...)."""
    named = {f"{m}.{n}": p for m in parts.modules for n, p in getattr(agent, m).named_parameters()}
    named.update({t: getattr(agent, t) for t in parts.tensors})
    return named


class Nets:
    """Seed-level calls of a member's sub-networks on the parameters one vmapped seed sees:
    ``nets("critic.convs", x)`` is ``agent.critic.convs(x)`` with ``params``' tensors."""

    def __init__(self, templates: dict[str, nn.Module], params: dict[str, torch.Tensor]):
        self.templates, self.params = templates, params

    def __call__(self, path: str, *args: torch.Tensor) -> Any:
        prefix = path + "."
        own = {k[len(prefix):]: v for k, v in self.params.items() if k.startswith(prefix)}
        return functional_call(self.templates[path], own, args)

    def tensor(self, name: str) -> torch.Tensor:
        """A loose parameter's slice (CURL's ``W``), as :meth:`egosearch.rl.common.ModuleNets.tensor`."""
        return self.params[name]


class StackedAgents:
    """N agents of one learner and one architecture (seeds of one variant) updated as one stacked
    model. ``update(batches)`` does what ``[agent.update(b) for agent, b in zip(members, batches)]``
    does, each member drawing its random numbers from its own stream of ``streams``.

    A subclass names its ``parts``, the member class it stacks, the sub-network paths its update calls
    (``paths``), draws one seed's random numbers
    (:meth:`draw`) and writes the stacked update (:meth:`update_tensors`)."""

    parts: ClassVar[StackedParts]
    member_type: ClassVar[type]
    paths: ClassVar[tuple[str, ...]]
    draw_keys: ClassVar[tuple[str, ...]]
    """The keys :meth:`draw` returns (always all of them: a recorded update needs fixed inputs)."""
    implemented: ClassVar[frozenset[str]]
    """The learner's config fields (all but the run settings, which the training loop reads) that the stacked
    update does as the learner's own update does. Any other field set away from its default is refused
    (:meth:`refusal`): a field added to the learner's update is not silently dropped by stacked seeds; it joins
    this list once the stacked update does it too (tests/test_rl_stacked.py holds the list to the config)."""

    @classmethod
    def refusal(cls, cfg: Any) -> str | None:
        """Why a config of this learner cannot be stacked (a field the stacked update does not implement, set away
        from its default), or None."""
        for f in update_fields(cfg):
            default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
            value = getattr(cfg, f.name)
            if f.name not in cls.implemented and value != default:
                return (f"{f.name}={value!r}: the stacked {cls.member_type.__name__} update does not implement it "
                        "(egosearch.rl.stacked); train these seeds one by one, without --stack-seeds")
        return None

    def __init__(self, members: list[Any], streams: SeedStreams):
        if len(members) < 1 or len(streams.states) != len(members):
            raise StackingError(f"{len(members)} members and {len(streams.states)} seed streams: one stream per member")
        if any(type(m) is not self.member_type for m in members):
            raise StackingError(f"{type(self).__name__} stacks {self.member_type.__name__} agents only")
        first = members[0]
        if any(m.arch() != first.arch() for m in members):
            raise StackingError("the agents have different architectures")
        if len({m.num_updates for m in members}) != 1:
            raise StackingError("the agents are at different updates")
        check_stackable(first.cfg)
        self.members, self.streams = members, streams
        self.cfg, self.device, self.n = first.cfg, first.device, len(members)
        self.num_updates = first.num_updates
        # the structure vmap calls with each seed's tensors (built before the members' tensors become views)
        self.templates = {path: copy.deepcopy(submodule(first, path)).to("meta") for path in self.paths}
        named = [member_tensors(m, self.parts) for m in members]
        # the stacked leaves, then each member's tensors made views of its slice (so acting, actor files
        # and agent states read the stacked values with no copy)
        self.params: dict[str, torch.Tensor] = {}
        for name, tensor in named[0].items():
            stacked = torch.stack([nt[name].detach() for nt in named]).contiguous()
            self.params[name] = stacked.requires_grad_(tensor.requires_grad)
            for k, nt in enumerate(named):
                nt[name].data = stacked.data[k]
        self.name_of = [{id(t): name for name, t in nt.items()} for nt in named]
        self.optimisers = {key: self._stacked_optimiser(key) for key in first.optimisers}
        self.graphed = self._graphed()

    # ---- set-up --------------------------------------------------------------------------
    def _graphed(self) -> GraphedUpdate | None:
        """The update recorded as CUDA graphs where the members' own would be (their optimisers can be
        recorded); never on a CPU."""
        capturable = all(g.get("capturable", False) for opt in self.optimisers.values() for g in opt.param_groups)
        if self.device.type == "cuda" and self.cfg.cuda_graph and capturable:
            return GraphedUpdate(self.update_tensors)
        return None

    def _stacked_optimiser(self, key: str) -> torch.optim.Optimizer:
        """The members' optimiser ``key`` over the stacked tensors: same class, groups and
        hyper-parameters, its state (a resumed run's) stacked from theirs."""
        opts = [m.optimisers[key] for m in self.members]
        groups = [{**{h: v for h, v in g.items() if h != "params"},
                   "params": [self.params[self.name_of[0][id(p)]] for p in g["params"]]}
                  for g in opts[0].param_groups]
        stacked = type(opts[0])(groups, **opts[0].defaults)
        member_params = [[p for g in opt.param_groups for p in g["params"]] for opt in opts]
        for i, sp in enumerate(p for g in stacked.param_groups for p in g["params"]):
            states = [opt.state.get(params[i]) for opt, params in zip(opts, member_params)]
            if all(s is None for s in states):
                continue
            if any(s is None for s in states) or len({float(s["step"]) for s in states}) != 1:
                raise StackingError(f"the members' {key} optimisers are at different steps")
            stacked.state[sp] = {name: value.clone() if name == "step" else torch.stack([s[name] for s in states])
                                 for name, value in states[0].items()}
        return stacked

    # ---- the members ---------------------------------------------------------------------
    def sync_members(self) -> None:
        """Copy the stacked optimiser states and the update count into the members (their parameters
        are views already): then ``member.state_dict()`` is the agent state a separate run saves."""
        for k, member in enumerate(self.members):
            member.num_updates = self.num_updates
            for key, opt in self.optimisers.items():
                own = member.optimisers[key]
                member_params = [p for g in own.param_groups for p in g["params"]]
                for p, sp in zip(member_params, (p for g in opt.param_groups for p in g["params"])):
                    state = opt.state.get(sp)
                    if state is None:
                        own.state.pop(p, None)
                        continue
                    own.state[p] = {name: value.clone() if name == "step" else value[k].clone()
                                    for name, value in state.items()}

    # ---- updating ------------------------------------------------------------------------
    def draw(self, member: Any, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """One seed's random numbers for the update ``self.num_updates`` (already counted), in the
        order its own ``update`` draws them (a subclass's)."""
        raise NotImplementedError

    def update_tensors(self, inputs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """The stacked update on stacked batches and draws: metrics as (N,) tensors (a subclass's)."""
        raise NotImplementedError

    def update(self, batches: list[dict[str, torch.Tensor]]) -> list[dict[str, float]]:
        """One update of every seed, ``batches[k]`` seed ``k``'s; returns each seed's metrics
        (:data:`METRIC_KEYS`, NaN for a loss not computed), as the members' ``update`` would."""
        if len(batches) != self.n:
            raise ValueError(f"{len(batches)} batches for {self.n} stacked seeds")
        self.num_updates += 1
        draws = []
        for k, (member, batch) in enumerate(zip(self.members, batches)):
            with self.streams.stream(k):
                draws.append(self.draw(member, batch))
        keys = [k for k in batches[0] if torch.is_tensor(batches[0][k])]
        inputs = {key: torch.stack([b[key] for b in batches]) for key in keys}
        inputs.update({key: torch.stack([d[key] for d in draws]) for key in self.draw_keys})
        if self.graphed is not None:
            out = self.graphed(self.step_flags(), inputs)
        else:
            out = self.update_tensors(inputs)
        for member in self.members:
            member.num_updates = self.num_updates
        return self.metrics(out)

    def step_flags(self) -> tuple[bool, ...]:
        """Which optional steps this update takes (a recorded graph per pattern)."""
        return ()

    def metrics(self, out: dict[str, torch.Tensor]) -> list[dict[str, float]]:
        """(N,) tensors -> each seed's metric dict, in one host sync."""
        nan = torch.full((self.n,), float("nan"), device=self.device)
        table = torch.stack([out.get(k, nan).detach().float().reshape(self.n) for k in METRIC_KEYS]).T.tolist()
        return [dict(zip(METRIC_KEYS, row)) for row in table]

    # ---- helpers for the subclasses ------------------------------------------------------------
    def seeds(self, fn: Callable[..., Any], *args: Any, grad: bool = True) -> Any:
        """``fn(nets, *args)`` for every seed at once: vmapped over the stacked parameters and over
        the leading (seed) dimension of ``args``; ``grad`` False runs it without autograd."""
        def one_seed(params: dict[str, torch.Tensor], *seed_args: Any) -> Any:
            return fn(Nets(self.templates, params), *seed_args)

        with torch.set_grad_enabled(grad and torch.is_grad_enabled()):
            return vmap(one_seed)(self.params, *args)

    def opt_params(self, key: str) -> list[torch.Tensor]:
        return [p for g in self.optimisers[key].param_groups for p in g["params"]]

    def step_with(self, key: str, loss: torch.Tensor, params: list[torch.Tensor] | None = None,
                  allow_unused: bool = False) -> None:
        """Optimiser ``key``'s step on the per-seed losses ``loss`` (N,): the gradient of their sum,
        which is each seed's own on its slice. Unused tensors get no gradient (Adam skips them)."""
        params = self.opt_params(key) if params is None else params
        grads = torch.autograd.grad(loss.sum(), params, allow_unused=allow_unused)
        for p, g in zip(params, grads):
            # a batched matmul's weight gradient comes transposed in memory, and the fused Adam reads a
            # gradient's memory as laid out like its parameter's (measured: wrong steps without this)
            p.grad = None if g is None else g.contiguous()
        self.optimisers[key].step()

    def named(self, prefix: str) -> list[torch.Tensor]:
        """The stacked tensors whose names start with ``prefix``, in the members' order."""
        return [t for name, t in self.params.items() if name.startswith(prefix)]

    def alpha_step(self, log_pi: torch.Tensor, target_entropy: float, out: dict[str, torch.Tensor]) -> None:
        """SAC's temperature step (:meth:`egosearch.rl.pooled.SacMixin.actor_and_alpha_step`'s second half)."""
        def alpha_loss(log_alpha: torch.Tensor, lp: torch.Tensor) -> torch.Tensor:
            return (log_alpha.exp() * (-lp - target_entropy).detach()).mean()

        log_alpha = self.params["log_alpha"]
        loss = vmap(alpha_loss)(log_alpha, log_pi)
        log_alpha.grad = torch.autograd.grad(loss.sum(), [log_alpha])[0].contiguous()
        self.optimisers["alpha"].step()
        out["alpha_loss"] = loss


def stack_crop(x: torch.Tensor, oy: torch.Tensor, ox: torch.Tensor, size: int) -> torch.Tensor:
    """Crop stacked frames (N, B, C, H, W) at offsets (N, B): each sample as the member crops it."""
    n, b = x.shape[:2]
    flat = crop_at(x.reshape(n * b, *x.shape[2:]), oy.reshape(-1), ox.reshape(-1), size)
    return flat.reshape(n, b, *flat.shape[1:])


# ---- SAC + CURL ---------------------------------------------------------------------------

class StackedSacCurl(StackedAgents):
    """Seeds of :class:`egosearch.rl.sac_curl.SacCurlAgent` (``impl="fast"``) stacked: its
    ``_update_fast`` with ``share_encoder_forward`` off, step for step, on the same loss functions."""

    parts = StackedParts(("critic", "critic_target", "actor"), ("W", "log_alpha"))
    member_type = SacCurlAgent
    paths = ("critic.convs", "critic.proj", "critic.q1", "critic.q2", "critic_target.convs",
             "critic_target.proj", "critic_target.q1", "critic_target.q2", "actor")
    draw_keys = ("anchor_oy", "anchor_ox", "next_oy", "next_ox", "pos_oy", "pos_ox", "noise_next", "noise_pi")
    implemented = frozenset(NETWORK_FIELDS | SAC_FIELDS | {"crop_size", "encoder_tau", "encoder_beta1",
                                                           "encoder_beta2", "curl_latent", "curl_double_encoder_step",
                                                           "curl_update_freq", "contact_signal", "strided_history"})

    @classmethod
    def refusal(cls, cfg: Any) -> str | None:
        if cfg.compile:
            return "SAC+CURL with compile is not stacked"
        return super().refusal(cfg)  # share_encoder_forward among the fields it does not implement

    def __init__(self, members: list[SacCurlAgent], streams: SeedStreams):
        if any(getattr(m, "impl", "fast") != "fast" for m in members):
            raise StackingError("only SAC+CURL's fast update is stacked (impl='reference' is its oracle)")
        super().__init__(members, streams)
        self.target_entropy = members[0].target_entropy

    def step_flags(self) -> tuple[bool, ...]:
        cfg, step = self.cfg, self.num_updates
        return (step % cfg.curl_update_freq == 0, step % cfg.actor_update_freq == 0,
                step % cfg.critic_target_update_freq == 0)

    def draw(self, member: SacCurlAgent, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        # SacCurlAgent._crops draws the three crops' offsets first, then the update draws the noise
        obs = batch["obs_depth"]
        b, device, cfg = obs.shape[0], obs.device, self.cfg
        (ay, ax), (ny, nx), (py, px) = [crop_offsets(b, cfg.image_size, cfg.crop_size, device) for _ in range(3)]
        shape = (b, member.action_dim)
        noise_next = torch.randn(shape, device=self.device)
        do_actor = self.step_flags()[1]
        noise_pi = torch.randn(shape, device=self.device) if do_actor else torch.zeros(shape, device=self.device)
        return {"anchor_oy": ay, "anchor_ox": ax, "next_oy": ny, "next_ox": nx, "pos_oy": py, "pos_ox": px,
                "noise_next": noise_next, "noise_pi": noise_pi}

    def update_tensors(self, inputs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        cfg = self.cfg
        do_curl, do_actor, do_polyak = self.step_flags()
        early_key = do_curl and not do_polyak  # the key encoder's weights are those of the target pass
        size = cfg.crop_size
        anchor = stack_crop(inputs["obs_depth"], inputs["anchor_oy"], inputs["anchor_ox"], size).float()
        nxt = stack_crop(inputs["next_obs_depth"], inputs["next_oy"], inputs["next_ox"], size).float()
        pos = stack_crop(inputs["obs_depth"], inputs["pos_oy"], inputs["pos_ox"], size).float()
        extra = torch.cat([inputs["mask"], inputs["proprio"]], dim=-1)
        next_extra = torch.cat([inputs["next_mask"], inputs["next_proprio"]], dim=-1)
        alpha = self.params["log_alpha"].detach().exp()
        out: dict[str, torch.Tensor] = {}

        # vmap returns no None: without the early key the target's z_pos is not returned
        def target(nets, *args):
            target_q, z_pos = curl_target(nets, *args, gamma=cfg.gamma, early_key=early_key)
            return (target_q, z_pos) if early_key else (target_q,)

        target_out = self.seeds(target, nxt, pos, next_extra, inputs["reward"], inputs["not_done"],
                                inputs["noise_next"], alpha, grad=False)
        target_q, z_pos = target_out[0], target_out[1] if early_key else None
        critic_loss, out["q_mean"], _, _ = self.seeds(curl_critic_loss, anchor, extra, inputs["action"], target_q)
        self.step_with("critic", critic_loss)
        out["critic_loss"] = critic_loss

        # the anchor's features after the critic step (CURL's order), shared by the actor and CURL
        z_post = None
        if do_curl:
            h_post, z_post = self.seeds(curl_features, anchor)
        elif do_actor:
            h_post = self.seeds(lambda nets, a: nets("critic.convs", a), anchor, grad=False)

        if do_actor:
            actor_loss, log_pi, out["entropy"] = self.seeds(
                partial(curl_actor_loss, z_given=z_post is not None), h_post, h_post if z_post is None else z_post,
                extra, inputs["noise_pi"], alpha)
            self.step_with("actor", actor_loss)
            out["actor_loss"] = actor_loss
            self.alpha_step(log_pi, self.target_entropy, out)

        if do_polyak:
            with torch.no_grad():
                for part, tau in ((("q1.", "q2."), cfg.critic_tau), (("convs.", "proj."), cfg.encoder_tau)):
                    online = [t for p in part for t in self.named("critic." + p)]
                    held = [t for p in part for t in self.named("critic_target." + p)]
                    torch._foreach_lerp_(held, online, tau)

        if do_curl:
            if not early_key:  # the key encoder just moved: CURL uses the new one
                z_pos = self.seeds(curl_key, pos, grad=False)
            curl_loss = self.seeds(curl_contrastive_loss, z_post, z_pos)
            self.step_with("curl", curl_loss)
            out["curl_loss"] = curl_loss
        out["alpha"] = self.params["log_alpha"].detach().exp()
        return out


# ---- SAC-DrQ ------------------------------------------------------------------------------

class StackedSacDrq(StackedAgents):
    """Seeds of :class:`egosearch.rl.sac_drq.SacDrqAgent` stacked: its ``update`` and
    ``finish_update``, step for step, on the same loss functions."""

    parts = StackedParts(("encoder", "critic", "critic_target", "actor"), ("log_alpha",))
    member_type = SacDrqAgent
    paths = ("encoder", "critic", "critic_target", "actor")
    draw_keys = ("obs_oy", "obs_ox", "next_oy", "next_ox", "noise_next", "noise_pi")
    # not encoder_aux_loss / encoder_aux_weight (SAC-AE's decoder) nor map_image (its map readers)
    implemented = frozenset(NETWORK_FIELDS | SAC_FIELDS | {
        "obs_downsample", "encoder_stride2_layers", "aug_pad", "critic_layer_norm", "critic_privileged_state",
        "demo_episodes", "demo_teacher", "bc_updates", "dagger_rounds", "dagger_episodes", "dagger_states",
        "critic_warmup_updates", "demo_batch_fraction", "bc_weight", "bc_decay_steps", "bc_weight_floor",
        "contact_signal", "strided_history"})

    def __init__(self, members: list[SacDrqAgent], streams: SeedStreams):
        super().__init__(members, streams)
        self.target_entropy = members[0].target_entropy
        self.templates["encoder"].channels_last = False  # a layout only; vmap gives it stacked inputs

    def warming_up(self) -> bool:
        return self.num_updates <= self.cfg.critic_warmup_updates

    def actor_due(self) -> bool:
        return self.num_updates % self.cfg.actor_update_freq == 0 and not self.warming_up()

    def draw(self, member: SacDrqAgent, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        # SacDrqAgent.update: random_shift of obs (y then x offsets), of next_obs, then the noise
        b, pad, device = batch["obs_depth"].shape[0], self.cfg.aug_pad, self.device
        offsets = []
        for _ in range(2):
            if pad > 0:
                offsets += [torch.randint(0, 2 * pad + 1, (b,), device=device) for _ in range(2)]
            else:
                offsets += [torch.zeros(b, dtype=torch.long, device=device)] * 2
        shape = (b, member.action_dim)
        noise_next = torch.randn(shape, device=device)
        noise_pi = torch.randn(shape, device=device) if self.actor_due() else torch.zeros(shape, device=device)
        return dict(zip(self.draw_keys, [*offsets, noise_next, noise_pi]))

    def shift(self, x: torch.Tensor, oy: torch.Tensor, ox: torch.Tensor) -> torch.Tensor:
        """:func:`egosearch.rl.sac_drq.random_shift` of stacked frames at the drawn offsets."""
        pad = self.cfg.aug_pad
        if pad <= 0:
            return x
        n, b = x.shape[:2]
        flat = x.reshape(n * b, *x.shape[2:])
        padded = F.pad(flat, (pad, pad, pad, pad), mode="replicate")
        return crop_at(padded, oy.reshape(-1), ox.reshape(-1), flat.shape[-2]).reshape(x.shape)

    def update_tensors(self, inputs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        cfg = self.cfg
        warming_up, do_actor = self.warming_up(), self.actor_due()
        extra, next_extra, critic_extra, next_critic_extra, discount = drq_inputs(
            inputs, self.members[0].state_dim, cfg.gamma)
        obs = self.shift(inputs["obs_depth"].float(), inputs["obs_oy"], inputs["obs_ox"])
        nxt = self.shift(inputs["next_obs_depth"].float(), inputs["next_oy"], inputs["next_ox"])
        alpha = self.params["log_alpha"].detach().exp()
        out: dict[str, torch.Tensor] = {}

        target_q = self.seeds(drq_target, nxt, next_extra, next_critic_extra, inputs["reward"], inputs["not_done"],
                              discount, inputs["noise_next"], alpha, grad=False)
        critic_loss, out["q_mean"], h = self.seeds(partial(drq_critic_loss, warming_up=warming_up), obs,
                                                   critic_extra, inputs["action"], target_q)
        self.step_with("critic", critic_loss, allow_unused=warming_up)
        out["critic_loss"] = critic_loss

        if do_actor:
            bc_weight = self.members[0].bc_weight_now if "demo" in inputs else 0.0
            demo = inputs["demo"] if bc_weight > 0 else torch.zeros_like(inputs["reward"])
            total, out["actor_loss"], log_pi, out["entropy"], bc_loss = self.seeds(
                partial(drq_actor_loss, bc_weight=bc_weight), h, extra, critic_extra, inputs["action"], demo,
                inputs["noise_pi"], alpha)
            if bc_weight > 0:
                out["bc_loss"] = bc_loss
            self.step_with("actor", total)
            self.alpha_step(log_pi, self.target_entropy, out)

        if self.num_updates % cfg.critic_target_update_freq == 0:
            with torch.no_grad():
                torch._foreach_lerp_(self.named("critic_target."), self.named("critic."), cfg.critic_tau)
        out["alpha"] = self.params["log_alpha"].detach().exp()
        return out


STACKED: dict[type, type[StackedAgents]] = {SacCurlAgent: StackedSacCurl, SacDrqAgent: StackedSacDrq}
"""The learners whose seeds can be stacked, by agent class."""


def stack_agents(members: list[Any], streams: SeedStreams) -> StackedAgents:
    """The stacked form of ``members`` (one learner's agents, one per stream of ``streams``)."""
    kind = STACKED.get(type(members[0])) if members else None
    if kind is None:
        names = ", ".join(t.__name__ for t in STACKED)
        raise StackingError(f"cannot stack {type(members[0]).__name__ if members else 'no'} agents; stacked: {names}")
    return kind(members, streams)
