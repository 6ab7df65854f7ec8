"""SAC + CURL learner: shapes, CURL, Polyak targets, fast == reference math, config, Table 2."""

from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest
import torch

from egosearch.rl.common import METRIC_KEYS, AgentStateError, center_crop, crop_at, crop_gather, crop_loop
from egosearch.rl.config import PRESETS, TABLE2_PAPER, LearnerConfig, load_config, table2_rows
from egosearch.rl.sac_curl import SacCurlAgent, conv_out_side, load_actor_net

# A small but structurally complete config (100 -> 84 crops, K = 5, 4 conv layers).
SMALL = {"encoder_num_filters": 8, "encoder_latent_dim": 32, "curl_latent": 32,
         "actor_hidden_dim": 64, "critic_hidden_dim": 64, "device": "cpu"}


def make_agent(impl="fast", action_dim=5, seed=0, **overrides):
    torch.manual_seed(seed)
    return SacCurlAgent(load_config("paper", {**SMALL, **overrides}), action_dim, impl=impl)


def make_batch(b=16, action_dim=5, seed=0):
    g = torch.Generator().manual_seed(seed)
    window = torch.randint(0, 256, (b, 6, 100, 100), dtype=torch.uint8, generator=g)
    return {"obs_depth": window[:, :-1], "next_obs_depth": window[:, 1:],
            "mask": torch.randn(b, 30, generator=g), "proprio": torch.randn(b, 4, generator=g),
            "next_mask": torch.randn(b, 30, generator=g), "next_proprio": torch.randn(b, 4, generator=g),
            "action": torch.rand(b, action_dim, generator=g) * 2 - 1,
            "reward": torch.randn(b, 1, generator=g),
            "not_done": (torch.rand(b, 1, generator=g) > 0.2).float()}


def one_obs(action_dim=5):
    rng = np.random.default_rng(0)
    return {"depth": rng.integers(0, 256, (5, 100, 100), dtype=np.uint8),
            "mask": rng.normal(size=30).astype(np.float32), "proprio": rng.normal(size=4).astype(np.float32)}


# ---- networks and shapes ------------------------------------------------------------------

@pytest.mark.parametrize("action_dim", [5, 3])
def test_act_and_update_shapes(action_dim):
    agent = make_agent(action_dim=action_dim)
    for deterministic in (True, False):
        a = agent.act(one_obs(), deterministic=deterministic)
        assert a.shape == (action_dim,) and a.dtype == np.float32
        assert np.all(np.abs(a) <= 1)
    batch = make_batch(action_dim=action_dim)
    m1, m2 = agent.update(batch), agent.update(batch)
    assert set(m1) == set(METRIC_KEYS)
    assert np.isnan(m1["actor_loss"])  # the actor is updated every 2nd update (CURL)
    assert np.isnan(m2["aux_loss"])  # SAC+CURL's encoder has CURL's loss, no decoder
    assert np.isnan(m2["bc_loss"])  # nor a teacher
    assert all(np.isfinite(v) for k, v in m2.items() if k not in ("aux_loss", "bc_loss"))
    assert m2["alpha"] != pytest.approx(0.1, abs=0) and m2["alpha"] == pytest.approx(0.1, rel=1e-2)


def test_paper_architecture_sizes():
    cfg = LearnerConfig()
    agent = SacCurlAgent(cfg, 5, device="cpu")
    assert conv_out_side(84, 4) == 35
    convs = agent.critic.convs.convs
    assert len(convs) == 4 and [c.stride for c in convs] == [(2, 2), (1, 1), (1, 1), (1, 1)]
    assert all(c.out_channels == 32 and c.kernel_size == (3, 3) for c in convs)
    assert agent.critic.proj.fc.in_features == 32 * 35 * 35 and agent.critic.proj.fc.out_features == 128
    linears = [m for m in agent.actor.trunk if isinstance(m, torch.nn.Linear)]
    assert len(linears) == 4 and [m.out_features for m in linears] == [1024, 1024, 1024, 10]
    assert linears[0].in_features == 128 + 30 + 4
    q_linears = [m for m in agent.critic.q1 if isinstance(m, torch.nn.Linear)]
    assert len(q_linears) == 4 and q_linears[0].in_features == 128 + 30 + 4 + 5
    assert agent.W.shape == (128, 128) and agent.target_entropy == -5.0
    assert agent.alpha == pytest.approx(0.1)


