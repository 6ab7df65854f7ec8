"""Learning from the classical searcher: behaviour cloning, the critic's warm-up, the behaviour-cloning
term on the actor, and a training that holds demonstrations (half batches, resumable)."""

from __future__ import annotations

import json

import gymnasium
import numpy as np
import pytest
import torch

from egosearch.core.staging import CHECKPOINT_NAME, START_ACTOR_NAME
from egosearch.rl.actor import ActorPolicy
from egosearch.rl.config import load_config
from egosearch.rl.demos import collect_demonstrations, load_demonstrations
from egosearch.rl.sac_drq import SacDrqAgent
from egosearch.rl.train import train
from egosearch.variants import load_variant

ENV = {"layout": "kitchen_living", "placement": "everywhere"}
SMALL = {"device": "cpu", "num_threads": 1, "algorithm": "sac_drq", "obs_downsample": 2, "encoder_num_layers": 2,
         "encoder_stride2_layers": 2, "aug_pad": 1, "target_memory": True, "critic_privileged_state": True,
         "train_height_min": 0.45, "n_step": 3, "batch_size": 32, "actor_update_freq": 1,
         "critic_target_update_freq": 1}
"""The cpu preset's learner and observation at smoke sizes."""


@pytest.fixture(scope="module")
def demos(tmp_path_factory):
    cfg = load_config("smoke", {**SMALL, "seed": 2})
    path = tmp_path_factory.mktemp("demos") / "teacher.replay.npz"
    collect_demonstrations("EgoSearch-v0", cfg, ENV, 3, path, seed=2, progress=False)
    replay = load_demonstrations(path, cfg)
    return cfg, replay


def new_agent(cfg, replay) -> SacDrqAgent:
    torch.manual_seed(0)
    batch = replay.sample(2)
    return SacDrqAgent(cfg, 5, batch["mask"].shape[1], batch["proprio"].shape[1], "cpu", batch["state"].shape[1])


def squared_error(agent: SacDrqAgent, batch: dict) -> float:
    """The actor's mean action against the batch's, summed over an action's values, mean over the batch."""
    with torch.no_grad():
        extra = torch.cat([batch["mask"], batch["proprio"]], dim=-1)
        mu, _ = agent.actor(agent.encoder(batch["obs_depth"].float()), extra)
        return float((torch.tanh(mu) - batch["action"]).pow(2).sum(-1).mean())


def parameters(module: torch.nn.Module) -> list[torch.Tensor]:
    return [p.detach().clone() for p in module.parameters()]


def same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return all(torch.equal(x, y) for x, y in zip(a, b))


def test_cloning_fits_the_teachers_actions_and_leaves_the_critic_alone(demos):
    cfg, replay = demos
    agent = new_agent(cfg, replay)
    held = replay.sample(200)
    before, critic = squared_error(agent, held), parameters(agent.critic)
    optimiser = torch.optim.Adam(agent.clone_parameters(), lr=1e-3)
    for _ in range(150):
        metrics = agent.clone_update(replay.sample(32), optimiser)
    after = squared_error(agent, held)
    assert after < 0.5 * before, (before, after)
    assert set(metrics) == {"bc_loss"} and metrics["bc_loss"] >= 0
    assert same(critic, parameters(agent.critic))
    assert agent.num_updates == 0  # cloning is not an RL update: the critic's warm-up counts from the first


def test_the_critic_warms_up_while_the_clone_stays_as_it_is(demos):
    cfg, replay = demos
    agent = new_agent(load_config("smoke", {**SMALL, "demo_episodes": 3, "critic_warmup_updates": 2}), replay)
    encoder, actor, critic = parameters(agent.encoder), parameters(agent.actor), parameters(agent.critic)
    alpha = agent.alpha
    for _ in range(2):
        metrics = agent.update(replay.sample(32))
        assert metrics["actor_loss"] != metrics["actor_loss"]  # NaN: no actor step
    assert same(encoder, parameters(agent.encoder)) and same(actor, parameters(agent.actor))
    assert agent.alpha == alpha
    assert not same(critic, parameters(agent.critic))
    agent.update(replay.sample(32))  # the third: SAC as usual
    assert not same(encoder, parameters(agent.encoder)) and not same(actor, parameters(agent.actor))


