"""The learner registry and the Agent protocol: every registered learner is an Agent, and a learner
registered from outside egosearch (a toy defined here) trains through the real training loop and its
actor file acts through ActorPolicy, as every written contract (egosearch.rl.learner) says it will."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.rl.actor import ActorPolicy, AgentPolicy, load_any_actor_net
from egosearch.rl.common import AgentStateError
from egosearch.rl.config import load_config
from egosearch.rl.learner import ActorFileNet, Agent, AgentBase
from egosearch.rl.learner_registry import ALGORITHMS, LEARNERS, actor_loader, learner, make_agent, register
from egosearch.rl.train import train
from egosearch.rl.training_aids import DemonstrationSettings

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, register_fake_envs  # noqa: E402

sys.path.insert(0, str(TESTS / "extensions"))
from toy_bc import ToyActorNet, ToyBcAgent, load_actor_net  # noqa: E402

register_fake_envs()

TOY_AGENT_FORMAT, TOY_ACTOR_FORMAT = "toy-agent-v1", "toy-actor-v1"


def load_toy_actor_net(state: dict, device) -> ToyActorNet:
    return load_actor_net(state, device)


class ToyAgent(ToyBcAgent):
    """Behaviour cloning of the replay's own actions (the extension test's toy learner, under this test's own
    formats and name), counting the batches it is given."""

    agent_format, actor_format = TOY_AGENT_FORMAT, TOY_ACTOR_FORMAT

    def __init__(self, *args, **kwargs):
        self.batch_sizes: list[int] = []
        super().__init__(*args, **kwargs)

    def learning_rate(self) -> float:
        return 0.01  # registered without settings of its own

    def update(self, batch: dict[str, torch.Tensor]) -> dict[str, float]:
        self.batch_sizes.append(int(batch["action"].shape[0]))
        return super().update(batch)


TOY = "registry_test_toy"
"""The test's own learner's name: a user's learner may well be called "toy"."""


@pytest.fixture
def toy_learner():
    """The toy learner registered for the test only (the registry is a module global)."""
    assert TOY not in LEARNERS
    with pytest.raises(ValueError, match="algorithm"):
        load_config("smoke", {"algorithm": TOY})  # not a learner before it is registered
    created: list[ToyAgent] = []

    def factory(*args, **kwargs) -> ToyAgent:
        created.append(ToyAgent(*args, **kwargs))
        return created[-1]

    entry = register(TOY, "toy BC", factory, {TOY_ACTOR_FORMAT: load_toy_actor_net})
    try:
        yield entry, created
    finally:
        del LEARNERS[TOY]


