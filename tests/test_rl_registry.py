"""The learner registry and the Agent protocol: every registered learner is an Agent, and a learner
registered from outside egosearch (a toy defined here) trains through the real training loop."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.rl.actor import AgentPolicy, load_any_actor_net
from egosearch.rl.agent import Agent, AgentBase
from egosearch.rl.common import METRIC_KEYS, AgentStateError
from egosearch.rl.config import load_config
from egosearch.rl.registry import ALGORITHMS, LEARNERS, actor_loader, learner, make_agent, register
from egosearch.rl.train import train

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

register_fake_envs()

TOY_AGENT_FORMAT, TOY_ACTOR_FORMAT = "toy-agent-v1", "toy-actor-v1"


class ToyActorNet(torch.nn.Module):
    """A linear policy on [mask, proprio] (it ignores depth)."""

    def __init__(self, in_dim: int, action_dim: int):
        super().__init__()
        self.fc = torch.nn.Linear(in_dim, action_dim)

    def forward(self, extra: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.fc(extra))


def load_toy_actor_net(state: dict, device) -> ToyActorNet:
    net = ToyActorNet(state["arch"]["in_dim"], state["arch"]["action_dim"])
    net.load_state_dict(state["state_dict"])
    return net.to(device).eval()


class ToyAgent(AgentBase):
    """Behaviour cloning of the replay's own actions: the smallest learner the loop can drive."""

    def __init__(self, cfg, action_dim: int, mask_dim: int, proprio_dim: int, device=None, state_dim: int = 0):
        self.cfg = cfg.validate()
        self.arch = {"in_dim": mask_dim + proprio_dim, "action_dim": action_dim}
        self.net = ToyActorNet(mask_dim + proprio_dim, action_dim)
        self.opt = torch.optim.SGD(self.net.parameters(), lr=0.01)
        self.num_updates = 0
        self.batch_sizes: list[int] = []

    @property
    def alpha(self) -> float:
        return 0.0

    def act(self, obs: dict, deterministic: bool = False) -> np.ndarray:
        extra = torch.as_tensor(np.concatenate([obs["mask"], obs["proprio"]]), dtype=torch.float32)
        with torch.no_grad():
            a = self.net(extra)
            if not deterministic:
                a = (a + 0.3 * torch.randn_like(a)).clamp(-1.0, 1.0)
        return a.numpy()

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        self.num_updates += 1
        self.batch_sizes.append(int(batch["action"].shape[0]))
        loss = (self.net(torch.cat([batch["mask"], batch["proprio"]], -1)) - batch["action"]).pow(2).mean()
        self.opt.zero_grad()
        loss.backward()
        self.opt.step()
        return {**dict.fromkeys(METRIC_KEYS, float("nan")), "critic_loss": float(loss.detach()), "alpha": 0.0}

    def state_dict(self) -> dict:
        return {"format": TOY_AGENT_FORMAT, "net": self.net.state_dict(), "opt": self.opt.state_dict(),
                "num_updates": self.num_updates}

    def load_state_dict(self, state: dict) -> None:
        if state.get("format") != TOY_AGENT_FORMAT:
            raise AgentStateError("not a toy agent state")
        self.net.load_state_dict(state["net"])
        self.opt.load_state_dict(state["opt"])
        self.num_updates = int(state["num_updates"])

    def actor_state(self, metadata: dict | None = None) -> dict:
        weights = {k: v.detach().clone() for k, v in self.net.state_dict().items()}
        return {"format": TOY_ACTOR_FORMAT, "arch": dict(self.arch), "state_dict": weights,
                "metadata": dict(metadata or {})}


@pytest.fixture
def toy_learner():
    """``toy`` registered for the test only (the registry is a module global)."""
    assert "toy" not in LEARNERS
    with pytest.raises(ValueError, match="algorithm"):
        load_config("smoke", {"algorithm": "toy"})  # not a learner before it is registered
    created: list[ToyAgent] = []

    def factory(*args, **kwargs) -> ToyAgent:
        created.append(ToyAgent(*args, **kwargs))
        return created[-1]

    entry = register("toy", "toy BC", factory, {TOY_ACTOR_FORMAT: load_toy_actor_net})
    try:
        yield entry, created
    finally:
        del LEARNERS["toy"]