def test_the_cloning_term_pulls_the_actor_to_the_teacher_on_the_demonstration_rows(demos):
    cfg, replay = demos
    held = replay.sample(200)
    errors, bc_losses = {}, {}
    for weight in (0.0, 50.0):
        agent = new_agent(cfg, replay)
        agent.bc_weight_now = weight
        torch.manual_seed(1)
        for _ in range(60):
            batch = replay.sample(32)
            batch["demo"] = torch.cat([torch.zeros(16, 1), torch.ones(16, 1)])
            metrics = agent.update(batch)
        errors[weight], bc_losses[weight] = squared_error(agent, held), metrics["bc_loss"]
    assert errors[50.0] < 0.7 * errors[0.0], errors
    assert bc_losses[0.0] != bc_losses[0.0] and bc_losses[50.0] >= 0  # logged only when the term is on


def constant_evaluator(policy) -> dict:
    return {"success_rate": 0.5, "spl": 0.25, "episode_return": 1.0}


def test_a_training_with_demonstrations_clones_mixes_batches_and_resumes_as_one_run(tmp_path, monkeypatch):
    cfg = load_config("smoke", {**SMALL, "seed": 4, "demo_episodes": 2, "bc_updates": 20, "critic_warmup_updates": 10,
                                "demo_batch_fraction": 0.25, "bc_weight": 0.4, "bc_decay_steps": 200})
    from egosearch.rl import train as train_module

    drawn = []
    sample = train_module.LiveRun.sample

    def counting(run):
        batch = sample(run)
        drawn.append(int(batch["demo"].sum()))
        return batch

    monkeypatch.setattr(train_module.LiveRun, "sample", counting)
    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    probe_obs = gymnasium.make("EgoSearchMemory-v0", **ENV).reset(seed=3)[0]  # target_memory: the env it trains in
    evaluated = []

    def recording_evaluator(policy) -> dict:
        evaluated.append(policy.act(probe_obs))
        return constant_evaluator(policy)

    train("EgoSearch-v0", cfg, whole, ENV, recording_evaluator, progress=False)
    assert drawn and set(drawn) == {8}  # a quarter of 32 from the demonstrations, every update
    # actor_start.pt is the clone that the step-0 evaluation ran (stored in float16), not the final actor
    start, final = ActorPolicy(whole / START_ACTOR_NAME), ActorPolicy(whole / "actor.pt")
    assert start.metadata["start"] and start.metadata["env_steps"] == 0 and final.metadata["env_steps"] == 300
    np.testing.assert_allclose(start.act(probe_obs), evaluated[0], atol=2e-2)
    assert np.abs(final.act(probe_obs) - start.act(probe_obs)).max() > 0.05

    class Stop(Exception):
        pass

    def stop(step: int) -> None:
        if step == 230:
            raise Stop

    with pytest.raises(Stop):
        train("EgoSearch-v0", cfg, resumed, ENV, constant_evaluator, progress=False, on_step=stop)
    assert (resumed / CHECKPOINT_NAME).parent.joinpath("demos.replay.npz").exists()
    train("EgoSearch-v0", cfg, resumed, ENV, constant_evaluator, progress=False)
    for name in ("actor.pt", START_ACTOR_NAME):
        a, b = (torch.load(run / name, weights_only=True)["state_dict"] for run in (whole, resumed))
        assert all(torch.equal(a[k], b[k]) for k in a)
    a = torch.load(whole / "actor.pt", weights_only=True)["state_dict"]

    # a run stopped before its first checkpoint (while cloning, say) keeps its demonstrations and starts from them
    early = tmp_path / "early"
    with pytest.raises(Stop):
        train("EgoSearch-v0", cfg, early, ENV, constant_evaluator, progress=False,
              on_step=lambda step: stop(230 if step == 40 else step))
    assert not (early / CHECKPOINT_NAME).exists()

    def collect_again(*args, **kwargs):
        raise AssertionError("collected again")

    monkeypatch.setattr(train_module, "collect_demonstrations", collect_again)
    train("EgoSearch-v0", cfg, early, ENV, constant_evaluator, progress=False)
    c = torch.load(early / "actor.pt", weights_only=True)["state_dict"]
    assert all(torch.equal(a[k], c[k]) for k in a)

    done = json.loads((whole / "done.json").read_text())
    assert done["demonstrations"]["episodes"] == 2 and done["demonstrations"]["teacher_head"]
    assert not (whole / CHECKPOINT_NAME).parent.exists()  # the demonstrations went with the checkpoint
    first = (whole / "train.csv").read_text().splitlines()[1].split(",")
    header = (whole / "train.csv").read_text().splitlines()[0].split(",")
    assert float(first[header.index("env_steps")]) == 0 and float(first[header.index("bc_loss")]) > 0


