"""The learners on CUDA (the ``gpu`` marker: skipped where CUDA is absent), and a CUDA-trained actor
file read on this machine (runs everywhere).

The CUDA tests compare one update on CUDA with the same update on the CPU, from the same weights,
optimiser state and batch. Both draw their random numbers (crop offsets, shifts, the policy's noise)
from one host generator, so that only the arithmetic differs. TF32 is switched off for them: with
it, convolutions round their inputs to 10 mantissa bits and the two devices no longer compute the
same function. Stated tolerance, per tensor: ``|d_cuda - d_cpu| <= 1e-3 |d_cpu| + 1e-7 sqrt(n)``
for each weight tensor's change ``d`` over the update (Euclidean norms, ``n`` its size), and
``1e-4`` relative for the update's losses. The measured differences are written to the JSON file
``$EGOSEARCH_CUDA_REPORT`` names, when it names one.
"""

from __future__ import annotations

import contextlib
import copy
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import torch

# cuBLAS reads this when it starts: before any test of this process touches CUDA (deterministic GEMMs)
os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")

from egosearch.rl.bench_learner import _filled_replay  # noqa: E402
from egosearch.rl.config import load_config  # noqa: E402
from egosearch.rl.learner_registry import make_agent  # noqa: E402
from egosearch.rl.sac_curl import load_actor_net  # noqa: E402
from egosearch.rl.train import train  # noqa: E402
from egosearch.sim.env import PRIVILEGED_STATE_DIM  # noqa: E402

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID  # noqa: E402
from test_rl_train import TIMING_COLUMNS, Interrupt, check_complete_run, read_csv  # noqa: E402

CUDA_ACTOR = TESTS / "data" / "cuda_actor.pt"
"""An actor trained on CUDA: ``test_cuda_training_resumes_and_its_actor_loads_without_cuda`` wrote it
on a GPU machine (``EGOSEARCH_CUDA_ACTOR_OUT``), in the first GPU check (commit ce339b0); the stored
results/paper/gpu_check/cuda_tests.log is a later run of the same tests, which kept its actor elsewhere."""

needs_cuda = pytest.mark.skipif(not torch.cuda.is_available(), reason="CUDA is not available")
REPORT: dict = {}


def _report(key: str, value) -> None:
    REPORT[key] = value
    path = os.environ.get("EGOSEARCH_CUDA_REPORT")
    if path:
        Path(path).write_text(json.dumps(REPORT, indent=1) + "\n")


@contextlib.contextmanager
def host_random(seed: int):
    """``torch.randint`` and ``torch.randn_like`` drawn from one CPU generator, then moved to the
    device asked for: the same numbers on either device (the learners draw nothing else)."""
    gen = torch.Generator().manual_seed(seed)
    randint, randn = torch.randint, torch.randn

    def host_randint(low, high, size, *, device=None, **_):
        return randint(low, high, size, generator=gen).to(device)

    def host_randn_like(x, **_):
        return randn(x.shape, generator=gen, dtype=x.dtype).to(x.device)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(torch, "randint", host_randint)
        mp.setattr(torch, "randn_like", host_randn_like)
        yield


@contextlib.contextmanager
def exact_fp32():
    saved = torch.backends.cudnn.allow_tf32, torch.backends.cuda.matmul.allow_tf32
    torch.backends.cudnn.allow_tf32 = torch.backends.cuda.matmul.allow_tf32 = False
    try:
        yield
    finally:
        torch.backends.cudnn.allow_tf32, torch.backends.cuda.matmul.allow_tf32 = saved


def _weights(agent) -> dict[str, torch.Tensor]:
    state = agent.state_dict()
    out = {}
    for part, value in state.items():
        if isinstance(value, dict) and part != "optimisers" and part != "arch":
            out.update({f"{part}.{k}": v.detach().float().cpu().clone() for k, v in value.items()
                        if torch.is_tensor(v) and v.is_floating_point()})
        elif torch.is_tensor(value) and value.is_floating_point():
            out[part] = value.detach().float().cpu().clone()
    return out


