"""Training loop on the fake env: outputs, kill-and-resume, bad checkpoints, and learning."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from egosearch.core.machine import cpu_model
from egosearch.core.staging import CHECKPOINT_NAME
from egosearch.rl.actor import ActorPolicy
from egosearch.rl.common import AgentStateError
from egosearch.rl.config import load_config
from egosearch.rl.run_files import CheckpointError
from egosearch.rl.train import CURVE_COLUMNS, TRAIN_COLUMNS, default_evaluator, train

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))
from test_rl_fake_env import FAKE_ENV_ID, FAKE_NOHEAD_ENV_ID, register_fake_envs  # noqa: E402

register_fake_envs()
SMOKE = {"device": "cpu", "num_threads": 1}


def read_csv(path: Path) -> tuple[list[str], list[dict]]:
    with open(path) as f:
        reader = csv.DictReader(f)
        return list(reader.fieldnames), list(reader)


class Interrupt(Exception):
    pass


def interrupt_at(n: int):
    def hook(step: int) -> None:
        if step == n:
            raise Interrupt(step)
    return hook


TIMING_COLUMNS = {"steps_per_s", "updates_per_s", "wall_s"}
"""The columns of train.csv and curve.csv that a resumed run cannot reproduce."""


def train_whole_and_resumed(cfg, root: Path, stop_after: int, after_stop=None,
                            logs: tuple[str, ...] = ("train.csv", "curve.csv")) -> tuple[Path, Path]:
    """Train ``cfg`` on the fake env once whole and once stopped after ``stop_after`` env steps and
    rerun, and check that the two runs are one: the same actor weights to the bit, and the same
    ``logs`` but for their timing columns. ``after_stop(resumed_dir)`` looks at the stopped run
    before it resumes. Returns the two run directories."""
    whole, resumed = root / "whole", root / "resumed"

    def stop(step: int) -> None:
        if step >= stop_after:
            raise Interrupt(step)

    train(FAKE_ENV_ID, cfg, whole, progress=False)
    with pytest.raises(Interrupt):
        train(FAKE_ENV_ID, cfg, resumed, progress=False, on_step=stop)
    if after_stop is not None:
        after_stop(resumed)
    train(FAKE_ENV_ID, cfg, resumed, progress=False)
    a = torch.load(whole / "actor.pt", weights_only=True)["state_dict"]
    b = torch.load(resumed / "actor.pt", weights_only=True)["state_dict"]
    assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    for name in logs:
        rows = [[{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in read_csv(run / name)[1]]
                for run in (whole, resumed)]
        assert rows[0] == rows[1], name
    return whole, resumed


def check_complete_run(out: Path, cfg, checkpoint_kept: bool = False) -> dict:
    columns, rows = read_csv(out / "curve.csv")
    assert tuple(columns) == CURVE_COLUMNS
    steps = [int(r["env_steps"]) for r in rows]
    expected = sorted({0, cfg.total_env_steps} | set(range(cfg.eval_every, cfg.total_env_steps + 1, cfg.eval_every)))
    assert steps == expected, steps
    columns, rows = read_csv(out / "train.csv")
    assert tuple(columns) == TRAIN_COLUMNS
    assert [int(r["env_steps"]) for r in rows] == list(range(cfg.log_every, cfg.total_env_steps + 1, cfg.log_every))
    done = json.loads((out / "done.json").read_text())
    assert done["env_steps"] == cfg.total_env_steps
    assert done["updates"] == cfg.total_env_steps - cfg.init_steps + 1  # an update after every step >= init_steps
    # core time is read against the machine that spent it (the budget study's `trained on`)
    assert {k: done["machine"][k] for k in ("cpu", "cores")} == {"cpu": cpu_model(), "cores": os.cpu_count()}
    # deleted at the end unless asked for (it holds the replay buffer)
    assert (out / CHECKPOINT_NAME).exists() == checkpoint_kept
    assert not list(out.glob("**/.tmp*"))  # no temp file left behind, even after a kill -9
    return done


def test_smoke_training_outputs(tmp_path):
    cfg = load_config("smoke", SMOKE)
    summary = train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False)
    done = check_complete_run(tmp_path, cfg)
    assert summary == done
    assert json.loads((tmp_path / "config.json").read_text())["config"] == cfg.to_dict()
    # actor.pt: actor-only weights + metadata, readable with weights_only=True
    state = torch.load(tmp_path / "actor.pt", weights_only=True)
    assert state["metadata"]["variant"] == "head-on" and state["metadata"]["env_id"] == FAKE_ENV_ID
    assert state["metadata"]["config"] == cfg.to_dict()
    policy = ActorPolicy(tmp_path / "actor.pt")
    policy.reset(seed=3)
    import gymnasium

    env = gymnasium.make(FAKE_ENV_ID)
    obs, _ = env.reset(seed=0)
    a1, a2 = policy.act(obs), policy.act(obs)
    assert a1.shape == (5,) and a1.dtype == np.float32 and np.array_equal(a1, a2)  # deterministic
    # a finished run is not trained again
    mtime = (tmp_path / "actor.pt").stat().st_mtime_ns
    assert train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False) == done
    assert (tmp_path / "actor.pt").stat().st_mtime_ns == mtime


def test_head_off_variant_and_a_custom_evaluator(tmp_path):
    cfg = load_config("smoke", {**SMOKE, "total_env_steps": 150, "eval_every": 50})
    calls = []

    def evaluate_fn(policy):
        policy.reset(seed=0)
        calls.append(policy.act({"depth": np.zeros((5, 100, 100), np.uint8), "mask": np.zeros(30, np.float32),
                                 "proprio": np.zeros(4, np.float32)}))
        return {"success_rate": 0.5, "spl": 0.25, "episode_return": -1.0}

    train(FAKE_NOHEAD_ENV_ID, cfg, tmp_path, evaluate_fn=evaluate_fn, progress=False)
    assert ActorPolicy(tmp_path / "actor.pt").action_dim == 3
    assert len(calls) == 4 and calls[0].shape == (3,)  # steps 0, 50, 100, 150
    _, rows = read_csv(tmp_path / "curve.csv")
    assert [float(r["spl"]) for r in rows] == [0.25] * 4


def test_interrupt_and_resume_continues_without_duplicate_rows(tmp_path):
    cfg = load_config("smoke", SMOKE)  # checkpoints at 150 and 300; eval at 0, 150, 300
    with pytest.raises(Interrupt):
        train(FAKE_ENV_ID, cfg, tmp_path, progress=False, on_step=interrupt_at(230))
    # rows after the checkpoint at 150 exist on disk (train.csv at 200) ...
    _, rows = read_csv(tmp_path / "train.csv")
    assert [int(r["env_steps"]) for r in rows][-1] == 200
    ckpt = torch.load(tmp_path / CHECKPOINT_NAME, weights_only=True)
    assert ckpt["env_steps"] == 150 and ckpt["csv_rows"] == {"curve": 2, "train": 3, "curve_episodes": 0}
    # ... and the rerun drops them, resumes at 150 and ends with exactly one row per step
    seen = []
    train(FAKE_ENV_ID, cfg, tmp_path, progress=False, on_step=seen.append)
    assert seen[0] == 151 and seen[-1] == 300
    check_complete_run(tmp_path, cfg)


def test_kill_minus_9_and_rerun(tmp_path):
    cfg = load_config("smoke", {**SMOKE, "checkpoint_every": 50, "total_env_steps": 400})
    script = textwrap.dedent(f"""
        import sys, time
        sys.path.insert(0, {str(TESTS)!r})
        from test_rl_fake_env import register_fake_envs, FAKE_ENV_ID
        from egosearch.rl.config import LearnerConfig
        from egosearch.rl.train import train
        register_fake_envs()
        cfg = LearnerConfig.from_dict({cfg.to_dict()!r})
        train(FAKE_ENV_ID, cfg, {str(tmp_path)!r}, progress=False, on_step=lambda s: time.sleep(0.01))
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    ckpt = tmp_path / CHECKPOINT_NAME
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if ckpt.exists() and torch.load(ckpt, weights_only=True)["env_steps"] >= 150:
            break
        time.sleep(0.2)
    assert proc.poll() is None, proc.stderr.read().decode()[-2000:]
    time.sleep(0.37)  # somewhere mid-step / mid-write
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    assert not (tmp_path / "done.json").exists()
    train(FAKE_ENV_ID, cfg, tmp_path, progress=False)
    check_complete_run(tmp_path, cfg)


