"""A toy learner (the extension test's, tests/test_extending.py): behaviour cloning of the replay's own actions
by a linear policy on [mask, proprio]. Copied to egosearch/rl/toy_bc.py in a temporary copy of the repository."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from egosearch.rl.common import METRIC_KEYS, AgentStateError
from egosearch.rl.learner import AgentBase

AGENT_FORMAT, ACTOR_FORMAT = "toy-bc-agent-v1", "toy-bc-actor-v1"


@dataclass
class ToyBcSettings:
    """The toy learner's own settings."""

    toy_bc_lr: float = 0.01
    """Ours (a toy of the extension test): the SGD step of the linear policy."""

    def own_checks(self, bad) -> None:
        if not self.toy_bc_lr > 0:
            bad("toy_bc_lr", "> 0")


class ToyActorNet(torch.nn.Module):
    """``(depth, extra) -> (mean before the tanh, None)``, as an actor file's network is called."""

    def __init__(self, extra_dim: int, action_dim: int):
        super().__init__()
        self.fc = torch.nn.Linear(extra_dim, action_dim)

    def forward(self, depth: torch.Tensor | None, extra: torch.Tensor) -> tuple[torch.Tensor, None]:
        return self.fc(extra), None


def load_actor_net(state: dict, device) -> ToyActorNet:
    net = ToyActorNet(state["arch"]["extra_dim"], state["arch"]["action_dim"])
    net.load_state_dict(state["state_dict"])
    return net.to(device).eval()


class ToyBcAgent(AgentBase):
    """The smallest learner the training loop can drive (tests/test_rl_registry.py's toy is one too)."""

    agent_format, actor_format = AGENT_FORMAT, ACTOR_FORMAT

    def __init__(self, cfg, action_dim: int, mask_dim: int, proprio_dim: int, device=None, state_dim: int = 0):
        self.cfg = cfg.validate()
        # an ActorArch's sizes and nothing else: no crop_size, so a policy hands it whole frames
        self.arch = {"action_dim": action_dim, "extra_dim": mask_dim + proprio_dim}
        self.net = ToyActorNet(mask_dim + proprio_dim, action_dim)
        self.opt = torch.optim.SGD(self.net.parameters(), lr=self.learning_rate())
        self.num_updates = 0

    def learning_rate(self) -> float:
        return self.cfg.toy_bc_lr

    @property
    def alpha(self) -> float:
        return 0.0

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        extra = torch.as_tensor(np.concatenate([obs["mask"], obs["proprio"]]), dtype=torch.float32)
        with torch.no_grad():
            a = torch.tanh(self.net(None, extra)[0])
            if not deterministic:
                a = (a + 0.3 * torch.randn_like(a)).clamp(-1.0, 1.0)
        return a.numpy()

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        self.num_updates += 1
        mean, _ = self.net(None, torch.cat([batch["mask"], batch["proprio"]], -1))
        loss = (torch.tanh(mean) - batch["action"]).pow(2).mean()
        self.opt.zero_grad()
        loss.backward()
        self.opt.step()
        return {**dict.fromkeys(METRIC_KEYS, float("nan")), "critic_loss": float(loss.detach()), "alpha": 0.0}

    def state_dict(self) -> dict:
        return {"format": self.agent_format, "net": self.net.state_dict(), "opt": self.opt.state_dict(),
                "num_updates": self.num_updates}

    def load_state_dict(self, state: dict) -> None:
        if state.get("format") != self.agent_format:
            raise AgentStateError(f"not a {self.agent_format} agent state")
        self.net.load_state_dict(state["net"])
        self.opt.load_state_dict(state["opt"])
        self.num_updates = int(state["num_updates"])

    def actor_state(self, metadata: dict | None = None) -> dict:
        weights = {k: v.detach().clone() for k, v in self.net.state_dict().items()}
        return {"format": self.actor_format, "arch": dict(self.arch), "state_dict": weights,
                "metadata": dict(metadata or {})}