def test_crop_helpers():
    x = torch.randint(0, 256, (4, 5, 100, 100), dtype=torch.uint8)
    oy, ox = torch.tensor([0, 16, 3, 9]), torch.tensor([16, 0, 7, 9])
    for crop in (crop_at, crop_gather, crop_loop):  # crop_gather is the accelerator path
        out = crop(x, oy, ox, 84)
        for i in range(4):
            assert torch.equal(out[i], x[i, :, oy[i]:oy[i] + 84, ox[i]:ox[i] + 84])
    assert torch.equal(center_crop(x, 84), x[..., 8:92, 8:92])


# ---- CURL and targets ---------------------------------------------------------------------

def test_curl_only_updates_lower_the_contrastive_loss_on_a_fixed_batch():
    agent = make_agent()
    batch = make_batch(b=16)
    anchor = crop_at(batch["obs_depth"], torch.randint(0, 17, (16,)), torch.randint(0, 17, (16,)), 84)
    pos = crop_at(batch["obs_depth"], torch.randint(0, 17, (16,)), torch.randint(0, 17, (16,)), 84)
    losses = [agent.curl_update(anchor, pos) for _ in range(20)]
    assert losses[-1] < 0.8 * losses[0], losses


def test_targets_move_by_polyak_tau_exactly():
    agent = make_agent(critic_target_update_freq=2)
    batch = make_batch()
    before = [p.clone() for p in agent.critic_target.parameters()]
    agent.update(batch)  # update 1: no Polyak step with freq 2
    assert all(torch.equal(a, b) for a, b in zip(before, agent.critic_target.parameters()))
    agent.update(batch)  # update 2: Polyak step
    assert not all(torch.equal(a, b) for a, b in zip(before, agent.critic_target.parameters()))

    online_q = [p.detach().clone() for p in agent.critic.q_parameters()]
    target_q = [p.detach().clone() for p in agent.critic_target.q_parameters()]
    online_e = [p.detach().clone() for p in agent.critic.encoder_parameters()]
    target_e = [p.detach().clone() for p in agent.critic_target.encoder_parameters()]
    agent._polyak()
    tau_q, tau_e = agent.cfg.critic_tau, agent.cfg.encoder_tau
    for o, t, new in zip(online_q, target_q, agent.critic_target.q_parameters()):
        torch.testing.assert_close(new, (1 - tau_q) * t + tau_q * o, rtol=1e-6, atol=1e-7)
    for o, t, new in zip(online_e, target_e, agent.critic_target.encoder_parameters()):
        torch.testing.assert_close(new, (1 - tau_e) * t + tau_e * o, rtol=1e-6, atol=1e-7)
    assert (tau_q, tau_e) == (0.01, 0.05)


# ---- the optimised update computes CURL's math ---------------------------------------------

def _params(agent):
    nets = [agent.critic, agent.critic_target, agent.actor]
    return [p.detach() for net in nets for p in net.parameters()] + [agent.W.detach(), agent.log_alpha.detach()]


@pytest.mark.parametrize("channels_last, freqs", [
    (False, (2, 2, 1)), (True, (2, 2, 1)), (True, (1, 1, 1)), (True, (1, 3, 2))])
