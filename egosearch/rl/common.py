"""The lowest-level pieces every learner (SAC + CURL, SAC-DrQ, recurrent SAC-DrQ, PPO) builds from:
devices, layers, the actor head and its tanh-Gaussian sample, the crops, observation -> tensors,
the metric dict an ``update`` returns, agent-state checks and the actor files' weights.

What the pooled-depth learners share above these (their encoder and actor, SAC's set-up and steps)
is in :mod:`egosearch.rl.pooled`; the interface the training loop drives is
:class:`egosearch.rl.learner.Agent`. A learner module keeps only what makes it that learner (its
critic, losses and update).
The module and attribute names below are part of every checkpoint's and actor file's state_dict
keys (``head.proj.fc.weight``, ``head.trunk.0.bias``...): renaming one breaks stored runs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

METRIC_KEYS = ("critic_loss", "actor_loss", "alpha", "alpha_loss", "curl_loss", "aux_loss", "bc_loss", "entropy",
               "q_mean")
"""What every learner's ``update`` returns (NaN for a loss not computed that update)."""
LOG_2PI = math.log(2.0 * math.pi)


class AgentStateError(ValueError):
    """A saved agent / actor does not match (format, variant, architecture) or is unreadable."""


def check_agent_state(state: Any, fmt: str, kind: str, arch: dict[str, Any]) -> None:
    """Raise :class:`AgentStateError` unless ``state`` is a ``kind`` agent state (format ``fmt``)
    of the same architecture ``arch``: what every learner's ``load_state_dict`` checks first."""
    if not isinstance(state, dict) or state.get("format") != fmt:
        raise AgentStateError(f"not a {kind} agent state "
                              f"(format={state.get('format') if isinstance(state, dict) else None!r})")
    # both ways: a key only one side records (an option off by default) differs too
    diff = sorted(k for k in set(arch) | set(state["arch"]) if state["arch"].get(k) != arch.get(k))
    if diff:
        raise AgentStateError("agent state has a different architecture: " + ", ".join(diff))


def resolve_device(name: str = "auto") -> torch.device:
    """"auto" -> CUDA when available, else CPU."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def adam(params, lr: float, betas: tuple[float, float], capturable: bool = False) -> torch.optim.Adam:
    """Fused Adam where the device and dtype allow it (one kernel for every tensor), else foreach;
    ``capturable`` keeps its step counter on the device, so that a CUDA graph can record its step."""
    params = list(params)
    try:
        return torch.optim.Adam(params, lr=lr, betas=betas, fused=True, capturable=capturable)
    except (RuntimeError, ValueError):
        return torch.optim.Adam(params, lr=lr, betas=betas, foreach=True, capturable=capturable)


def activation(name: str) -> nn.Module:
    return {"relu": nn.ReLU, "elu": nn.ELU, "leaky_relu": nn.LeakyReLU, "gelu": nn.GELU,
            "tanh": nn.Tanh}[name]()


def weight_init(m: nn.Module) -> None:
    """CURL's init: orthogonal Linear weights, delta-orthogonal convs, zero biases."""
    if isinstance(m, nn.Linear):
        nn.init.orthogonal_(m.weight.data)
        m.bias.data.fill_(0.0)
    elif isinstance(m, nn.Conv2d):
        m.weight.data.fill_(0.0)
        m.bias.data.fill_(0.0)
        mid = m.weight.size(2) // 2
        nn.init.orthogonal_(m.weight.data[:, :, mid, mid], nn.init.calculate_gain("relu"))


def mlp(in_dim: int, hidden_dim: int, out_dim: int, num_layers: int, act: str,
        layer_norm: bool = False) -> nn.Sequential:
    """``num_layers`` Linear layers (the last one is the output layer), ``act`` between; with
    ``layer_norm`` a LayerNorm before each of those activations (RLPD's critic)."""
    dims = [in_dim] + [hidden_dim] * (num_layers - 1) + [out_dim]
    layers: list[nn.Module] = []
    for i in range(num_layers):
        layers.append(nn.Linear(dims[i], dims[i + 1]))
        if i < num_layers - 1:
            if layer_norm:
                layers.append(nn.LayerNorm(dims[i + 1]))
            layers.append(activation(act))
    return nn.Sequential(*layers)


# ---- crops --------------------------------------------------------------------------------

def crop_at(x: torch.Tensor, oy: torch.Tensor, ox: torch.Tensor, size: int) -> torch.Tensor:
    """Crop (B, C, H, W) at per-sample offsets (uint8 or float, any device): one strided copy
    per sample on the CPU (~4x faster there than a gather), one gather on accelerators (no
    host sync)."""
    if x.device.type == "cpu":
        return crop_loop(x, oy, ox, size)
    return crop_gather(x, oy, ox, size)


def crop_loop(x: torch.Tensor, oy: torch.Tensor, ox: torch.Tensor, size: int) -> torch.Tensor:
    ys, xs = oy.tolist(), ox.tolist()
    return torch.stack([x[i, :, y:y + size, xx:xx + size] for i, (y, xx) in enumerate(zip(ys, xs))])