@pytest.mark.gpu
@needs_cuda
@pytest.mark.parametrize("preset", ["paper", "cpu"])
def test_one_update_on_cuda_matches_the_cpu_update(preset):
    """``paper``: SAC+CURL at Table 2's sizes; ``cpu``: SAC-DrQ with the privileged critic."""
    cfg = load_config(preset, {"device": "cpu"})
    state_dim = PRIVILEGED_STATE_DIM if cfg.critic_privileged_state else 0
    torch.manual_seed(0)
    cpu_agent = make_agent(cfg, 5, 30, 4, torch.device("cpu"), state_dim)
    replay = _filled_replay(5, torch.device("cpu"), n=300, size=getattr(cpu_agent, "replay_image_size", cfg.image_size),
                            state_dim=state_dim)
    with host_random(1):  # a few updates first, so that Adam's moments are not at their first step
        for _ in range(3):
            cpu_agent.update(replay.sample(cfg.batch_size))
    state = copy.deepcopy(cpu_agent.state_dict())
    batch = replay.sample(cfg.batch_size)
    cuda_agent = make_agent(load_config(preset, {"device": "cuda"}), 5, 30, 4, torch.device("cuda"), state_dim)
    cuda_agent.load_state_dict(state)
    before = _weights(cpu_agent)
    with exact_fp32():
        with host_random(2):
            m_cpu = cpu_agent.update(batch)
        with host_random(2):
            m_cuda = cuda_agent.update({k: v.to("cuda") if k != "index" else v for k, v in batch.items()})
    worst_metric, worst_tensor = 0.0, 0.0
    for key, a in m_cpu.items():
        b = m_cuda[key]
        assert math.isnan(a) == math.isnan(b), key
        if not math.isnan(a):
            worst_metric = max(worst_metric, abs(a - b) / max(abs(a), 1e-6))
            assert abs(a - b) <= 1e-4 * max(abs(a), 1e-3), (key, a, b)
    w_cpu, w_cuda = _weights(cpu_agent), _weights(cuda_agent)
    assert w_cpu.keys() == w_cuda.keys() == before.keys()
    moved = 0
    for name, start in before.items():
        d_cpu, d_cuda = w_cpu[name] - start, w_cuda[name] - start
        err, scale = float((d_cuda - d_cpu).norm()), float(d_cpu.norm())
        moved += scale > 0
        worst_tensor = max(worst_tensor, err / scale if scale > 0 else 0.0)
        assert err <= 1e-3 * scale + 1e-7 * math.sqrt(start.numel()), (name, err, scale)
    assert moved >= len(before) // 2  # the update changed the networks: the comparison compares something
    _report(f"update_{preset}", {"algorithm": cfg.algorithm, "batch": cfg.batch_size, "tensors": len(before),
                                  "tensors_moved": moved, "max_relative_metric_difference": worst_metric,
                                  "max_relative_update_difference": worst_tensor})


@contextlib.contextmanager
def fixed_device_random():
    """``torch.randint`` and ``torch.randn_like`` as fixed functions of the shape, computed on the
    device: a recorded update replays the same numbers an eager one draws (torch's generator gives
    a graph other offsets), and nothing is copied from the host inside a capture."""

    def fixed_randint(low, high, size, *, device=None, **_):
        n = math.prod(size)
        return ((torch.arange(n, device=device) * 7 + 3) % (high - low) + low).reshape(size)

    def fixed_randn_like(x, **_):
        return torch.sin(torch.arange(x.numel(), device=x.device, dtype=x.dtype) * 0.37).reshape(x.shape)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(torch, "randint", fixed_randint)
        mp.setattr(torch, "randn_like", fixed_randn_like)
        yield