def test_fast_update_equals_reference_math(channels_last, freqs):
    """With CURL's order (share_encoder_forward=False, the default) the fast path == the
    transcription of CURL's update: same losses, same parameters after 4 updates (incl. actor,
    alpha, Polyak and CURL on and off their schedules).

    On one thread: with two, on an AVX2 CPU, the two paths' kernels split their sums differently,
    and Adam, which divides by the gradient's size, turns that rounding into lr-sized steps of the
    near-zero-gradient entries (0.28% of one tensor's entries differed by more than 1e-5 there,
    against none on one thread). The comparison is about the math, so the thread count is fixed."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        _compare_fast_with_reference(channels_last, freqs)
    finally:
        torch.set_num_threads(threads)


def _compare_fast_with_reference(channels_last, freqs):
    actor_f, target_f, curl_f = freqs
    kw = {"actor_update_freq": actor_f, "critic_target_update_freq": target_f, "curl_update_freq": curl_f}
    fast = make_agent("fast", channels_last=channels_last, **kw)
    ref = make_agent("reference", **kw)
    for a, b in zip(_params(fast), _params(ref)):
        assert torch.equal(a, b)
    for i in range(4):
        batch = make_batch(seed=i)
        torch.manual_seed(100 + i)
        mf = fast.update(batch)
        torch.manual_seed(100 + i)
        mr = ref.update(batch)
        for k in METRIC_KEYS:
            assert mf[k] == pytest.approx(mr[k], rel=1e-4, abs=1e-5, nan_ok=True), (i, k)
    max_lr = 2 * fast.cfg.encoder_lr
    for a, b in zip(_params(fast), _params(ref)):
        # Adam normalises gradients, so float-level differences can show up as up to ~lr in a
        # few near-zero-gradient entries; everything else must agree to float precision.
        diff = (a - b).abs()
        assert diff.max() <= 4 * max_lr
        assert (diff > 1e-5).float().mean() < 1e-3


def test_shared_forward_differs_only_by_one_step_of_lag():
    shared = make_agent("fast", share_encoder_forward=True)
    ref = make_agent("reference", share_encoder_forward=True)  # the reference ignores it
    batch = make_batch()
    torch.manual_seed(7)
    ms = shared.update(batch)
    torch.manual_seed(7)
    mr = ref.update(batch)
    # same weights before the step: the critic loss is identical; in CURL's order the CURL loss
    # is computed after the critic's Adam step moved the encoder, so it differs
    assert ms["critic_loss"] == pytest.approx(mr["critic_loss"], rel=1e-5)
    assert ms["curl_loss"] != pytest.approx(mr["curl_loss"], rel=1e-4)
    assert ms["curl_loss"] == pytest.approx(mr["curl_loss"], rel=0.25)


def test_double_encoder_step_matches_two_adam_steps():
    """CURL steps its encoder with two identical Adam optimisers; the fast path does one step
    at 2 x lr: the results agree."""
    fast = make_agent("fast")
    ref = make_agent("reference")
    batch = make_batch()
    anchor = center_crop(batch["obs_depth"], 84)
    pos = crop_at(batch["obs_depth"], torch.zeros(16, dtype=torch.long), torch.zeros(16, dtype=torch.long), 84)
    for _ in range(3):
        assert fast.curl_update(anchor, pos) == pytest.approx(ref.curl_update(anchor, pos), rel=1e-5)
    for a, b in zip(fast.critic.encoder_parameters(), ref.critic.encoder_parameters()):
        torch.testing.assert_close(a, b, rtol=1e-4, atol=1e-6)


# ---- persistence ---------------------------------------------------------------------------

def test_state_dict_roundtrip_weights_only():
    a = make_agent()
    batch = make_batch()
    a.update(batch)
    a.update(batch)
    buf = io.BytesIO()
    torch.save(a.state_dict(), buf)
    buf.seek(0)
    state = torch.load(buf, weights_only=True)
    b = make_agent(seed=123)
    b.load_state_dict(state)
    assert b.num_updates == 2
    torch.manual_seed(0)
    ma = a.update(batch)
    torch.manual_seed(0)
    mb = b.update(batch)
    assert ma == pytest.approx(mb, nan_ok=True, rel=0, abs=0)
    other = make_agent(encoder_num_filters=4)
    with pytest.raises(AgentStateError, match="encoder_num_filters"):
        other.load_state_dict(state)


@pytest.mark.parametrize("storage", [torch.float32, torch.float16])
def test_actor_state_loads_weights_only_and_acts_like_the_agent(storage):
    agent = make_agent()
    agent.update(make_batch())
    buf = io.BytesIO()
    torch.save(agent.actor_state({"variant": "head-on", "config": agent.cfg.to_dict()}, storage_dtype=storage), buf)
    buf.seek(0)
    state = torch.load(buf, weights_only=True)
    assert state["metadata"]["variant"] == "head-on"
    assert not any(k.startswith("q") for k in state["state_dict"])  # actor only
    assert all(v.dtype == storage for v in state["state_dict"].values() if v.is_floating_point())
    net = load_actor_net(state)
    obs = one_obs()
    with torch.no_grad():
        depth = center_crop(torch.as_tensor(obs["depth"])[None], 84).float()
        extra = torch.cat([torch.as_tensor(obs["mask"]), torch.as_tensor(obs["proprio"])])[None]
        mu, _ = net(depth, extra)
    # float16 weights: within ~1e-3 of the live float32 agent.
    np.testing.assert_allclose(torch.tanh(mu)[0].numpy(), agent.act(obs, deterministic=True), atol=5e-3)
    # However it was stored, the loaded actor is the same float16 actor.
    other = torch.float16 if storage == torch.float32 else torch.float32
    twin = load_actor_net(torch.load(_saved(agent.actor_state({}, storage_dtype=other)), weights_only=True))
    with torch.no_grad():
        assert torch.equal(twin(depth, extra)[0], mu)


def _saved(state) -> io.BytesIO:
    buf = io.BytesIO()
    torch.save(state, buf)
    buf.seek(0)
    return buf


# ---- config ----------------------------------------------------------------------------------

@pytest.mark.parametrize("overrides, field", [
    ({"crop_size": 101}, "crop_size"),
    ({"actor_lr": -1e-3}, "actor_lr"),
    ({"gamma": 0.0}, "gamma"),
    ({"gamma": 1.01}, "gamma"),
    ({"critic_tau": 1.5}, "critic_tau"),
    ({"alpha_beta1": 1.0}, "alpha_beta1"),
    ({"batch_size": 0}, "batch_size"),
    ({"actor_activation": "swish"}, "actor_activation"),
    ({"curl_latent": 64}, "curl_latent"),
    ({"encoder_num_layers": 30}, "encoder_num_layers"),
    ({"batch_size": 3.5}, "batch_size"),
])
def test_config_validation_errors_are_one_line_and_name_the_field(overrides, field):
    with pytest.raises(ValueError) as err:
        load_config("paper", overrides)
    msg = str(err.value)
    assert "\n" not in msg and field in msg


def test_unknown_preset_or_field():
    with pytest.raises(ValueError, match="unknown preset 'fast'; allowed: smoke, cpu, paper"):
        load_config("fast", {})
    with pytest.raises(ValueError, match="unknown LearnerConfig field"):
        load_config("paper", {"learning_rate": 1e-3})


def test_presets_are_valid_and_paper_is_table2():
    for name in PRESETS:
        load_config(name, {})
    paper = load_config("paper", {})
    # Table 2's values are the defaults; the preset adds how a GPU runs them (cuda_graph, housekeeping)
    assert {f for f, v in paper.to_dict().items() if v != LearnerConfig().to_dict()[f]} == {"cuda_graph"}


def test_the_configs_forms_of_r_d_are_the_envs():
    from egosearch.rl.config import DISTANCE_REWARDS
    from egosearch.sim.env import DISTANCE_REWARDS as ENV_DISTANCE_REWARDS

    assert DISTANCE_REWARDS == ENV_DISTANCE_REWARDS
    # and a variant file's env may name each of them (the schema that checks it lists the same)
    import json
    from pathlib import Path

    import egosearch.workflow

    schema = json.loads((Path(egosearch.workflow.__file__).parent / "variant.schema.json").read_text())
    found = [node["enum"] for node in _walk(schema) if "distance_reward" in node.get("properties", {})
             for node in [node["properties"]["distance_reward"]]]
    assert found and all(tuple(e) == ENV_DISTANCE_REWARDS for e in found)


def _walk(node):
    if isinstance(node, dict):
        yield node
        for value in node.values():
            yield from _walk(value)
    elif isinstance(node, list):
        for value in node:
            yield from _walk(value)


def test_every_preset_and_the_sensor_use_the_frames_the_env_renders(tmp_path):
    """One image size (egosearch.sim.body.IMAGE_SIZE): the env's frames, the sensor's default, and every
    preset's image_size; a config that differs is refused in one line when it is loaded or trained."""
    from egosearch.rl.train import train
    from egosearch.sim.body import IMAGE_SIZE
    from egosearch.sim.env import SearchEnv
    from egosearch.sim.sensor import DEFAULT_HEIGHT, DEFAULT_WIDTH

    env = SearchEnv(layout="kitchen_living")
    try:
        assert env.observation_space["depth"].shape[1:] == (IMAGE_SIZE, IMAGE_SIZE)
    finally:
        env.close()
    assert (DEFAULT_WIDTH, DEFAULT_HEIGHT) == (IMAGE_SIZE, IMAGE_SIZE)
    assert {load_config(name, {}).image_size for name in PRESETS} == {LearnerConfig().image_size} == {IMAGE_SIZE}
    with pytest.raises(ValueError, match=r"image_size=90 is out of range; allowed: 100 \(the env renders") as err:
        load_config("smoke", {"image_size": 90})
    assert "\n" not in str(err.value)
    # a config made around the check (dataclasses.replace skips it) is refused by the training before any work
    smaller = dataclasses.replace(load_config("smoke", {"device": "cpu", "num_envs": 1}), image_size=90)
    with pytest.raises(ValueError, match=r"image_size=90 is out of range"):
        train("EgoSearch-v0", smaller, tmp_path, env_kwargs={"layout": "kitchen_living"}, progress=False)
    assert not any(tmp_path.iterdir())


