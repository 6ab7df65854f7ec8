"""Stacked seeds (issue 47, item 4): a stacked update equals N separate updates from the same states
and batches, to float rounding: parameters, optimiser states, metrics and what each seed's random
stream has consumed, for SAC + CURL and for SAC-DrQ."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest
import torch

from egosearch.rl.config import load_config
from egosearch.rl.sac_curl import SacCurlAgent
from egosearch.rl.sac_drq import SacDrqAgent
from egosearch.rl.stacked import SeedStreams, StackedSacCurl, StackingError, check_stackable, stack_agents

SEEDS = (0, 1, 2)
STREAM_BASE = 500
"""Seed k's random stream for the updates starts at ``torch.manual_seed(STREAM_BASE + k)``."""
CURL_SMALL = {"encoder_num_filters": 8, "encoder_latent_dim": 32, "curl_latent": 32, "actor_hidden_dim": 64,
              "critic_hidden_dim": 64, "device": "cpu"}
DRQ_SMALL = {"encoder_num_filters": 8, "encoder_latent_dim": 32, "actor_hidden_dim": 64,
             "critic_hidden_dim": 64, "device": "cpu", "critic_warmup_updates": 2, "num_threads": 1}
STATE_DIM = 7
ROUNDING = {"rtol": 1e-4, "atol": 2e-5}
"""Float rounding between a stacked (grouped, batched) kernel and a separate one."""
AMPLIFIED_SHARE, AMPLIFIED_MAX = 1e-4, 1e-3
"""Adam divides a gradient by its own running size, so on a weight whose gradient is near zero (a
conv feature almost always 0 under the projection) a rounding difference can move the step by up to
a learning rate: at most this share of a tensor's values may differ beyond ``ROUNDING``, by at most
this much (measured on SAC+CURL: 1 value in 300k, 2e-4 after four updates). The comparisons run on
the portable kernels (conftest.PORTABLE_KERNELS): with an AVX2 host's own, the grouped convolution sums
in another order than the single one, and 1 value in 115 of a conv layer moved beyond ``ROUNDING``."""


def curl_agent(seed: int, **overrides) -> SacCurlAgent:
    torch.manual_seed(seed)
    return SacCurlAgent(load_config("paper", {**CURL_SMALL, **overrides}), 5)


def curl_cuda_agent(seed: int, graphed: bool = False) -> SacCurlAgent:
    return curl_agent(seed, device="cuda", cuda_graph=graphed)


def drq_agent(seed: int) -> SacDrqAgent:
    torch.manual_seed(seed)
    agent = SacDrqAgent(load_config("cpu", DRQ_SMALL), 5, state_dim=STATE_DIM)
    agent.bc_weight_now = 0.3
    return agent