def test_cloning_draws_from_each_source_in_proportion_to_its_size():
    from egosearch.rl.imitation import proportional_counts

    assert proportional_counts([90, 10], 64) == [58, 6]  # 57.6 and 6.4: the larger remainder gets the rest
    assert proportional_counts([1, 1, 1], 32) == [11, 11, 10]
    assert sum(proportional_counts([5, 700, 33], 64)) == 64


class StandStill:
    """A student that never moves: the teacher must still label every state it is shown."""

    replay_image_size = 50
    episodes_started = 0

    def act(self, obs, deterministic=True):
        return np.zeros(5, np.float32)

    def reset_policy_state(self):  # a student with a memory forgets the last episode here
        self.episodes_started += 1


def test_dagger_labels_each_state_the_student_reaches_with_the_teachers_action(demos):
    from egosearch.rl.imitation import DAGGER_SEED_BASE, dagger_round
    from egosearch.rl.train_env import make_train_env, train_env_kwargs
    from egosearch.searchers.frontier import FrontierPolicy

    cfg, _ = demos
    student = StandStill()
    labelled, figures = dagger_round(student, "EgoSearchMemory-v0", cfg, ENV, 1, round_index=1)
    assert student.episodes_started == 1  # its memory, if it has one, starts empty
    buf = labelled.buffers[0]
    assert figures["episodes"] == 1 and figures["transitions"] == buf.n_added > 0
    # the same episode again: the student stands still, a fresh teacher says what it would do at each state
    env = make_train_env("EgoSearchMemory-v0", train_env_kwargs(cfg, ENV))
    obs, _ = env.reset(seed=DAGGER_SEED_BASE + 100_000 * cfg.seed + 10_000 * 1)
    teacher = FrontierPolicy(env)
    teacher.reset()
    for t in range(buf.n_added):
        np.testing.assert_allclose(buf.action[t], teacher.act(obs), atol=1e-6)
        obs, *_ = env.step(np.zeros(5, np.float32))
    env.close()
    assert np.abs(buf.action[:buf.n_added]).max() > 0.1  # the teacher wanted to move


def test_near_contact_keeps_the_steps_within_the_window_of_a_collision():
    from egosearch.rl.imitation import near_contact

    collided = [False] * 12
    collided[3] = collided[10] = True
    # window 2: steps 1-5 around the first collision, 8-11 around the second (the episode ends at 11)
    assert near_contact(collided, window=2) == [i in (1, 2, 3, 4, 5, 8, 9, 10, 11) for i in range(12)]
    assert near_contact([False] * 5) == [False] * 5
    assert near_contact([True], window=5) == [True]


