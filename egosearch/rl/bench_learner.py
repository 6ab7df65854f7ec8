"""``egosearch bench learner``: the learners' update speed and replay memory (about two minutes).

Every number is a full SAC + CURL update (replay sampling, crops, critic, actor + temperature
every 2nd update, Polyak every 2nd update, CURL), batch 32, 5 x 100 x 100 uint8 frames cropped
to 84 x 84, timed over a stretch of consecutive updates after a warm-up. Updates/s are reported
from the MEDIAN update time; ``*_best`` keys give the fastest update (the least disturbed by
other processes on a shared machine; ``other_load`` is the CPU time other processes used during
the run, in cores).

Keys:
- ``updates_per_s_table2``: the optimised update (``impl="fast"``, CURL's math exactly) at
  Table 2 sizes, all cores;
- ``updates_per_s_table2_shared``: same, with ``share_encoder_forward=True`` (not CURL's math);
- ``updates_per_s_naive``: CURL's update transcribed line by line (``impl="reference"``);
- ``updates_per_s_table2_1thread``: the optimised update at Table 2 sizes on ONE thread;
- ``updates_per_s_cpu_profile``: the ``cpu`` preset's update (its learner, batch and sizes) on its
  thread count (one);
- ``env_steps_per_core_s_cpu_profile``: env steps per core-second of a short real training run of
  the ``cpu`` preset's RL phase (env, acting and updates all in, its imitation phase left out;
  ``cpu_profile_run`` has its details), counted in ``cpu_profile_steps`` ("body steps"; "decisions"
  while the preset was a modular searcher);
- ``*_avx2`` (on a CPU with AVX-512): the cpu preset's rows again in a process whose oneDNN may
  use AVX2 at most (``ONEDNN_MAX_CPU_ISA=AVX2``), for what a CPU without AVX-512 pays;
- ``memory_levers`` (with ``--memory-levers``): the same short training with each memory lever's
  observation beside the plain one, alternating, and each one's cost ratio (:func:`memory_lever_costs`);
- ``replay_gb_100k``: memory of a 100k-transition replay buffer (frames stored once);
- ``torch_threads``, ``device``, ``cpu``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import warnings
from typing import Protocol, runtime_checkable

import numpy as np
import torch

from egosearch.core.allocator import keep_freed_memory
from egosearch.core.machine import cpu_seconds_all, cpu_vector_unit, own_cpu_seconds
from egosearch.envs import observation_kwargs
from egosearch.rl.common import resolve_device
from egosearch.rl.config import DECISIONS, LearnerConfig, load_config
from egosearch.rl.learner_registry import make_agent
from egosearch.rl.replay import ReplayBuffer, replay_gb
from egosearch.rl.train import torch_threads, train
from egosearch.rl.training_aids import DemonstrationSettings, critic_reads_state, demonstration_settings
from egosearch.runs.evaluate import scenario_evaluator
from egosearch.sim.bench_env import OPTIONS_TIMED
from egosearch.sim.env import PRIVILEGED_STATE_DIM
from egosearch.sim.home_pool import curve_homes


@runtime_checkable
class TrainingRun(Protocol):
    """What :func:`gpu_check` reads of the training it times: a variant resolved at a learner preset
    (:class:`egosearch.variants.ResolvedVariant` is one). The CLI resolves it, and rl/ names only what
    it reads, so that it never imports the variants layer above it."""

    @property
    def name(self) -> str: ...

    @property
    def config(self) -> LearnerConfig: ...

    @property
    def env_id(self) -> str: ...

    @property
    def train_env(self) -> dict: ...


def _filled_replay(action_dim: int, device: torch.device, n: int = 600, seed: int = 0, size: int = 100,
                  state_dim: int = 0) -> ReplayBuffer:
    rng = np.random.default_rng(seed)
    buf = ReplayBuffer(n, size, 5, 30, 4, action_dim, device=device, seed=seed, state_dim=state_dim)
    frames = np.repeat(rng.integers(0, 256, (1, size, size), dtype=np.uint8), 5, axis=0)
    obs = {"depth": frames, "mask": np.zeros(30, np.float32), "proprio": np.zeros(4, np.float32),
           "state": np.zeros(state_dim, np.float32)}
    for t in range(n):
        frames = np.concatenate([frames[1:], rng.integers(0, 256, (1, size, size), dtype=np.uint8)])
        nxt = {"depth": frames, "mask": rng.normal(size=30).astype(np.float32),
               "proprio": rng.normal(size=4).astype(np.float32), "state": rng.normal(size=state_dim).astype(np.float32)}
        end = (t + 1) % 100 == 0
        buf.add(obs, rng.uniform(-1, 1, action_dim), float(rng.normal()), nxt, False, end)
        obs = nxt if not end else {**nxt, "depth": np.repeat(frames[-1:], 5, axis=0)}
    return buf


def time_updates(preset: str = "paper", overrides: dict | None = None, agent_options: dict | None = None,
                 threads: int | None = None, warmup: int = 3, updates: int = 10,
                 action_dim: int = 5) -> dict[str, float]:
    """Median and best seconds per full update (sampling included); ``agent_options``: keyword arguments
    of the preset's learner's own constructor (SAC+CURL's ``impl``)."""
    before = torch.get_num_threads()
    if threads:
        torch.set_num_threads(threads)
    try:
        cfg = load_config(preset, {**(overrides or {}), "device": "auto"})
        torch.manual_seed(0)
        device = resolve_device(cfg.device)
        state_dim = PRIVILEGED_STATE_DIM if critic_reads_state(cfg) else 0
        agent = make_agent(cfg, action_dim, 30, 4, device, state_dim, **(agent_options or {}))
        replay = _filled_replay(action_dim, device, size=agent.replay_image_size, state_dim=state_dim)
        sync = torch.cuda.synchronize if device.type == "cuda" else (lambda: None)
        for _ in range(warmup):
            agent.update(replay.sample(cfg.batch_size))
        sync()
        times = []
        for _ in range(updates):
            t0 = time.perf_counter()
            agent.update(replay.sample(cfg.batch_size))
            sync()
            times.append(time.perf_counter() - t0)
        return {"median_s": float(np.median(times)), "best_s": float(np.min(times))}
    finally:
        torch.set_num_threads(before)


def bench_stacked(seeds: int = 3, preset: str = "cpu", warmup: int = 3, rounds: int = 15,
                  overrides: dict | None = None) -> dict:
    """``egosearch bench stacked``: the update of ``seeds`` seeds stacked as one model
    (:mod:`egosearch.rl.stacked`) against the same seeds' separate updates one after the other, at
    ``preset``'s learner, batch and sizes and its thread count, each seed sampling its own replay. The
    two alternate round by round (a round: one update of every seed), so that a shared machine's load
    falls on both alike; the medians and the fastest rounds are reported. The critic warm-up is off
    (``critic_warmup_updates`` 0) so that every update is a whole one, actor and temperature included."""
    from egosearch.rl.stacked import SeedStreams, stack_agents

    cfg = load_config(preset, {**(overrides or {}), "device": "auto"})
    if isinstance(cfg, DemonstrationSettings):
        cfg = load_config(preset, {"critic_warmup_updates": 0, **(overrides or {}), "device": "auto"})
    before = torch.get_num_threads()
    torch.set_num_threads(torch_threads(cfg.num_threads))
    try:
        device = resolve_device(cfg.device)
        state_dim = PRIVILEGED_STATE_DIM if critic_reads_state(cfg) else 0
        streams, separate, members, replays = SeedStreams(device), [], [], []
        for seed in range(seeds):
            for agents in (separate, members):
                torch.manual_seed(seed)
                agents.append(make_agent(cfg, 5, 30, 4, device, state_dim))
            streams.capture()
            replays.append(_filled_replay(5, device, seed=seed, size=separate[-1].replay_image_size,
                                          state_dim=state_dim))
        stack = stack_agents(members, streams)
        sync = torch.cuda.synchronize if device.type == "cuda" else (lambda: None)
        times: dict[str, list[float]] = {"separate": [], "stacked": []}
        for i in range(warmup + rounds):
            t0 = time.perf_counter()
            for agent, replay in zip(separate, replays):
                agent.update(replay.sample(cfg.batch_size))
            sync()
            t1 = time.perf_counter()
            stack.update([replay.sample(cfg.batch_size) for replay in replays])
            sync()
            t2 = time.perf_counter()
            if i >= warmup:
                times["separate"].append(t1 - t0)
                times["stacked"].append(t2 - t1)
        median = {k: float(np.median(v)) for k, v in times.items()}
        return {"preset": preset, "algorithm": cfg.algorithm, "seeds": seeds, "batch_size": cfg.batch_size,
                "torch_threads": torch.get_num_threads(), "device": str(device), "rounds": rounds,
                "separate_round_s": round(median["separate"], 4), "stacked_round_s": round(median["stacked"], 4),
                "separate_round_s_best": round(min(times["separate"]), 4),
                "stacked_round_s_best": round(min(times["stacked"]), 4),
                "stacked_speedup": round(median["separate"] / median["stacked"], 2)}
    finally:
        torch.set_num_threads(before)


def training_throughput(preset: str = "cpu", env_steps: int = 3000, overrides: dict | None = None) -> dict:
    """Env steps per core-second of a short REAL training run of ``preset`` (head-on,
    kitchen_living, everywhere): env stepping, acting and updates all in, its own evaluations
    left out. Core-seconds are this process's CPU time (user + system), so the figure holds on
    a busy machine too. Warm-up is cut to a tenth of the run so that updates weigh as in a long run
    (unless ``overrides`` set ``init_steps``: PPO has no warm-up)."""


    overrides = overrides or {}
    full = load_config(preset, overrides)
    short = {"total_env_steps": env_steps, "init_steps": overrides.get("init_steps", max(1, env_steps // 10)),
             "eval_every": env_steps, "checkpoint_every": env_steps, "log_every": env_steps}
    if demonstration_settings(full).demo_episodes:
        # A preset that learns from the classical searcher first: the stored rates count its RL phase
        # alone (egosearch.cost.rates), so this run does too. A few demonstrations fill the replay's demo
        # half (an update costs the same whatever they hold), the cloning is cut to a token, the critic's
        # warm-up scaled to the run's share of a whole training; their CPU time is taken off below.
        short.update(demo_episodes=max(2, full.num_envs), bc_updates=min(full.bc_updates, 20), dagger_rounds=0,
                     critic_warmup_updates=round(full.critic_warmup_updates * env_steps / full.total_env_steps))
    cfg = load_config(preset, {**overrides, **short})
    with tempfile.TemporaryDirectory() as out:
        cpu0, wall0 = time.process_time(), time.perf_counter()
        summary = train("EgoSearch-v0", cfg, out, env_kwargs={"layout": "kitchen_living", "placement": "everywhere"},
                        evaluate_fn=lambda policy: {}, progress=False, variant="bench")
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    outside_rl = (summary.get("demonstrations", {}).get("cpu_s", 0.0)
                  + summary.get("imitation", {}).get("cpu_s", 0.0))
    rl_cpu = cpu - outside_rl
    return {"env_steps": env_steps, "core_s": round(rl_cpu, 2), "wall_s": round(wall, 2),
            "core_s_before_rl": round(outside_rl, 2),
            "env_steps_per_core_s": round(env_steps / rl_cpu, 1), "threads": torch_threads(cfg.num_threads)}


def cpu_preset_run_steps(quick: bool = False) -> int:
    """Env steps of the benchmark's real cpu-preset training: about a minute of it (about 4,000 body steps;
    a modular searcher's decision walks several, so fewer decisions), or a few seconds with ``quick``."""
    cfg = load_config("cpu", {})
    if cfg.env_step_unit == DECISIONS:
        return 8 * cfg.num_envs if quick else 600
    return 400 * cfg.num_envs if quick else 4000


def bench_learner(quick: bool = False, cpu_profile_run: bool = True, memory_levers: bool = False) -> dict:
    """Benchmarks of the learner (see the module docstring); ``quick`` for tests (~seconds);
    ``cpu_profile_run=False`` leaves out the cpu preset's training run (a GPU check times a real
    paper-preset training instead); ``memory_levers`` adds :func:`memory_lever_costs` under
    ``"memory_levers"`` (two rounds of three short trainings more)."""
    keep_freed_memory()  # as a training does, so that its updates cost here what they cost there
    torch.set_num_threads(torch_threads(0))
    n = 3 if quick else 10
    cpu0, own0, wall0 = cpu_seconds_all(), own_cpu_seconds(), time.perf_counter()
    eager = {"cuda_graph": False}  # the paper preset records its update on a GPU; these rows time it launched eagerly
    runs = {
        "table2": time_updates("paper", eager, updates=n),
        "table2_shared": time_updates("paper", {**eager, "share_encoder_forward": True}, updates=n),
        "naive": time_updates("paper", agent_options={"impl": "reference"}, warmup=2, updates=max(3, n // 2)),
        "table2_1thread": time_updates("paper", eager, threads=1, updates=max(3, n // 2)),
    }
    if torch.cuda.is_available():  # the captured update: 4 eager warm-up updates and 2 captures first
        runs["table2_graph"] = time_updates("paper", {"cuda_graph": True}, warmup=8, updates=n)
    cpu_cfg = load_config("cpu", {})
    cpu_threads = torch_threads(cpu_cfg.num_threads)
    # "cpu_profile": the record keys keep the word the stored benchmarks were written with (core.preset_word)
    runs["cpu_profile"] = time_updates("cpu", threads=cpu_threads, updates=2 * n)
    throughput = training_throughput("cpu", env_steps=cpu_preset_run_steps(quick)) if cpu_profile_run else None
    # oneDNN picks its kernels once per process, so the AVX2-limited rows need a process of their own
    avx2 = (_avx2_limited_cpu_profile(quick, cpu_profile_run)
            if cpu_vector_unit() == "AVX-512" and resolve_device("auto").type == "cpu" else None)
    levers = memory_lever_costs(quick) if memory_levers else None
    wall = time.perf_counter() - wall0
    cpu1 = cpu_seconds_all()
    own = own_cpu_seconds() - own0
    result: dict = {}
    for key, r in runs.items():
        result[f"updates_per_s_{key}"] = round(1.0 / r["median_s"], 2)
        result[f"updates_per_s_{key}_best"] = round(1.0 / r["best_s"], 2)
    result["speedup_vs_naive"] = round(result["updates_per_s_table2"] / result["updates_per_s_naive"], 2)
    if "updates_per_s_table2_graph" in result:
        result["speedup_graph_vs_table2"] = round(result["updates_per_s_table2_graph"]
                                                  / result["updates_per_s_table2"], 2)
    if throughput is not None:
        result["env_steps_per_core_s_cpu_profile"] = throughput["env_steps_per_core_s"]
        result["cpu_profile_steps"] = cpu_cfg.env_step_unit  # a modular searcher's env step is a decision
        result["cpu_profile_run"] = throughput
    if avx2 is not None:
        result.update({f"{key}_avx2": value for key, value in avx2.items()})
    if levers is not None:
        result["memory_levers"] = levers
    result["replay_gb_100k"] = round(replay_gb(100_000), 3)
    result["torch_threads"] = torch.get_num_threads()
    result["cpu_profile_threads"] = torch_threads(cpu_cfg.num_threads)
    result["device"] = str(resolve_device("auto"))
    result["cpu"] = platform.processor() or platform.machine()
    if cpu0 is not None and cpu1 is not None:
        result["other_load"] = round(max(0.0, (cpu1 - cpu0) - own) / wall, 2) if wall > 0 else None
    result["bench_s"] = round(wall, 1)
    return result


MEMORY_LEVER_OPTIONS = OPTIONS_TIMED
"""The observation options of the memory levers (issue "the student remembers where it has been") whose
training cost ``bench learner --memory-levers`` measures beside the plain observation's: those whose env step
``bench env`` times, so that the two records name the same options."""


def memory_lever_costs(quick: bool = False, rounds: int = 2) -> dict:
    """What each memory lever's observation costs a training: the cpu preset's short real training
    (:func:`training_throughput`: env, acting and updates, in this process's core-seconds) with the plain
    observation and with each of :data:`MEMORY_LEVER_OPTIONS`, alternating round by round, so that a shared
    machine's load falls on all of them alike. Reports each one's env steps per core-second (the median of
    its rounds) and, for each option, its core-seconds per env step against the plain one's
    (``<option>_cost_ratio``: 1.4 means a training's RL phase costs 40 % more)."""
    keep_freed_memory()
    steps = cpu_preset_run_steps(quick)
    rates: dict[str, list[float]] = {name: [] for name in ("plain", *MEMORY_LEVER_OPTIONS)}
    for _ in range(rounds):
        for name in rates:
            overrides = {} if name == "plain" else {name: True}
            rates[name].append(training_throughput("cpu", env_steps=steps, overrides=overrides)["env_steps_per_core_s"])
    result: dict = {"env_steps": steps, "rounds": rounds}
    for name, values in rates.items():
        result[f"env_steps_per_core_s_{name}"] = round(float(np.median(values)), 1)
        result[f"env_steps_per_core_s_{name}_rounds"] = values
    for name in MEMORY_LEVER_OPTIONS:
        result[f"{name}_cost_ratio"] = round(result["env_steps_per_core_s_plain"]
                                             / result[f"env_steps_per_core_s_{name}"], 2)
    return result


def cpu_preset_rows(quick: bool, cpu_profile_run: bool) -> dict:
    """The cpu preset's update rate and, with ``cpu_profile_run``, its short training's env steps per
    core-second, as :func:`bench_learner` names them (without a suffix)."""
    keep_freed_memory()
    n = 3 if quick else 10
    threads = torch_threads(load_config("cpu", {}).num_threads)
    r = time_updates("cpu", threads=threads, updates=2 * n)
    rows = {"updates_per_s_cpu_profile": round(1.0 / r["median_s"], 2)}
    if cpu_profile_run:
        rows["env_steps_per_core_s_cpu_profile"] = training_throughput(
            "cpu", env_steps=cpu_preset_run_steps(quick))["env_steps_per_core_s"]
    return rows


def _avx2_limited_cpu_profile(quick: bool, cpu_profile_run: bool) -> dict | None:
    """:func:`cpu_preset_rows` in a child process whose oneDNN may use AVX2 at most
    (``ONEDNN_MAX_CPU_ISA=AVX2``): what the same update costs on a CPU without AVX-512. None if the
    child fails (its error is printed)."""
    code = ("import json, sys; from egosearch.rl.bench_learner import cpu_preset_rows; "
            f"print(json.dumps(cpu_preset_rows({quick!r}, {cpu_profile_run!r})))")
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           env={**os.environ, "ONEDNN_MAX_CPU_ISA": "AVX2"})
    if child.returncode != 0:
        print(f"the AVX2-limited rows failed: {child.stderr.strip().splitlines()[-1:]}", flush=True)
        return None
    return json.loads(child.stdout.strip().splitlines()[-1])


def host_syncs_per_update(preset: str = "paper", updates: int = 6, overrides: dict | None = None) -> float | None:
    """Host-device synchronisations per full update (replay sampling excluded), counted with
    torch's CUDA sync debug mode; None off CUDA. The update's metrics are read back in ONE sync
    (``metric_values``); anything above 1 is a round trip inside the update. The first 6 updates
    are left out (a captured update warms up and records its graphs in them)."""


    if not torch.cuda.is_available():
        return None
    cfg = load_config(preset, {**(overrides or {}), "device": "cuda"})
    torch.manual_seed(0)
    state_dim = PRIVILEGED_STATE_DIM if critic_reads_state(cfg) else 0
    agent = make_agent(cfg, 5, 30, 4, torch.device("cuda"), state_dim)
    replay = _filled_replay(5, torch.device("cuda"), size=agent.replay_image_size, state_dim=state_dim)
    batches = [replay.sample(cfg.batch_size) for _ in range(updates + 6)]
    for batch in batches[:6]:
        agent.update(batch)
    torch.cuda.synchronize()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        torch.cuda.set_sync_debug_mode("warn")
        try:
            for batch in batches[6:]:
                agent.update(batch)
        finally:
            torch.cuda.set_sync_debug_mode("default")
    syncs = [w for w in caught if "synchroniz" in str(w.message).lower()]
    return round(len(syncs) / updates, 2)


def gpu_check(seconds: float, out_dir: str, run: TrainingRun, overrides: dict | None = None,
              baseline_seconds: float = 0.0) -> dict:
    """The paper preset on this machine's accelerator: the learner benchmarks, then a real training
    of ``run`` (a variant resolved at the paper preset, :func:`egosearch.variants.resolve_variant`;
    its curve evaluations included) for ``seconds`` of wall time, stopped with a checkpoint
    (``egosearch train --max-wall-s`` resumes it). The run's curve.csv, train.csv and config.json are
    left in ``out_dir``; ``overrides`` are the config fields the caller resolved ``run`` with, for the
    record. With ``baseline_seconds`` the same training with the update launched eagerly
    (``cuda_graph`` false) runs that long in ``out_dir/baseline``, so that both rates come from one
    machine."""
    result = {"learner": bench_learner(cpu_profile_run=False),
              "host_syncs_per_update_table2": host_syncs_per_update("paper", overrides={"cuda_graph": False}),
              "host_syncs_per_update_cpu_profile": host_syncs_per_update("cpu")}
    if torch.cuda.is_available():
        result["host_syncs_per_update_table2_graph"] = host_syncs_per_update("paper", overrides={"cuda_graph": True})
    overrides = dict(overrides or {})
    result["training"] = _timed_training(seconds, out_dir, run, run.config, overrides)
    if baseline_seconds > 0:
        eager = dataclasses.replace(run.config, cuda_graph=False).validate()
        result["training_baseline"] = _timed_training(baseline_seconds, os.path.join(out_dir, "baseline"), run, eager,
                                                      {**overrides, "cuda_graph": False})
    return result


def _timed_training(seconds: float, out_dir: str, run: TrainingRun, cfg: LearnerConfig, overrides: dict) -> dict:
    """A training of ``run`` with ``cfg`` (its config, or that config launched eagerly) for ``seconds``, and
    its rates read back from its CSVs."""
    env_id = run.env_id
    evaluator = scenario_evaluator(env_id, curve_homes(run.train_env), run.train_env["placement"],
                                   n=cfg.eval_episodes, env_kwargs=observation_kwargs(cfg.to_dict()))
    eval_s: list[float] = []

    def timed_evaluator(policy) -> dict:
        t0 = time.perf_counter()
        row = evaluator(policy)
        eval_s.append(time.perf_counter() - t0)
        return row

    wall0 = time.perf_counter()
    try:
        summary = train(env_id, cfg, out_dir, env_kwargs=run.train_env, evaluate_fn=timed_evaluator,
                        variant=run.name, progress=False, max_wall_s=seconds)
    finally:
        evaluator.close()
    wall = time.perf_counter() - wall0
    with open(os.path.join(out_dir, "train.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out_dir, "curve.csv")) as f:
        curve = list(csv.DictReader(f))
    rates = [(float(r["steps_per_s"]), float(r["updates_per_s"])) for r in rows[1:]]  # the first row holds warm-up
    return {
        "variant": run.name, "seed": cfg.seed, "overrides": overrides, "cuda_graph": cfg.cuda_graph,
        "env_steps": summary["env_steps"], "updates": summary["updates"],
        "wall_s": round(wall, 1), "curve_rows": len(curve),
        "env_steps_per_s_overall": round(summary["env_steps"] / wall, 1),
        "env_steps_per_s_updating": round(float(np.median([s for s, _ in rates])), 1) if rates else None,
        "updates_per_s_updating": round(float(np.median([u for _, u in rates])), 1) if rates else None,
        "train_rows_used": len(rates), "total_env_steps": cfg.total_env_steps,
        "curve_evaluations": len(eval_s),
        "curve_evaluation_s_mean": round(float(np.mean(eval_s)), 1) if eval_s else None,
        "eval_every": cfg.eval_every, "eval_episodes": cfg.eval_episodes,
    }