def _agent_tensors(agent) -> list[torch.Tensor]:
    """Every tensor an update reads or writes: weights, target weights, W, temperature, Adam state."""
    tensors = [*agent.critic.parameters(), *agent.critic_target.parameters(), *agent.actor.parameters(),
               agent.W, agent.log_alpha]
    for opt in agent.optimisers.values():
        for group in opt.param_groups:
            for p in group["params"]:
                tensors += [opt.state[p][k] for k in sorted(opt.state.get(p, {}))]
    return tensors


@pytest.mark.gpu
@needs_cuda
def test_a_graphed_update_matches_the_eager_update_and_survives_a_reload():
    """``cuda_graph``: each of 16 Table 2 updates (both patterns warmed up, recorded and replayed,
    then a state loaded, which drops the graphs, and the same again) equals the eager update from
    the same state and batch, within the CPU-vs-CUDA tolerance.

    Before each update the eager agent's state is copied into the graphed agent's tensors in place
    (the graphs read those addresses), so that each update is compared alone: run apart, the two
    drift, as two eager runs do (cuDNN's backward kernels add in no fixed order); on an H200 the
    actor loss was 1.9e-4 apart after 8 updates. The eager agent's Adam is capturable too, so that
    both run the same optimiser kernels."""
    from dataclasses import replace

    from egosearch.rl.sac_curl import SacCurlAgent

    cfg = load_config("paper", {"device": "cuda"})
    torch.manual_seed(0)
    eager = SacCurlAgent(replace(cfg, cuda_graph=False), 5, device="cuda")  # the paper preset graphs by default
    for opt in eager.optimisers.values():
        for group in opt.param_groups:
            group["capturable"] = True
    graphed = SacCurlAgent(replace(cfg, cuda_graph=True), 5, device="cuda")
    assert eager.graphed is None and graphed.graphed is not None
    graphed.load_state_dict(eager.state_dict())
    replay = _filled_replay(5, torch.device("cuda"), n=300)
    worst_metric = worst_tensor = 0.0
    with exact_fp32(), fixed_device_random():
        for i in range(16):
            if i == 10:  # a checkpoint loaded mid-run: the graphs must not write into stale optimiser state
                assert graphed.graphed.captures == 2  # odd and even updates: two patterns of steps
                # a copy: Adam's load_state_dict keeps a state tensor that is already on the right device
                graphed.load_state_dict(copy.deepcopy(eager.state_dict()))
                assert graphed.graphed.graphs == {}
            source, target = _agent_tensors(eager), _agent_tensors(graphed)
            assert len(source) == len(target)
            with torch.no_grad():
                for a, b in zip(source, target):
                    b.copy_(a)
            before = _weights(eager)
            batch = replay.sample(cfg.batch_size)
            m_eager, m_graph = eager.update(batch), graphed.update(batch)
            for key, a in m_eager.items():
                b = m_graph[key]
                assert math.isnan(a) == math.isnan(b), (i, key)
                if not math.isnan(a):
                    worst_metric = max(worst_metric, abs(a - b) / max(abs(a), 1e-6))
                    assert abs(a - b) <= 1e-4 * max(abs(a), 1e-3), (i, key, a, b)
            w_eager, w_graph = _weights(eager), _weights(graphed)
            for name, start in before.items():
                d_eager, d_graph = w_eager[name] - start, w_graph[name] - start
                err, scale = float((d_graph - d_eager).norm()), float(d_eager.norm())
                worst_tensor = max(worst_tensor, err / scale if scale > 0 else 0.0)
                assert err <= 1e-3 * scale + 1e-7 * math.sqrt(start.numel()), (i, name, err, scale)
    assert graphed.graphed.captures == 2 and len(graphed.graphed.graphs) == 2  # recorded again after the load
    _report("graph_vs_eager", {"updates": 16, "tensors": len(before),
                               "max_relative_metric_difference": worst_metric,
                               "max_relative_update_difference": worst_tensor})