def test_corrupted_or_foreign_checkpoint_is_a_clear_error(tmp_path):
    cfg = load_config("smoke", SMOKE)
    with pytest.raises(Interrupt):
        train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False, on_step=interrupt_at(160))
    ckpt = tmp_path / CHECKPOINT_NAME
    good = ckpt.read_bytes()
    listing = sorted(p.name for p in tmp_path.iterdir())
    curve = (tmp_path / "curve.csv").read_text()

    # another variant or another config: refused, nothing written
    with pytest.raises(CheckpointError, match="variant='head-on'") as err:
        train(FAKE_ENV_ID, cfg, tmp_path, variant="head-off", progress=False)
    assert "\n" not in str(err.value)
    with pytest.raises(CheckpointError, match="different config: batch_size=32 \\(now 16\\)"):
        train(FAKE_ENV_ID, load_config("smoke", {**SMOKE, "batch_size": 16}), tmp_path,
              variant="head-on", progress=False)
    with pytest.raises(CheckpointError, match="env_kwargs"):
        train(FAKE_ENV_ID, cfg, tmp_path, env_kwargs={"max_steps": 20}, variant="head-on", progress=False)
    # a truncated (corrupted) file
    ckpt.write_bytes(good[: len(good) // 2])
    with pytest.raises(CheckpointError, match="cannot read checkpoint") as err:
        train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False)
    assert "\n" not in str(err.value)
    ckpt.write_bytes(b"garbage")
    with pytest.raises(CheckpointError, match="cannot read checkpoint"):
        train(FAKE_ENV_ID, cfg, tmp_path, variant="head-on", progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == listing
    assert (tmp_path / "curve.csv").read_text() == curve
    assert not (tmp_path / "actor.pt").exists() and not (tmp_path / "done.json").exists()

    ckpt.write_bytes(good)  # restored: resumes fine, and implementation-only fields may change
    resumed = load_config("smoke", {**SMOKE, "keep_checkpoint": True})
    train(FAKE_ENV_ID, resumed, tmp_path, variant="head-on", progress=False)
    check_complete_run(tmp_path, cfg, checkpoint_kept=True)


def test_bad_actor_file_is_a_clear_error(tmp_path):
    bad = tmp_path / "actor.pt"
    bad.write_bytes(b"\x00" * 100)
    with pytest.raises(AgentStateError, match="is not an egosearch actor file") as err:
        ActorPolicy(bad)
    assert "weights_only" not in str(err.value) and "\n" not in str(err.value)
    text = tmp_path / "README.md"
    text.write_text("# not weights\n")
    with pytest.raises(AgentStateError, match=r"README.md is not an egosearch actor file; an actor file is"):
        ActorPolicy(text)
    torch.save({"a": 1}, bad)
    with pytest.raises(AgentStateError, match="is not an egosearch actor file"):
        ActorPolicy(bad)
    torch.save({"format": "something-else"}, bad)
    with pytest.raises(AgentStateError, match="not an actor file"):
        ActorPolicy(bad)


LEARNERS = {
    # ~25 s on one core: 500 updates of the smoke-sized learner (100 -> 84 crops, K = 5, CURL)
    "sac_curl": {"total_env_steps": 700},
    # the cpu preset's learner at smoke sizes: 4 lockstep envs, 3-step returns, 500 updates of 64
    "sac_drq": {"algorithm": "sac_drq", "obs_downsample": 2, "encoder_num_layers": 2, "encoder_stride2_layers": 2,
                "aug_pad": 2, "num_envs": 4, "n_step": 3, "batch_size": 64, "update_every": 2,
                "actor_update_freq": 1, "critic_target_update_freq": 1, "total_env_steps": 1200},
}


@pytest.mark.parametrize("learner", list(LEARNERS))
def test_learning_beats_random_on_the_fake_env(tmp_path, learner):
    from egosearch.searchers.policies import RandomPolicy

    steps = LEARNERS[learner]["total_env_steps"]
    cfg = load_config("smoke", {**SMOKE, **LEARNERS[learner], "init_steps": 200, "eval_every": steps,
                                "checkpoint_every": steps, "log_every": 100, "eval_episodes": 5, "seed": 0})
    train(FAKE_ENV_ID, cfg, tmp_path, progress=False)
    evaluate = default_evaluator(FAKE_ENV_ID, {}, episodes=20)
    trained = evaluate(ActorPolicy(tmp_path / "actor.pt"))
    random = evaluate(RandomPolicy(5, seed=0))
    evaluate.close()
    assert trained["success_rate"] >= 0.8, trained
    assert random["success_rate"] <= 0.2, random
    assert trained["episode_return"] > random["episode_return"] + 10


def test_target_memory_trains_the_policy_in_the_memory_env_of_its_head(tmp_path):
    """The config field and a variant naming the *Memory-v0 id are one observation: a head-off run with
    target_memory acts, and is checked, in EgoSearchNoHeadMemory-v0, whose mask is wider."""
    from egosearch.envs import env_space_dims, observed_env_id
    from egosearch.sim.body_envs import ENV_IDS

    assert observed_env_id("EgoSearch-v0", True) == "EgoSearchMemory-v0"
    assert observed_env_id("EgoSearchNoHead-v0", True) == "EgoSearchNoHeadMemory-v0"
    assert observed_env_id("EgoSearchMap-v0", True) == "EgoSearchMap-v0"  # already remembers
    assert all(observed_env_id(env_id, False) == env_id for env_id in ENV_IDS)

    cfg = load_config("smoke", {**SMOKE, "target_memory": True, "total_env_steps": 120, "init_steps": 100,
                                "eval_every": 120, "eval_episodes": 1, "checkpoint_every": 120})
    train("EgoSearchNoHead-v0", cfg, tmp_path, env_kwargs={"layout": "kitchen_living", "placement": "everywhere"},
          progress=False)
    actor = ActorPolicy(tmp_path / "actor.pt")
    assert actor.trained_env_id() == "EgoSearchNoHeadMemory-v0"
    assert env_space_dims("EgoSearchNoHeadMemory-v0")["mask"] > env_space_dims("EgoSearchNoHead-v0")["mask"]
    actor.check_env("EgoSearchNoHeadMemory-v0")
    with pytest.raises(AgentStateError, match="was trained in EgoSearchNoHeadMemory-v0"):
        actor.check_env("EgoSearchNoHead-v0")


def test_a_run_stopped_at_its_wall_time_limit_checkpoints_and_resumes(tmp_path):
    """``max_wall_s``: the run stops at the first env step past the limit with a checkpoint there and
    no actor; the same call without a limit resumes from that step."""
    cfg = load_config("smoke", {**SMOKE, "total_env_steps": 200, "eval_every": 100, "checkpoint_every": 100})
    stopped = train(FAKE_ENV_ID, cfg, tmp_path, progress=False, max_wall_s=1e-9)
    assert stopped["stopped"] and stopped["env_steps"] == 1 and stopped["updates"] == 0
    assert (tmp_path / CHECKPOINT_NAME).exists() and not (tmp_path / "actor.pt").exists()
    assert not (tmp_path / "done.json").exists()
    seen: list[int] = []
    done = train(FAKE_ENV_ID, cfg, tmp_path, progress=False, on_step=seen.append)
    assert seen[0] == 2 and done["env_steps"] == 200 and "stopped" not in done



def test_the_vector_unit_is_read_from_the_cpu_flags(tmp_path):
    from egosearch.core.machine import cpu_vector_unit

    info = tmp_path / "cpuinfo"
    for flags, unit in (("fpu sse2 avx avx2 avx512f avx512bw", "AVX-512"), ("fpu sse2 avx avx2 fma", "AVX2"),
                        ("fpu sse2 avx", "AVX"), ("fpu sse2", "no AVX")):
        info.write_text(f"processor\t: 0\nmodel name\t: AMD EPYC\nflags\t\t: {flags}\n")
        assert cpu_vector_unit(info) == unit
    info.write_text("processor\t: 0\n")  # no flags line (not x86, say)
    assert cpu_vector_unit(info) is None
    assert cpu_vector_unit(tmp_path / "absent") is None