def crop_gather(x: torch.Tensor, oy: torch.Tensor, ox: torch.Tensor, size: int) -> torch.Tensor:
    windows = x.unfold(2, size, 1).unfold(3, size, 1)  # (B, C, H-size+1, W-size+1, size, size) view
    return windows[torch.arange(x.shape[0], device=x.device), :, oy, ox]


def center_crop(x: torch.Tensor, size: int) -> torch.Tensor:
    """CURL's centre crop: top = (H - size) // 2, left = (W - size) // 2."""
    top, left = (x.shape[-2] - size) // 2, (x.shape[-1] - size) // 2
    return x[..., top:top + size, left:left + size]


def obs_to_tensors(obs: dict, device: torch.device, crop_size: int) -> tuple[torch.Tensor, torch.Tensor]:
    """One env observation (or a batch of them) -> (centre-cropped uint8 depth (B, K, S, S),
    [mask, proprio] float (B, D)) on ``device``."""
    depth = torch.as_tensor(np.asarray(obs["depth"]))
    mask = torch.as_tensor(np.asarray(obs["mask"], np.float32))
    proprio = torch.as_tensor(np.asarray(obs["proprio"], np.float32))
    if depth.ndim == 3:
        depth, mask, proprio = depth[None], mask[None], proprio[None]
    depth = center_crop(depth, crop_size).to(device)
    return depth, torch.cat([mask, proprio], dim=-1).to(device)


# ---- the actor ----------------------------------------------------------------------------

class Projection(nn.Module):
    """Linear + LayerNorm (+ tanh if ``tanh``) after the convs: the 128-d embedding."""

    def __init__(self, in_dim: int, latent_dim: int, tanh: bool):
        super().__init__()
        self.fc = nn.Linear(in_dim, latent_dim)
        self.ln = nn.LayerNorm(latent_dim)
        self.tanh = tanh

    def forward(self, h: torch.Tensor) -> torch.Tensor:
        z = self.ln(self.fc(h))
        return torch.tanh(z) if self.tanh else z


class MapReader(nn.Module):
    """An image inside the observation's extra values (an image option's, ``map_image``), read by small convs:
    ``(B, D) -> (B, D - C*H*W + out_dim)``, the image's values replaced by its features. Two 3x3 stride-2 convs and
    a projection with LayerNorm and tanh, as the depth encoder's."""

    def __init__(self, start: int, shape: tuple[int, int, int], filters: int = 16, out_dim: int = 64,
                 act: str = "relu"):
        super().__init__()
        self.start, self.shape = int(start), tuple(int(v) for v in shape)
        channels, side = self.shape[0], self.shape[1]
        self.convs = nn.ModuleList([nn.Conv2d(channels, filters, 3, stride=2),
                                    nn.Conv2d(filters, 2 * filters, 3, stride=2)])
        for _ in range(2):
            side = (side - 3) // 2 + 1
        self.fc = nn.Linear(2 * filters * side * side, out_dim)
        self.ln = nn.LayerNorm(out_dim)
        self.act = activation(act)
        self.size, self.out_dim = channels * self.shape[1] * self.shape[2], int(out_dim)

    def extra_dim(self, extra_dim: int) -> int:
        """The size of what :meth:`forward` gives for ``extra_dim`` values in."""
        return extra_dim - self.size + self.out_dim

    def forward(self, extra: torch.Tensor) -> torch.Tensor:
        end = self.start + self.size
        x = extra[..., self.start:end].reshape(-1, *self.shape)
        for conv in self.convs:
            x = self.act(conv(x))
        features = torch.tanh(self.ln(self.fc(x.flatten(1)))).reshape(*extra.shape[:-1], self.out_dim)
        return torch.cat([extra[..., :self.start], extra[..., end:], features], dim=-1)


def map_reader(arch: dict[str, Any]) -> MapReader | None:
    """The :class:`MapReader` an arch dict asks for (``map_image``: the image's shape, ``map_offset``: where its
    values start in the extra values), or None."""
    if "map_image" not in arch:
        return None
    return MapReader(arch["map_offset"], tuple(arch["map_image"]))