# the paper's Table 2 (Appendix A), verbatim
PAPER_TABLE2 = [
    ("Image Size", "100x100"), ("Augmentation", "Random Crop (84x84)"),
    ("Image History Buffer Size", "5"), ("Head History Buffer Size", "1"),
    ("Replay buffer", "100000"), ("Discount rate γ", "0.99"),
    ("Number of training steps", "0.75M"), ("Batch-size", "32"),
    ("Alpha (SAC) : initial temperature", "0.1"), ("Alpha (SAC) : learning rate", "0.0001"),
    ("Alpha (SAC) : optimizer β1", "0.5"), ("Alpha (SAC) : optimizer β2", "0.999"),
    ("Actor : learning rate", "0.001"), ("Actor : optimizer β1", "0.9"),
    ("Actor : optimizer β2", "0.999"), ("Actor : Number of layers", "4"),
    ("Actor : Hidden dim", "1024"), ("Actor : Activation function", "ReLU"),
    ("Critic : learning rate", "0.001"), ("Critic : τ (polyak averaging)", "0.01"),
    ("Critic : optimizer β1", "0.9"), ("Critic : optimizer β2", "0.999"),
    ("Critic : Number of layers", "4"), ("Critic : Hidden dim", "1024"),
    ("Critic : Activation function", "ReLU"), ("Encoder (CNN) : learning rate", "0.001"),
    ("Encoder (CNN) : τ (polyak averaging)", "0.05"), ("Encoder (CNN) : Number of layers", "4"),
    ("Encoder (CNN) : Number of filters", "32"), ("Encoder (CNN) : Latent dimension", "128"),
    ("Encoder (CNN) : Activation function", "ReLU"),
]