def test_a_registered_learner_trains_through_the_real_loop(toy_learner, tmp_path):
    entry, created = toy_learner
    assert learner(TOY) is entry and TOY in ALGORITHMS
    cfg = load_config("smoke", {"algorithm": TOY, "device": "cpu", "num_threads": 1, "num_envs": 2,
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
    assert isinstance(net, ToyActorNet) and isinstance(net, ActorFileNet)
    extra = torch.randn(3, state["arch"]["extra_dim"])
    assert torch.equal(net(None, extra)[0], agent.net(None, extra)[0].detach())

    # and the file acts through ActorPolicy as the trained agent does
    policy = ActorPolicy(tmp_path / "actor.pt", device="cpu")
    assert policy.action_dim == 5 and not policy.recurrent and policy.crop_size == 100
    rng = np.random.default_rng(1)
    for _ in range(3):
        obs = {"depth": rng.integers(0, 256, (5, 100, 100), dtype=np.uint8),
               "mask": rng.normal(size=30).astype(np.float32), "proprio": rng.normal(size=4).astype(np.float32)}
        policy.reset(seed=0)
        np.testing.assert_allclose(policy.act(obs), agent.act(obs, deterministic=True), rtol=0, atol=1e-6)


def test_an_actor_file_that_breaks_the_written_contract_is_one_line(toy_learner, tmp_path):
    cfg = load_config("smoke", {"algorithm": TOY, "device": "cpu"})
    good = make_agent(cfg, 5, 30, 4, torch.device("cpu")).actor_state({"env_id": "EgoSearch-v0"})
    bad_files = {
        "no_extra_dim": ({**good, "arch": {"action_dim": 5}}, "arch has extra_dim=None; it needs an integer >= 1"),
        "a_float_crop": ({**good, "arch": {**good["arch"], "crop_size": 84.0}}, "arch has crop_size=84.0"),
        "other_frames": ({**good, "arch": {**good["arch"], "image_size": 64}},
                         "trained on 64x64 depth frames \\(its arch's image_size\\); the envs render 100x100"),
        "other_config": ({**good, "metadata": {"config": {"image_size": 50}}},
                         "trained on 50x50 depth frames \\(its recorded config's image_size\\)"),
    }
    for name, (state, message) in bad_files.items():
        torch.save(state, tmp_path / f"{name}.pt")
        with pytest.raises(AgentStateError, match=message) as err:
            ActorPolicy(tmp_path / f"{name}.pt")
        assert str(err.value).startswith(str(tmp_path / name)) and "\n" not in str(err.value)
    torch.save(good, tmp_path / "good.pt")
    assert ActorPolicy(tmp_path / "good.pt").fits("EgoSearch-v0")


def test_register_refuses_a_taken_name_and_a_format_loaded_differently(toy_learner):
    with pytest.raises(ValueError, match="registered already"):
        register(TOY, "again", ToyAgent)
    with pytest.raises(ValueError, match="loaded differently"):
        register("toy2", "toy 2", ToyAgent, {TOY_ACTOR_FORMAT: "somewhere:else"})
    assert "toy2" not in LEARNERS
    with pytest.raises(AgentStateError, match="not an actor file"):
        load_any_actor_net({"format": "no-such-actor-v1"}, "cpu")
    assert actor_loader("no-such-actor-v1") is None


# overrides that make the smoke preset valid for each built-in learner
@pytest.mark.parametrize("name", list(LEARNERS))
def test_every_registered_learner_is_an_agent_and_writes_a_registered_actor_format(name):
    cfg = load_config("smoke", {"algorithm": name, "device": "cpu", **LEARNERS[name].smoke_overrides})
    torch.manual_seed(0)
    agent = make_agent(cfg, 5, 30, 4, torch.device("cpu"))
    assert isinstance(agent, Agent) and isinstance(agent, AgentBase)
    assert isinstance(agent, LEARNERS[name].agent_factory())
    # alpha, the entropy term's weight, is only logged: SAC's initial temperature, PPO's coefficient
    assert agent.num_updates == 0 and math.isfinite(agent.alpha) and agent.alpha >= 0
    if hasattr(cfg, "init_temperature"):  # a SAC learner starts at its initial temperature
        assert agent.alpha == pytest.approx(cfg.init_temperature)

    actor = agent.actor_state({"variant": "x"})
    assert actor["format"] in LEARNERS[name].actor_formats
    net = load_any_actor_net(actor, "cpu")
    assert type(net) is type(actor_loader(actor["format"])(actor, "cpu"))
    assert agent.recurrent == bool(getattr(net, "recurrent", False))  # its actor file acts as it does

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
    # behaviour cloning: the hooks of a learner that learns from demonstrations; every other learner refuses
    # them in one line (AgentBase's)
    assert agent.bc_weight_now == 0.0
    if isinstance(cfg, DemonstrationSettings):
        assert len(agent.clone_parameters()) > 0
    else:
        with pytest.raises(NotImplementedError, match="does not learn from demonstrations"):
            agent.clone_parameters()
        with pytest.raises(NotImplementedError, match="does not learn from demonstrations"):
            agent.clone_update({}, torch.optim.SGD([torch.zeros(1, requires_grad=True)], lr=0.1))


def test_every_hook_the_loop_calls_is_in_the_protocol():
    """Each ``agent.NAME`` that any module of the package uses (the training loop, imitation, the actor
    files, the benchmarks...) is a member of ``Agent`` (and so has a default in ``AgentBase`` or is one every
    learner defines). The stacked update is left out: it restates each learner's own update and reads the
    networks of the learners it stacks (and refuses the others)."""
    import ast
    from pathlib import Path

    import egosearch

    package = Path(egosearch.__file__).parent
    scanned = sorted(set(package.rglob("*.py")) - {package / "rl" / "stacked.py"})
    used = set()
    for path in scanned:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute):
                owner = node.value
                if isinstance(owner, ast.Name) and owner.id == "agent" or (
                        isinstance(owner, ast.Attribute) and owner.attr == "agent"):
                    used.add(node.attr)
    members = {name for name in dir(Agent) if not name.startswith("_")} | set(Agent.__annotations__)
    assert {"bc_weight_now", "clone_parameters", "clone_update", "update"} <= used
    assert used <= members, sorted(used - members)
    # AgentBase names every member (a default or an abstract method), but the counter a learner sets itself
    assert {name for name in members if not hasattr(AgentBase, name)} == {"num_updates"}