class DriveForward(StandStill):
    """A student that walks ahead for 25 steps, backs off for 10, and so on: it runs into furniture or a
    wall, leaves it and comes back, so that its contact states come in runs inside the episode."""

    def __init__(self):
        self.calls = 0

    def act(self, obs, deterministic=True):
        self.calls += 1
        forward = 1.0 if (self.calls - 1) % 35 < 25 else -1.0
        return np.array([forward, 0.0, 0.0, 0.0, 0.0], np.float32)


def test_a_contact_round_keeps_exactly_the_labelled_states_near_the_students_collisions(demos):
    from egosearch.rl.imitation import DAGGER_SEED_BASE, dagger_round, near_contact
    from egosearch.rl.train_env import make_train_env, train_env_kwargs

    cfg_all, _ = demos
    cfg_contact = load_config("smoke", {**SMALL, "seed": 2, "dagger_states": "contact"})
    every, figures_all = dagger_round(DriveForward(), "EgoSearchMemory-v0", cfg_all, ENV, 1, round_index=0)
    near, figures = dagger_round(DriveForward(), "EgoSearchMemory-v0", cfg_contact, ENV, 1, round_index=0)
    # the same episode again, to read which steps ran into something
    env = make_train_env("EgoSearchMemory-v0", train_env_kwargs(cfg_all, ENV))
    env.reset(seed=DAGGER_SEED_BASE + 100_000 * cfg_all.seed)
    collided, done, student = [], False, DriveForward()
    while not done:
        _, _, terminated, truncated, info = env.step(student.act(None))
        collided.append(bool(info["collided"]))
        done = terminated or truncated
    env.close()
    flags = near_contact(collided)
    keep = np.flatnonzero(flags)
    runs_inside = sum(1 for t in range(1, len(flags)) if flags[t] and not flags[t - 1])
    assert figures_all["transitions"] == figures["states_reached"] == len(collided)
    assert 0 < figures["transitions"] == len(keep) < len(collided)  # it hit something, and not at every step
    assert runs_inside >= 2  # runs that start inside the episode, after states that were left out
    # each kept state is stored as the student saw it: its whole depth stack, mask and proprioception
    mine, theirs = near.buffers[0], every.buffers[0]
    np.testing.assert_array_equal(mine.stacks(np.arange(len(keep)))[0], theirs.stacks(keep)[0])
    np.testing.assert_array_equal(mine.proprio[:len(keep)], theirs.proprio[keep])
    np.testing.assert_array_equal(mine.mask[:len(keep)], theirs.mask[keep])
    np.testing.assert_allclose(mine.action[:len(keep)], theirs.action[keep], atol=1e-6)


def test_dagger_states_other_than_all_or_contact_is_refused_in_one_line():
    with pytest.raises(ValueError, match="dagger_states.*all, contact"):
        load_config("smoke", {**SMALL, "dagger_states": "stuck"})


def test_a_training_with_dagger_records_its_rounds(tmp_path):
    cfg = load_config("smoke", {**SMALL, "seed": 5, "demo_episodes": 2, "bc_updates": 10, "dagger_rounds": 2,
                                "dagger_episodes": 1, "total_env_steps": 150, "init_steps": 100, "eval_every": 150,
                                "checkpoint_every": 150})
    done = train("EgoSearch-v0", cfg, tmp_path, ENV, constant_evaluator, progress=False)
    assert [r["round"] for r in done["dagger"]] == [1, 2]
    assert all(r["episodes"] == 1 and r["transitions"] > 0 for r in done["dagger"])