def test_table2_rows_match_the_paper():
    assert table2_rows(load_config("paper", {})) == PAPER_TABLE2
    assert list(TABLE2_PAPER) == PAPER_TABLE2
    cpu = load_config("cpu", {})
    rows = dict(table2_rows(cpu))
    assert rows["Batch-size"] == str(cpu.batch_size) and rows["Replay buffer"] == "100000"
    assert rows["Encoder (CNN) : Number of filters"] == str(cpu.encoder_num_filters)
    side = 100 // cpu.obs_downsample
    assert rows["Augmentation"] == f"Random Shift (±{cpu.aug_pad} px at {side}x{side})"
    assert rows["Encoder (CNN) : τ (polyak averaging)"].startswith("none")


def test_departures_list_exactly_the_fields_that_differ_from_the_paper():
    from egosearch.rl.config import HOUSEKEEPING_FIELDS, departure_rows, field_defaults, field_docs, field_order

    assert departure_rows(load_config("paper", {})) == []
    cfg = load_config("paper", {"batch_size": 64, "seed": 7, "algorithm": "sac_drq", "encoder_num_layers": 2})
    rows = {f: (mine, paper, doc) for f, mine, paper, doc in departure_rows(cfg)}
    assert set(rows) == {"batch_size", "algorithm", "encoder_num_layers"}  # seed is housekeeping
    assert rows["batch_size"][:2] == ("64", "32") and rows["batch_size"][2].startswith('Table 2 "Batch-size"')
    assert rows["algorithm"][2].startswith("Paper 4.2")
    docs = field_docs()  # every field documents its source, so every departure can name one
    assert set(docs) == set(field_defaults()) and all(docs.values())
    assert "seed" in HOUSEKEEPING_FIELDS
    # the order departures are listed in names every field of every learner once
    assert sorted(field_order()) == sorted(field_defaults())