@pytest.mark.gpu
@needs_cuda
def test_a_graphed_update_draws_fresh_random_numbers_at_each_replay():
    """With torch's own generator, a replayed graph must not repeat its crops and noise: each
    replay moves the CUDA generator's offset on, as an eager update does."""
    from dataclasses import replace

    from egosearch.rl.sac_curl import SacCurlAgent

    cfg = replace(load_config("paper", {"device": "cuda"}), cuda_graph=True)
    torch.manual_seed(0)
    agent = SacCurlAgent(cfg, 5, device="cuda")
    replay = _filled_replay(5, torch.device("cuda"), n=300)
    for _ in range(6):
        agent.update(replay.sample(cfg.batch_size))
    assert agent.graphed.captures == 2
    generator = torch.cuda.default_generators[torch.cuda.current_device()]
    offsets = [generator.get_offset()]
    for _ in range(4):
        assert math.isfinite(agent.update(replay.sample(cfg.batch_size))["critic_loss"])
        offsets.append(generator.get_offset())
    assert all(a < b for a, b in zip(offsets, offsets[1:])), offsets


@pytest.mark.gpu
@needs_cuda
def test_cuda_training_resumes_and_its_actor_loads_without_cuda(tmp_path):
    """A short SAC+CURL training on CUDA, stopped and resumed from its checkpoint; its actor file
    is then read by a process that sees no GPU (``torch.load(weights_only=True)``)."""
    cfg = load_config("smoke", {"device": "cuda", "total_env_steps": 300, "checkpoint_every": 150})
    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    torch.use_deterministic_algorithms(True, warn_only=True)
    try:
        train(FAKE_ENV_ID, cfg, whole, progress=False)

        def stop(step: int) -> None:
            if step >= 200:
                raise Interrupt(step)

        with pytest.raises(Interrupt):
            train(FAKE_ENV_ID, cfg, resumed, progress=False, on_step=stop)
        ckpt = torch.load(resumed / "ckpt" / "train_state.ckpt", map_location="cpu", weights_only=True)
        assert ckpt["env_steps"] == 150 and "cuda" in ckpt["rng"]
        seen: list[int] = []
        train(FAKE_ENV_ID, cfg, resumed, progress=False, on_step=seen.append)
    finally:
        torch.use_deterministic_algorithms(False)
    assert seen[0] == 151 and seen[-1] == 300  # resumed at the checkpoint, not started over
    done = check_complete_run(resumed, cfg)
    assert done["machine"]["gpu"] == torch.cuda.get_device_name()
    a = torch.load(whole / "actor.pt", weights_only=True)["state_dict"]
    b = torch.load(resumed / "actor.pt", weights_only=True)["state_dict"]
    same_rows = all(
        [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in read_csv(run / "train.csv")[1]]
        == [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in read_csv(whole / "train.csv")[1]]
        for run in (resumed,))
    _report("resume", {"actor_bitwise_equal": all(torch.equal(a[k], b[k]) for k in a),
                       "actor_max_abs_difference": max(float((a[k].float() - b[k].float()).abs().max()) for k in a),
                       "train_csv_equal_but_timing": same_rows})
    assert all(v.device.type == "cpu" for v in b.values())

    out = os.environ.get("EGOSEARCH_CUDA_ACTOR_OUT")
    if out:
        Path(out).write_bytes((resumed / "actor.pt").read_bytes())
    obs = np.random.default_rng(0)
    depth = obs.integers(0, 256, (5, 100, 100), dtype=np.uint8)
    on_cuda = load_actor_net(torch.load(resumed / "actor.pt", weights_only=True), "cuda")
    with torch.no_grad():
        mu_cuda = on_cuda(torch.from_numpy(depth[None, :, 8:92, 8:92]).float().cuda(),
                          torch.zeros(1, 34, device="cuda"))[0]
    code = textwrap.dedent(f"""
        import json, numpy as np, torch
        from egosearch.rl.sac_curl import load_actor_net
        assert not torch.cuda.is_available()
        state = torch.load({str(resumed / 'actor.pt')!r}, weights_only=True)
        net = load_actor_net(state, "cpu")
        depth = np.random.default_rng(0).integers(0, 256, (5, 100, 100), dtype=np.uint8)
        with torch.no_grad():
            mu = net(torch.from_numpy(depth[None, :, 8:92, 8:92]).float(), torch.zeros(1, 34))[0]
        print(json.dumps(mu[0].tolist()))
    """)
    env = {**os.environ, "CUDA_VISIBLE_DEVICES": ""}
    done_cpu = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert done_cpu.returncode == 0, done_cpu.stderr[-2000:]
    mu_cpu = np.array(json.loads(done_cpu.stdout.strip().splitlines()[-1]))
    assert np.allclose(mu_cpu, mu_cuda[0].cpu().numpy(), atol=1e-2)