class ActorHead(nn.Module):
    """Actor on conv features: own projection, concat [mask, proprio], MLP -> (mu, log_std). With a ``map_reader``
    (an image inside mask) the image's values are replaced by its features first."""

    def __init__(self, conv_dim: int, latent_dim: int, extra_dim: int, action_dim: int,
                 hidden_dim: int, num_layers: int, act: str, log_std_min: float,
                 log_std_max: float, tanh: bool, map_reader: MapReader | None = None):
        super().__init__()
        self.proj = Projection(conv_dim, latent_dim, tanh)
        if map_reader is not None:  # a submodule only then: actor files without a map keep their keys
            self.map_reader = map_reader
            extra_dim = map_reader.extra_dim(extra_dim)
        self.trunk = mlp(latent_dim + extra_dim, hidden_dim, 2 * action_dim, num_layers, act)
        self.log_std_min, self.log_std_max = float(log_std_min), float(log_std_max)

    def forward(self, h: torch.Tensor, extra: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        if hasattr(self, "map_reader"):
            extra = self.map_reader(extra)
        mu, log_std = self.trunk(torch.cat([self.proj(h), extra], dim=-1)).chunk(2, dim=-1)
        log_std = torch.tanh(log_std)
        log_std = self.log_std_min + 0.5 * (self.log_std_max - self.log_std_min) * (log_std + 1)
        return mu, log_std


def actor_head(conv_dim: int, arch: dict[str, Any]) -> ActorHead:
    """The :class:`ActorHead` an arch dict (a learner's ``arch()``) describes."""
    return ActorHead(conv_dim, arch["encoder_latent_dim"], arch["extra_dim"], arch["action_dim"],
                     arch["actor_hidden_dim"], arch["actor_num_layers"], arch["actor_activation"],
                     arch["actor_log_std_min"], arch["actor_log_std_max"], arch["encoder_tanh"], map_reader(arch))


# ---- the networks an update's arithmetic calls ------------------------------------------------

def submodule(owner: Any, path: str) -> nn.Module:
    """``owner.critic.convs`` for ``"critic.convs"`` (agents are not modules themselves)."""
    obj = owner
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


class ModuleNets:
    """A learner's own networks, called by path: ``nets("critic", h, extra, a)`` is ``agent.critic(h, extra, a)``.

    A learner writes its update's arithmetic once, as functions of such a ``nets``: its plain update passes
    this, the stacked update of several seeds (:mod:`egosearch.rl.stacked`) passes each seed's slice of the
    stacked parameters under ``torch.func.vmap``, so that the two cannot compute different things."""

    def __init__(self, owner: Any):
        self.owner = owner

    def __call__(self, path: str, *args: torch.Tensor) -> Any:
        return submodule(self.owner, path)(*args)

    def tensor(self, name: str) -> torch.Tensor:
        """A loose parameter of the learner (CURL's ``W``), by attribute name."""
        return getattr(self.owner, name)


def squashed_sample(mu: torch.Tensor, log_std: torch.Tensor, noise: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """CURL's reparameterised tanh-Gaussian sample: (tanh(mu + std * noise), log pi)."""
    pi = mu + noise * log_std.exp()
    log_pi = (-0.5 * noise.pow(2) - log_std).sum(-1, keepdim=True) - 0.5 * LOG_2PI * noise.size(-1)
    pi = torch.tanh(pi)
    log_pi = log_pi - torch.log(F.relu(1 - pi.pow(2)) + 1e-6).sum(-1, keepdim=True)
    return pi, log_pi


def gaussian_entropy(log_std: torch.Tensor) -> torch.Tensor:
    """Mean entropy (nats) of the diagonal Gaussian before the tanh: the logged ``entropy``."""
    return (0.5 * log_std.shape[1] * (1.0 + LOG_2PI) + log_std.sum(dim=-1)).mean()


def metric_values(out: dict[str, torch.Tensor], device: torch.device) -> dict[str, float]:
    """An update's tensors -> :data:`METRIC_KEYS` floats, NaN where absent, in ONE host sync."""
    nan = torch.tensor(float("nan"), device=device)
    values = torch.stack([out.get(k, nan).detach().float().reshape(()) for k in METRIC_KEYS]).tolist()
    return dict(zip(METRIC_KEYS, values))


# ---- actor files --------------------------------------------------------------------------

def actor_weights(parts: dict[str, nn.Module], storage_dtype: torch.dtype) -> dict[str, torch.Tensor]:
    """``{prefix: module}`` -> ``{prefix.key: CPU tensor}`` with floating weights as ``storage_dtype``
    (float16 keeps a committed actor small; :func:`load_actor_weights` rounds through it anyway)."""
    weights = {f"{prefix}.{k}": v for prefix, module in parts.items() for k, v in module.state_dict().items()}
    return {k: v.detach().to("cpu", dtype=storage_dtype if v.is_floating_point() else v.dtype,
                             memory_format=torch.contiguous_format).clone()
            for k, v in weights.items()}


def load_actor_weights(net: nn.Module, state: dict[str, Any], device: str | torch.device) -> nn.Module:
    """Load an actor file's ``state_dict`` into ``net`` and put it in eval mode on ``device``."""
    # The stored policy is the float16 actor: weights saved in float32 (older files) are rounded
    # the same way, so an actor file's actions do not depend on how it was stored.
    weights = {k: v.to(torch.float16) if v.is_floating_point() else v for k, v in state["state_dict"].items()}
    try:
        net.load_state_dict(weights)
    except RuntimeError as err:
        raise AgentStateError(f"actor weights do not match their arch: {str(err).splitlines()[0]}") from None
    return net.to(device).eval()