def test_bench_timer_runs():
    from egosearch.rl.bench_learner import time_updates

    r = time_updates("smoke", threads=1, warmup=1, updates=2)
    assert 0 < r["best_s"] <= r["median_s"] < 10
    # the cpu preset's learner has a privileged critic: its update needs the replay's states
    r = time_updates("cpu", threads=1, warmup=1, updates=2)
    assert 0 < r["best_s"] <= r["median_s"] < 10


def test_the_learner_benchmark_times_table2_eagerly_although_the_paper_preset_graphs(monkeypatch):
    """The eager Table 2 rows are the baseline the graphed row is read against: they must turn the
    paper preset's cuda_graph off themselves, or on a GPU both sides would be graphed."""
    import egosearch.rl.bench_learner as bench

    asked = []

    def fake_time_updates(preset="paper", overrides=None, agent_options=None, threads=None, warmup=3, updates=10,
                          **_):
        asked.append((preset, dict(overrides or {}), (agent_options or {}).get("impl", "fast")))
        return {"median_s": 0.1, "best_s": 0.1}

    monkeypatch.setattr(bench, "time_updates", fake_time_updates)
    monkeypatch.setattr(bench, "cpu_vector_unit", lambda: "AVX-512")
    monkeypatch.setattr(bench, "_avx2_limited_cpu_profile", lambda quick, run: {"updates_per_s_cpu_profile": 3.0})
    result = bench.bench_learner(quick=True, cpu_profile_run=False)
    assert result["updates_per_s_cpu_profile_avx2"] == 3.0
    fast_table2 = [o for preset, o, impl in asked if preset == "paper" and impl == "fast"]
    assert len(fast_table2) == 3 and all(o.get("cuda_graph") is False for o in fast_table2)
    assert "updates_per_s_table2" in result