def batch(seed: int, side: int, b: int = 16, drq: bool = False) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    window = torch.randint(0, 256, (b, 6, side, side), dtype=torch.uint8, generator=g)
    out = {"obs_depth": window[:, :-1], "next_obs_depth": window[:, 1:],
           "mask": torch.randn(b, 30, generator=g), "proprio": torch.randn(b, 4, generator=g),
           "next_mask": torch.randn(b, 30, generator=g), "next_proprio": torch.randn(b, 4, generator=g),
           "action": torch.rand(b, 5, generator=g) * 2 - 1, "reward": torch.randn(b, 1, generator=g),
           "not_done": (torch.rand(b, 1, generator=g) > 0.2).float()}
    if drq:  # the cpu preset's batches: n-step discounts, the privileged state, half from demonstrations
        out.update(discount=torch.full((b, 1), 0.99 ** 3), state=torch.randn(b, STATE_DIM, generator=g),
                   next_state=torch.randn(b, STATE_DIM, generator=g),
                   demo=torch.cat([torch.zeros(b // 2, 1), torch.ones(b - b // 2, 1)]))
    return out


def flat(state, prefix=""):
    """A nested agent state -> {path: tensor or value}."""
    if isinstance(state, dict):
        return {k: v for key, value in state.items() for k, v in flat(value, f"{prefix}{key}/").items()}
    if isinstance(state, (list, tuple)):
        return {k: v for i, value in enumerate(state) for k, v in flat(value, f"{prefix}{i}/").items()}
    return {prefix: state}


def generator_state(device: torch.device) -> torch.Tensor:
    return torch.cuda.get_rng_state(device) if device.type == "cuda" else torch.get_rng_state()


def seeded_streams(device: torch.device) -> SeedStreams:
    streams = SeedStreams(device)
    for k in range(len(SEEDS)):
        torch.manual_seed(STREAM_BASE + k)
        streams.capture()
    return streams


def run_both(make, side: int, updates: int, drq: bool = False, device: str = "cpu"):
    """(separate agents after their updates, the stacked agents after theirs, the metrics of each,
    the seeds' torch generator states (the device's) after each)."""
    dev = torch.device(device)
    separate = [make(seed) for seed in SEEDS]
    members = [copy.deepcopy(a) for a in separate]
    stacked = stack_agents(members, seeded_streams(dev))
    batches = [[{k: v.to(dev) for k, v in batch(100 * u + k, side, drq=drq).items()} for k in range(len(SEEDS))]
               for u in range(updates)]
    separate_metrics, separate_rng = [], []
    for k, agent in enumerate(separate):
        torch.manual_seed(STREAM_BASE + k)
        separate_metrics.append([agent.update(batches[u][k]) for u in range(updates)])
        separate_rng.append(generator_state(dev))
    outside = torch.get_rng_state()
    stacked_metrics = [stacked.update(batches[u]) for u in range(updates)]
    assert torch.equal(torch.get_rng_state(), outside)  # the process's own stream is left alone
    stacked.sync_members()
    return separate, stacked, separate_metrics, stacked_metrics, separate_rng


def assert_same_runs(separate, stacked, separate_metrics, stacked_metrics, separate_rng):
    for k, agent in enumerate(separate):
        mine, theirs = flat(stacked.members[k].state_dict()), flat(agent.state_dict())
        assert mine.keys() == theirs.keys()
        for key, value in theirs.items():
            if torch.is_tensor(value):
                a, b = mine[key].float().cpu(), value.float().cpu()
                off = ~torch.isclose(a, b, **ROUNDING)
                assert off.float().mean() <= AMPLIFIED_SHARE, (k, key, off.float().mean().item())
                assert (a - b).abs().max() <= AMPLIFIED_MAX, (k, key, (a - b).abs().max().item())
            else:
                assert mine[key] == value, (k, key)
        for u, (m1, m2) in enumerate(zip(stacked_metrics, separate_metrics[k])):
            for name, value in m2.items():
                if math.isnan(value):
                    assert math.isnan(m1[k][name]), (k, u, name)
                else:
                    assert m1[k][name] == pytest.approx(value, rel=1e-4, abs=1e-5), (k, u, name)
        # each seed drew exactly what its separate update drew
        state = stacked.streams.states[k]
        assert torch.equal(state.torch_cuda if state.torch_cuda is not None else state.torch_cpu, separate_rng[k])
    # not trivially equal: the seeds differ from one another, and the updates moved them
    states = [flat(agent.state_dict()) for agent in separate]
    assert not torch.allclose(states[0]["critic/q1.0.weight/"], states[1]["critic/q1.0.weight/"])


@pytest.mark.portable_kernels
def test_stacked_sac_curl_equals_separate_updates():
    runs = run_both(curl_agent, 100, updates=4)
    separate, stacked, separate_metrics, stacked_metrics, _ = runs
    assert_same_runs(*runs)
    # the four updates took every step: the actor and the Polyak step every 2nd, CURL every one
    assert all(not math.isnan(m[k]["curl_loss"]) for m in stacked_metrics for k in range(3))
    assert [math.isnan(m[0]["actor_loss"]) for m in stacked_metrics] == [True, False, True, False]
    assert stacked.members[0].num_updates == 4 and stacked.num_updates == 4


@pytest.mark.portable_kernels
def test_stacked_sac_drq_equals_separate_updates():
    runs = run_both(drq_agent, 50, updates=4, drq=True)
    separate, stacked, separate_metrics, stacked_metrics, _ = runs
    assert_same_runs(*runs)
    # two critic warm-up updates, then the actor with its cloning term
    assert [math.isnan(m[1]["actor_loss"]) for m in stacked_metrics] == [True, True, False, False]
    assert not math.isnan(stacked_metrics[3][2]["bc_loss"])


def test_members_act_with_the_stacked_parameters():
    streams = SeedStreams(torch.device("cpu"))
    members = [curl_agent(seed) for seed in SEEDS]
    for k in range(len(SEEDS)):
        torch.manual_seed(k)
        streams.capture()
    stacked = stack_agents(members, streams)
    obs = {"depth": np.random.default_rng(0).integers(0, 256, (5, 100, 100), dtype=np.uint8),
           "mask": np.zeros(30, np.float32), "proprio": np.zeros(4, np.float32)}
    before = members[1].act(obs, deterministic=True)
    stacked.update([batch(k, 100) for k in range(len(SEEDS))])
    stacked.update([batch(10 + k, 100) for k in range(len(SEEDS))])  # the actor's first step
    assert not np.allclose(members[1].act(obs, deterministic=True), before)
    assert members[1].critic.q1[0].weight.data_ptr() == stacked.params["critic.q1.0.weight"][1].data_ptr()


def test_what_cannot_be_stacked_is_refused():
    streams = SeedStreams(torch.device("cpu"))
    streams.capture()
    streams.capture()
    with pytest.raises(StackingError, match="different architectures"):
        StackedSacCurl([curl_agent(0), curl_agent(1, critic_hidden_dim=32)], streams)
    with pytest.raises(StackingError, match="algorithm ppo is not stacked; stacked: sac_curl, sac_drq"):
        check_stackable(dataclasses.replace(load_config("smoke"), algorithm="ppo"))
    with pytest.raises(StackingError, match="encoder_aux_loss=.reconstruction.: the stacked SacDrqAgent update"):
        check_stackable(load_config("cpu", {"encoder_aux_loss": "reconstruction"}))
    with pytest.raises(StackingError, match="share_encoder_forward"):
        StackedSacCurl([curl_agent(0, share_encoder_forward=True), curl_agent(1, share_encoder_forward=True)],
                       streams)
    with pytest.raises(StackingError, match="one stream per member"):
        stack_agents([curl_agent(0)], streams)


def test_seed_streams_keep_each_seeds_draws_apart():
    streams = SeedStreams(torch.device("cpu"))
    for seed in (3, 3, 4):
        torch.manual_seed(seed)
        np.random.seed(seed)
        streams.capture()
    torch.manual_seed(9)
    outside = torch.rand(2)
    torch.manual_seed(9)
    draws = []
    for k in (0, 2, 1, 0):
        with streams.stream(k):
            draws.append((torch.rand(3), np.random.rand(2)))
    assert torch.equal(torch.rand(2), outside)  # the process's own stream went on as if nothing was drawn
    torch.manual_seed(3)
    np.random.seed(3)
    first, second = (torch.rand(3), np.random.rand(2)), (torch.rand(3), np.random.rand(2))
    # seeds 0 and 1 start alike and each goes on from its own last draw, whatever drew in between
    assert torch.equal(draws[0][0], first[0]) and np.array_equal(draws[0][1], first[1])
    assert torch.equal(draws[2][0], first[0]) and torch.equal(draws[3][0], second[0])
    assert not torch.equal(draws[1][0], first[0])  # seed 2's stream is another


# ---- on a GPU (the ``gpu`` marker: skipped without CUDA) -----------------------------------------

needs_cuda = pytest.mark.skipif(not torch.cuda.is_available(), reason="CUDA is not available")


@pytest.mark.gpu
@needs_cuda
def test_stacked_sac_curl_on_cuda_equals_separate_updates():
    assert_same_runs(*run_both(curl_cuda_agent, 100, updates=4, device="cuda"))


@pytest.mark.gpu
@needs_cuda
def test_the_stacked_update_recorded_as_cuda_graphs_equals_the_eager_one():
    """Its random numbers are drawn before the graph, from the seeds' streams, so the recorded stacked
    update and the eager one see the same draws: 8 updates warm up, record and replay both patterns."""
    device = torch.device("cuda")
    graphed = stack_agents([curl_cuda_agent(seed, graphed=True) for seed in SEEDS], seeded_streams(device))
    eager = stack_agents([curl_cuda_agent(seed) for seed in SEEDS], seeded_streams(device))
    assert graphed.graphed is not None and eager.graphed is None
    for u in range(8):
        batches = [{k: v.to(device) for k, v in batch(100 * u + k, 100).items()} for k in range(len(SEEDS))]
        for m1, m2 in zip(graphed.update(batches), eager.update(batches)):
            for name, value in m2.items():
                assert math.isnan(m1[name]) if math.isnan(value) else m1[name] == pytest.approx(value, rel=1e-3), name
    assert graphed.graphed.captures == 2
    for name, tensor in eager.params.items():
        assert torch.allclose(graphed.params[name], tensor, rtol=1e-3, atol=1e-4), name


def _changed(value):
    """A value other than ``value`` of the same kind (what refusal compares; never validated here)."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, (int, float)):
        return value * 2 + 1
    return f"{value}_other"


@pytest.mark.parametrize("algorithm", ["sac_drq", "sac_curl"])
def test_stacked_seeds_refuse_every_field_their_update_does_not_implement(algorithm):
    """Every field a learner's update may read is either done by the stacked update (its ``implemented`` list,
    whose names are all the config's) or refused in one line when set away from its default, and a field added to
    the learner's settings is refused until the stacked update implements it: stacked seeds never train without a
    field their learner reads."""
    from egosearch.rl.learner_registry import learner
    from egosearch.rl.stacked import STACKED, update_fields

    cfg = load_config("cpu" if algorithm == "sac_drq" else "paper", {"algorithm": algorithm})
    kind = STACKED[learner(algorithm).agent_factory()]
    names = {f.name for f in update_fields(cfg)}
    assert kind.implemented <= names, sorted(kind.implemented - names)
    check_stackable(cfg)  # the preset itself stacks
    for f in update_fields(cfg):
        if f.name in kind.implemented:
            continue
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
        with pytest.raises(StackingError, match=rf"^{f.name}=.*does not implement it"):
            check_stackable(dataclasses.replace(cfg, **{f.name: _changed(default)}))
    # a new field of the learner's update (a critic gradient-clip norm, say) is refused until implemented
    grown = dataclasses.make_dataclass("Grown", [("critic_grad_clip", float, dataclasses.field(default=0.0))],
                                       bases=(type(cfg),))
    with pytest.raises(StackingError, match="^critic_grad_clip=1.0"):
        check_stackable(grown(**{**dataclasses.asdict(cfg), "critic_grad_clip": 1.0}))
    check_stackable(grown(**dataclasses.asdict(cfg)))  # at its default it changes nothing