def test_figure6_marks_where_a_trainings_imitation_ends(tmp_path):
    from egosearch.report.figures import imitation_phases

    def phases(**fields):
        # the from-scratch learner's schedule (its stored variant's pins): the modular searcher takes no teacher
        cfg = load_config("cpu", {**load_variant("head_on_from_scratch").config, **fields}).to_dict()
        (tmp_path / "config.json").write_text(json.dumps({"config": cfg}))
        return [step for step, _ in imitation_phases(tmp_path / "curve.csv")]

    assert phases() == []  # from scratch
    # the first update at the warm-up's last step (4000), then 2500 critic-only updates, one every 4 env steps
    assert phases(demo_episodes=10, bc_updates=5, critic_warmup_updates=2500, demo_batch_fraction=0.5,
                  bc_weight=0.4, bc_decay_steps=100_000) == [14_000, 100_000]
    assert phases(demo_episodes=10, bc_updates=5, critic_warmup_updates=10**6) == []  # imitation alone: never ends
    floored = dict(demo_episodes=10, bc_updates=5, critic_warmup_updates=2500, demo_batch_fraction=0.5,
                   bc_weight=0.4, bc_decay_steps=100_000, bc_weight_floor=0.1)
    cfg = load_config("cpu", {**load_variant("head_on_from_scratch").config, **floored}).to_dict()
    (tmp_path / "config.json").write_text(json.dumps({"config": cfg}))
    assert imitation_phases(tmp_path / "curve.csv")[-1] == (100_000, "cloning term reaches 0.1")
    assert imitation_phases(tmp_path / "elsewhere" / "curve.csv") == []


def test_the_cloning_term_decays_linearly_to_its_floor_and_stays_there():
    """bc_weight 0.4 over 100k env steps: 0.4 at step 0, 0.2 at 50k, 0 from 100k on; with a floor of 0.1 the
    weight is 0.4 * (1 - 80k/100k) = 0.08 -> 0.1 at 80k, and 0.1 for ever after. A floor above the weight is one
    line."""
    from egosearch.rl.train import cloning_weight

    base = {"demo_episodes": 10, "demo_batch_fraction": 0.5, "bc_weight": 0.4, "bc_decay_steps": 100_000}
    plain = load_config("cpu", base)
    assert [cloning_weight(plain, s) for s in (0, 50_000, 100_000, 150_000)] == pytest.approx([0.4, 0.2, 0.0, 0.0])
    floored = load_config("cpu", {**base, "bc_weight_floor": 0.1})
    assert [cloning_weight(floored, s) for s in (0, 50_000, 80_000, 100_000, 190_000)] == pytest.approx(
        [0.4, 0.2, 0.1, 0.1, 0.1])
    assert cloning_weight(load_config("cpu", {"bc_weight": 0.0, "demo_batch_fraction": 0.0}), 10) == 0.0
    with pytest.raises(ValueError, match=r"bc_weight_floor=0.5 is out of range; allowed: \[0, bc_weight=0.4\]"):
        load_config("cpu", {**base, "bc_weight_floor": 0.5})


# ---- the GRU student (sac_drq_recurrent): the same imitation, in sequences --------------------------------

RECURRENT = {**SMALL, "algorithm": "sac_drq_recurrent", "recurrent_hidden_dim": 16, "sequence_length": 4,
             "burn_in": 2, "batch_size": 32}
"""Recurrent SAC-DrQ at smoke sizes on the same observation (its replay pools the frames as SAC-DrQ's)."""


def new_recurrent(cfg, replay):
    from egosearch.rl.sac_drq_recurrent import SacDrqRecurrentAgent

    torch.manual_seed(0)
    batch = replay.sample(2)
    return SacDrqRecurrentAgent(cfg, 5, batch["mask"].shape[1], batch["proprio"].shape[1], "cpu",
                                batch["state"].shape[1])