def test_a_registered_learner_trains_through_the_real_loop(toy_learner, tmp_path):
    entry, created = toy_learner
    assert learner("toy") is entry and "toy" in ALGORITHMS
    cfg = load_config("smoke", {"algorithm": "toy", "device": "cpu", "num_threads": 1, "num_envs": 2,
                                "total_env_steps": 120, "init_steps": 20, "eval_every": 60, "checkpoint_every": 60,
                                "log_every": 20, "eval_episodes": 1, "batch_size": 16, "replay_capacity": 200})
    summary = train(FAKE_ENV_ID, cfg, tmp_path, progress=False)

    agent = created[0]
    assert len(created) == 1 and isinstance(agent, Agent)
    assert agent.num_updates > 0 and summary["updates"] == agent.num_updates
    assert set(agent.batch_sizes) == {16}  # AgentBase.sample_batch: batch_size transitions
    for name in ("curve.csv", "train.csv", "actor.pt", "done.json", "config.json"):
        assert (tmp_path / name).is_file(), name
    assert json.loads((tmp_path / "done.json").read_text())["env_steps"] == 120
    assert len((tmp_path / "curve.csv").read_text().splitlines()) == 1 + 3  # header + steps 0, 60, 120

    # the actor file's format is the registry's: the generic loader finds the toy's network
    state = torch.load(tmp_path / "actor.pt", weights_only=True)
    assert state["format"] == TOY_ACTOR_FORMAT and state["metadata"]["env_id"] == FAKE_ENV_ID
    net = load_any_actor_net(state, "cpu")
    assert isinstance(net, ToyActorNet)
    extra = torch.randn(3, state["arch"]["in_dim"])
    assert torch.equal(net(extra), agent.net(extra).detach())


def test_register_refuses_a_taken_name_and_a_format_loaded_differently(toy_learner):
    with pytest.raises(ValueError, match="registered already"):
        register("toy", "again", ToyAgent)
    with pytest.raises(ValueError, match="loaded differently"):
        register("toy2", "toy 2", ToyAgent, {TOY_ACTOR_FORMAT: "somewhere:else"})
    assert "toy2" not in LEARNERS
    with pytest.raises(AgentStateError, match="not an actor file"):
        load_any_actor_net({"format": "no-such-actor-v1"}, "cpu")
    assert actor_loader("no-such-actor-v1") is None


# overrides that make the smoke profile valid for each built-in learner
LEARNER_OVERRIDES = {
    "sac_curl": {},
    "sac_drq": {"obs_downsample": 4, "encoder_stride2_layers": 2},
    "sac_drq_recurrent": {"obs_downsample": 4, "encoder_stride2_layers": 2, "recurrent_hidden_dim": 8,
                          "sequence_length": 2, "burn_in": 1},
    "ppo": {"obs_downsample": 4, "encoder_stride2_layers": 2, "init_steps": 0, "update_every": 32,
            "replay_capacity": 64},
}


@pytest.mark.parametrize("name", list(LEARNERS))
def test_every_registered_learner_is_an_agent_and_writes_a_registered_actor_format(name):
    assert name in LEARNER_OVERRIDES, f"add smoke overrides for the learner {name!r} here"
    cfg = load_config("smoke", {"algorithm": name, "device": "cpu", **LEARNER_OVERRIDES[name]})
    torch.manual_seed(0)
    agent = make_agent(cfg, 5, 30, 4, torch.device("cpu"))
    assert isinstance(agent, Agent) and isinstance(agent, AgentBase)
    assert isinstance(agent, LEARNERS[name].agent_factory())
    assert agent.num_updates == 0 and agent.alpha > 0
    assert agent.recurrent == (name == "sac_drq_recurrent")

    actor = agent.actor_state({"variant": "x"})
    assert actor["format"] in LEARNERS[name].actor_formats
    net = load_any_actor_net(actor, "cpu")
    assert type(net) is type(actor_loader(actor["format"])(actor, "cpu"))

    # the optional hooks every agent has (AgentBase's defaults or the learner's own)
    rng = np.random.default_rng(0)
    obs = {"depth": rng.integers(0, 256, (5, 100, 100), dtype=np.uint8), "mask": np.zeros(30, np.float32),
           "proprio": np.zeros(4, np.float32)}
    stored = agent.replay_obs(obs)
    assert stored["depth"].shape[-1] == agent.replay_image_size
    assert agent.act_batch({k: np.stack([v, v]) for k, v in obs.items()}, deterministic=True).shape == (2, 5)
    assert agent.act(obs, deterministic=True).shape == (5,)
    agent.reset_state(0)
    AgentPolicy(agent).reset(seed=0)
    assert set(agent.state_dict()) >= {"format", "num_updates"}