def test_memory_lever_costs_alternate_the_observations_and_divide_core_seconds_per_step(monkeypatch):
    """Round by round, plain then each option; the ratio is the plain rate over the option's (median of rounds)."""
    import egosearch.rl.bench_learner as bench

    asked, rates = [], {"plain": iter([100.0, 80.0]), "map_image": iter([60.0, 60.0]),
                        "strided_history": iter([90.0, 70.0])}

    def fake_throughput(preset="cpu", env_steps=3000, overrides=None):
        name = next(iter(overrides)) if overrides else "plain"
        asked.append((preset, name, dict(overrides or {})))
        return {"env_steps_per_core_s": next(rates[name])}

    monkeypatch.setattr(bench, "training_throughput", fake_throughput)
    result = bench.memory_lever_costs(quick=True, rounds=2)
    assert [name for _, name, _ in asked] == ["plain", "map_image", "strided_history"] * 2
    assert all(preset == "cpu" for preset, _, _ in asked)
    assert [o for _, name, o in asked if name == "map_image"] == [{"map_image": True}] * 2
    assert result["env_steps_per_core_s_plain"] == 90.0 and result["env_steps_per_core_s_map_image"] == 60.0
    assert result["map_image_cost_ratio"] == 1.5  # 90 / 60: a map-image step costs half as much again
    assert result["strided_history_cost_ratio"] == 1.12  # 90 / 80


def test_memory_levers_is_refused_by_the_benchmarks_that_do_not_read_it(tmp_path, capsys):
    from egosearch.cli import main

    for what in ("env", "stacked"):
        assert main(["bench", what, "--memory-levers", "--out", str(tmp_path / "r.json")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"egosearch bench: error: --memory-levers is read by `bench learner` only, not by "
                       f"`bench {what}`"]
    assert not (tmp_path / "r.json").exists()


def test_cuda_graph_is_on_in_the_paper_preset_alone_and_ignored_on_the_cpu():
    assert load_config("paper", {}).cuda_graph and not load_config("cpu", {}).cuda_graph
    assert not load_config("smoke", {}).cuda_graph
    load_config("paper", {"algorithm": "sac_drq", "compile": True})  # the learners it does not apply to ignore it
    small = {"device": "cpu", "batch_size": 4, "actor_hidden_dim": 16, "critic_hidden_dim": 16,
             "encoder_num_layers": 1, "encoder_num_filters": 4}
    agents = []
    for graph in (False, True):
        torch.manual_seed(0)
        agents.append(SacCurlAgent(load_config("paper", {**small, "cuda_graph": graph}), 5))
    assert agents[1].graphed is None  # a CPU has no graphs to record: the eager update runs
    assert not any(g.get("capturable") for opt in agents[1].optimisers.values() for g in opt.param_groups)
    rng = np.random.default_rng(0)
    batch = {"obs_depth": torch.from_numpy(rng.integers(0, 256, (4, 5, 100, 100), dtype=np.uint8)),
             "next_obs_depth": torch.from_numpy(rng.integers(0, 256, (4, 5, 100, 100), dtype=np.uint8)),
             "mask": torch.zeros(4, 30), "next_mask": torch.zeros(4, 30), "proprio": torch.zeros(4, 4),
             "next_proprio": torch.zeros(4, 4), "action": torch.zeros(4, 5), "reward": torch.ones(4, 1),
             "not_done": torch.ones(4, 1)}
    metrics = []
    for agent in agents:
        torch.manual_seed(1)
        metrics.append(agent.update(batch))
    np.testing.assert_equal(metrics[1], metrics[0])  # NaN where a loss was not computed, in both
    # a checkpoint from a GPU run with graphs (capturable Adam) resumes here without them
    state = agents[0].state_dict()
    for opt_state in state["optimisers"].values():
        for group in opt_state["param_groups"]:
            group["capturable"] = True
    agents[1].load_state_dict(state)
    assert not any(g["capturable"] for opt in agents[1].optimisers.values() for g in opt.param_groups)
    assert np.isfinite(agents[1].update(batch)["critic_loss"])