def sequence_error(agent, batch: dict) -> float:
    """The recurrent actor's mean action against the teacher's on every loss step of the batch's sequences."""
    from egosearch.rl.sac_drq_recurrent import _sequence_memory

    cfg = agent.cfg
    train_steps = slice(cfg.burn_in, cfg.burn_in + cfg.sequence_length)
    with torch.no_grad():
        feats = agent._features(batch["depth"].float())
        xa = agent.actor.inputs(feats, batch["extra"])
        mem = _sequence_memory(xa, batch["first"], agent.actor.gru, cfg.burn_in)
        mu, _ = agent.actor.out(mem[:, train_steps], xa[:, train_steps])
        return float((torch.tanh(mu) - batch["action"][:, train_steps]).pow(2).sum(-1).mean())


def test_the_gru_student_clones_the_teacher_in_sequences_and_leaves_the_critic_alone(demos):
    _, replay = demos
    cfg = load_config("smoke", {**RECURRENT, "seed": 2})
    agent = new_recurrent(cfg, replay)
    batch = agent.cloning_batch([replay], 32)
    assert batch["depth"].shape[:2] == (32 // 4, 2 + 4 + 1)  # sequences of burn-in + loss steps + the last next obs
    held = agent.cloning_batch([replay], 400)
    before, critic = sequence_error(agent, held), parameters(agent.critic)
    optimiser = torch.optim.Adam(agent.clone_parameters(), lr=1e-3)
    for _ in range(150):
        metrics = agent.clone_update(agent.cloning_batch([replay], 32), optimiser)
    after = sequence_error(agent, held)
    assert after < 0.5 * before, (before, after)
    assert set(metrics) == {"bc_loss"} and same(critic, parameters(agent.critic)) and agent.num_updates == 0


def test_the_gru_students_critic_warms_up_and_its_cloning_term_pulls_to_the_teacher(demos):
    _, replay = demos
    cfg = load_config("smoke", {**RECURRENT, "seed": 2, "demo_episodes": 3, "critic_warmup_updates": 2})
    agent = new_recurrent(cfg, replay)
    encoder, actor, critic = parameters(agent.encoder), parameters(agent.actor), parameters(agent.critic)
    for _ in range(2):
        metrics = agent.update(agent.sample_batch(replay))
        assert metrics["actor_loss"] != metrics["actor_loss"]  # NaN: no actor step
    assert same(encoder, parameters(agent.encoder)) and same(actor, parameters(agent.actor))
    assert not same(critic, parameters(agent.critic))
    agent.update(agent.sample_batch(replay))  # the third: SAC as usual
    assert not same(actor, parameters(agent.actor))
    # the term on the demonstration sequences (here the online replay is the teacher's too)
    held = agent.cloning_batch([replay], 400)
    errors = {}
    for weight in (0.0, 50.0):
        agent = new_recurrent(load_config("smoke", {**RECURRENT, "seed": 2}), replay)
        agent.bc_weight_now = weight
        torch.manual_seed(1)
        for _ in range(60):
            batch = agent.sample_with_demonstrations(replay, replay, 0.5)
            metrics = agent.update(batch)
        assert batch["demo"].squeeze(1).tolist() == [0.0] * 4 + [1.0] * 4
        errors[weight] = sequence_error(agent, held)
    assert errors[50.0] < 0.7 * errors[0.0], errors
    assert metrics["bc_loss"] >= 0


def test_a_gru_student_trains_through_imitation_dagger_and_fine_tuning(tmp_path):
    cfg = load_config("smoke", {**RECURRENT, "seed": 5, "demo_episodes": 2, "bc_updates": 10, "dagger_rounds": 1,
                                "dagger_episodes": 1, "critic_warmup_updates": 5, "demo_batch_fraction": 0.5,
                                "bc_weight": 0.4, "bc_decay_steps": 100, "total_env_steps": 150, "init_steps": 100,
                                "eval_every": 150, "checkpoint_every": 150})
    done = train("EgoSearch-v0", cfg, tmp_path, ENV, constant_evaluator, progress=False)
    assert [r["round"] for r in done["dagger"]] == [1] and done["imitation"]["bc_updates"] == 20
    assert done["updates"] > 5  # past the critic's warm-up