@pytest.mark.gpu
@needs_cuda
def test_the_default_preset_imitates_then_fine_tunes_on_cuda_and_its_actor_walks_on_the_cpu(tmp_path):
    """The ``cpu`` preset (the default) learns from the frontier searcher's demonstrations, then fine-tunes
    at every body step: on a machine with CUDA its training runs there (the teacher's episodes, the clone,
    the critic's warm-up, SAC with demonstrations in every batch, the privileged critic), and the actor and
    the start it leaves walk the body env on the CPU as evaluation runs them."""
    from egosearch.cli.acting import policy_factory
    from egosearch.core.staging import START_ACTOR_NAME
    from egosearch.runs.evaluate import evaluate
    from egosearch.sim.scenarios import generate_scenarios

    cfg = load_config("cpu", {"device": "cuda", "total_env_steps": 64, "init_steps": 16, "eval_every": 64,
                              "eval_episodes": 1, "checkpoint_every": 64, "log_every": 32, "curriculum_steps": 32,
                              "demo_episodes": 2, "bc_updates": 8, "critic_warmup_updates": 2, "bc_decay_steps": 32})
    assert not cfg.modular_searcher and cfg.demo_episodes and cfg.critic_privileged_state and cfg.target_memory
    done = train("EgoSearch-v0", cfg, tmp_path, {"layout": "kitchen_living"}, progress=False)
    assert done["env_steps"] == 64 and done["updates"] > 0 and done["machine"]["gpu"] == torch.cuda.get_device_name()
    assert done["imitation"]["bc_updates"] == 8 and done["demonstrations"]["episodes"] == 2
    for name in ("actor.pt", START_ACTOR_NAME):
        state = torch.load(tmp_path / name, weights_only=True)
        assert all(v.device.type == "cpu" for v in state["state_dict"].values())
        make_policy, env_id, _ = policy_factory("actor", str(tmp_path / name), 0)
        assert env_id == "EgoSearchMemory-v0"
        rows = evaluate(env_id, make_policy, generate_scenarios("kitchen_living", "everywhere", 1.05, n=2, seed=4),
                        seed=0)
        assert len(rows) == 2 and all(1 <= r["steps"] <= 100 for r in rows)
    _report("cpu_profile", {"env_steps": done["env_steps"], "updates": done["updates"],
                            "bc_updates": done["imitation"]["bc_updates"]})


def test_an_actor_trained_on_cuda_loads_and_acts_on_this_machine():
    """The stored CUDA-trained actor: ``weights_only=True`` reads it on any machine, its tensors
    are on the CPU, and it acts."""
    state = torch.load(CUDA_ACTOR, weights_only=True)
    assert state["metadata"]["config"]["device"] == "cuda" and state["metadata"]["env_steps"] == 300
    assert all(v.device.type == "cpu" for v in state["state_dict"].values())
    net = load_actor_net(state, "cpu")
    depth = torch.from_numpy(np.random.default_rng(0).integers(0, 256, (1, 5, 84, 84), dtype=np.uint8)).float()
    with torch.no_grad():
        mu, log_std = net(depth, torch.zeros(1, 34))
    assert mu.shape == (1, 5) and torch.isfinite(mu).all() and torch.isfinite(log_std).all()
