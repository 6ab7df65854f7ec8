"""The learner presets as data: ``smoke``, ``cpu`` and ``paper``, each the values it sets on top of the fields'
defaults (the defaults are Table 2's and CURL's, see the fields' docstrings).

A preset is for every learner: a learner takes the values of the fields it has and leaves the others (the
``cpu`` preset's pooled input means nothing to SAC + CURL), while a variant that names a field its learner
does not have is refused in one line (:func:`egosearch.rl.config.load_config`). Each preset names its
sources: the paper section or Table 2 row, and for the ``cpu`` preset the source of each departure beside its
value; the fields' own docstrings, which the generated Table 2 pages list beside every departure, say the same
field by field. How the ``cpu`` preset was found, measurement by measurement, is docs/learner.md ("How the
cpu preset was found").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

PAPER: dict[str, Any] = {
    "cuda_graph": True,  # ours: the same math, recorded as CUDA graphs on a GPU (docs/gpu.md); ignored on a CPU
}
"""Table 2 exactly (CURL's defaults for what Table 2 leaves out): 0.75M env steps, one update per step, batch 32,
1024-unit MLPs, 32-filter 4-layer encoder. About 35 hours on the 2-core reference CPU (~6 updates/s with both
cores); meant for a GPU, where the update is recorded as CUDA graphs (``cuda_graph``: the same math, launched at
once; ignored on a CPU)."""

CPU: dict[str, Any] = {
    # SAC with a DrQ-v2-style update (Yarats et al. 2021), a CHANGE OF ALGORITHM: an env step ~10x cheaper than
    # SAC + CURL at Table 2's sizes (the budget study, paper_figs/cpu/budget.*)
    "algorithm": "sac_drq",
    # Table 2: 750k. 200k searched as well as 300k (screen_head_on_memory_50px_200k_seed0_vs_head_on_memory_50px_seed0
    # and head_on_from_scratch_vs_head_on_memory_50px in results/cpu/compare/); 300k overran `all`'s budget
    "total_env_steps": 200_000,
    # cheaper steps, sized by the budget study: lockstep envs with batched acting (ours), batch 64 every 4 env
    # steps (ours), DrQ-v2's 3-step returns
    "num_envs": 8,
    "n_step": 3,
    "batch_size": 64,
    "update_every": 4,
    # 100 -> 50 px depth (PointNav learners train from 64 x 64: bps-nav) with the target memory: together they
    # raised success in every Table 1 cell (results/cpu/compare/head_on_memory_50px_vs_head_on_25px.csv); neither
    # alone did
    "obs_downsample": 2,
    "target_memory": True,  # where the target was last seen: a CHANGE OF THE PAPER'S OBSERVATION (as above)
    # a smaller encoder and nets, for the budget: 2 convs of 32 filters, both stride 2, DrQ-v2's random shift padded
    # by 1 px (DrQ-v2: 4); 3-layer MLPs of 256 units (CURL's layer count)
    "encoder_num_layers": 2,
    "encoder_stride2_layers": 2,
    "encoder_num_filters": 32,
    "aug_pad": 1,
    "actor_num_layers": 3,
    "critic_num_layers": 3,
    "actor_hidden_dim": 256,
    "critic_hidden_dim": 256,
    "actor_update_freq": 1,  # DrQ-v2: the actor and targets every update
    "critic_target_update_freq": 1,
    "alpha_lr": 1e-3,  # Table 2: 1e-4 left alpha near 0.05 after 10k updates, the policy near-random (measured)
    # training only: geodesic progress with the collision term unclipped (habitat-lab's DistanceToGoal), the
    # stuck-student redo's (ablations/head_on_tuned_teacher_geodesic_contact.yaml); with the paper's form the
    # resized learners stayed at 0.00
    "train_distance_reward": "geodesic",
    "curriculum_steps": 100_000,  # training only: start-distance curriculum (Florensa et al. 2017)
    # training only: every Table 1 camera height; on the paper's [1.0, 1.8] m this learner did not transfer to
    # 0.45 m (0.16 against 0.48-0.56 higher up, the stored run of commit 1a639e5)
    "train_height_min": 0.45,
    # asymmetric actor-critic (Pinto et al. 2018), a CHANGE OF ALGORITHM: 0.47 -> 0.59 at 1.05 m excluding low
    # cabinets (commit 6a90dfe's stored comparison; ablations/budget_drq_no_privileged_critic.yaml keeps it off)
    "critic_privileged_state": True,
    # imitation, then SAC fine-tuning, a teacher the paper's learner does not have: PIRLNav's cloning and critic
    # warm-up, RLPD's demonstrations in replay, TD3+BC's cloning term; higher at 1.05 and 1.65 m than learning from
    # scratch (results/cpu/compare/head_on_imitation_finetune_vs_head_on_from_scratch.csv)
    "demo_episodes": 1500,
    "bc_updates": 12_000,
    "critic_warmup_updates": 2500,
    "demo_batch_fraction": 0.5,
    "bc_weight": 0.4,
    "bc_decay_steps": 100_000,
    # the stuck-student redo (ablations/head_on_tuned_teacher_geodesic_contact.yaml, lever (d) of
    # docs/ablations/stuck.md): the tuned teacher and a contact signal (a CHANGE OF THE PAPER'S OBSERVATION)
    "demo_teacher": "frontier_tuned",
    "contact_signal": True,
    "init_steps": 4000,
    # how the run is watched and placed: evaluations and checkpoints every 20k env steps (a checkpoint cuts every
    # env's episode); each curve point reads 100 held-out scenarios, the same at every point, so that Figure 6 can
    # resolve a rise of 0.10 on 3 seeds (30 could not: +0.06 [-0.20, +0.29], the pair before; the redo,
    # ablations/head_on_curve100.yaml), and the actor is kept every 50k env steps to be read on the stored sets
    "eval_every": 20_000,
    "eval_episodes": 100,
    "actor_snapshot_every": 50_000,
    "log_every": 2000,
    "checkpoint_every": 20_000,
    "num_threads": 1,
}
"""The default: a learner that acts at every body step, sized for the 2-core reference CPU: SAC-DrQ with a
privileged critic, cloned from the tuned frontier searcher and then fine-tuned with its episodes in replay, on 50 px
depth with the last-seen target memory and a contact signal, 200k env steps. Each value that departs from the
paper names its source in the comment beside it and in its field's docstring (the generated Table 2 lists them);
how each was found, and the presets before it (``ablations/budget_cpu_curl_24k.yaml``,
``ablations/head_on_modular.yaml``, ...), is docs/learner.md ("How the cpu preset was found"). Its throughput:
``egosearch bench learner`` (``env_steps_per_core_s_cpu_profile``)."""

SMOKE: dict[str, Any] = {
    "total_env_steps": 300,
    "replay_capacity": 1_000,
    "init_steps": 100,
    "encoder_num_layers": 2,
    "encoder_num_filters": 8,
    "encoder_latent_dim": 32,
    "curl_latent": 32,
    "actor_hidden_dim": 64,
    "critic_hidden_dim": 64,
    "actor_num_layers": 3,
    "critic_num_layers": 3,
    "eval_every": 150,
    "eval_episodes": 2,
    "log_every": 50,
    "checkpoint_every": 150,
}
"""The toy sizes: a whole training run (warm-up, updates, evaluation, checkpoint, actor.pt) in a few seconds, a
2-layer 8-filter encoder, 64-unit MLPs, 300 env steps, a 1000-transition replay and 2 evaluation episodes.

Alone (``load_config("smoke")``, the unit tests' base) they sit on the fields' defaults: SAC + CURL with 100->84
crops and K = 5 as in the paper. A variant at the smoke preset (:func:`egosearch.rl.config.load_variant_config`,
what ``egosearch train``, the DAG and the cost line read) is instead its own ``cpu`` learner and levers with every
size of the run capped at :data:`SMOKE_CAPS`, so that any ``cpu`` lever can be smoke-tested in minutes."""

SMOKE_CAPS: dict[str, int] = {
    # what a run's time grows with: its env steps and episodes, its updates and their batches
    "total_env_steps": SMOKE["total_env_steps"],
    "init_steps": SMOKE["init_steps"],
    "num_envs": 2,
    "batch_size": 32,  # Table 2's, the smoke preset's
    "replay_capacity": SMOKE["replay_capacity"],
    "eval_episodes": SMOKE["eval_episodes"],
    "demo_episodes": 2,
    "bc_updates": 20,
    "critic_warmup_updates": 10,
    "dagger_rounds": 1,
    "dagger_episodes": 1,
    "ppo_epochs": 2,
    "update_every": 64,  # PPO's rollout (env steps per update), which must fit in the capped steps
    # the schedules, so that each still happens within the capped steps: the plumbing is what a smoke run tests
    "eval_every": SMOKE["eval_every"],
    "checkpoint_every": SMOKE["checkpoint_every"],
    "log_every": SMOKE["log_every"],
    "actor_snapshot_every": SMOKE["checkpoint_every"],
    "curriculum_steps": SMOKE["eval_every"],
    "bc_decay_steps": SMOKE["eval_every"],
    # the networks
    "encoder_num_layers": SMOKE["encoder_num_layers"],
    "encoder_num_filters": SMOKE["encoder_num_filters"],
    "encoder_latent_dim": SMOKE["encoder_latent_dim"],
    "curl_latent": SMOKE["curl_latent"],
    "actor_hidden_dim": SMOKE["actor_hidden_dim"],
    "critic_hidden_dim": SMOKE["critic_hidden_dim"],
    "actor_num_layers": SMOKE["actor_num_layers"],
    "critic_num_layers": SMOKE["critic_num_layers"],
    "recurrent_hidden_dim": 16,
    "sequence_length": 4,
    "burn_in": 2,
}
"""The most a smoke run of a variant takes of each size, whatever the variant pins (``head_on_25px`` pins 300,000
env steps; at smoke it trains 300): a smoke run is plumbing only, minutes long. A size the variant or its ``cpu``
config sets lower stays lower (a lever that shrinks a network is smoke-tested as it is); a size of 0 (off)
stays off. :func:`smoke_sized` applies them."""


def paper_preset() -> dict[str, Any]:
    """The ``paper`` preset's values (:data:`PAPER`)."""
    return dict(PAPER)


def cpu_preset() -> dict[str, Any]:
    """The ``cpu`` preset's values (:data:`CPU`, whose comments name the source of each departure from the
    paper)."""
    return dict(CPU)


def smoke_preset() -> dict[str, Any]:
    """The ``smoke`` preset's values (:data:`SMOKE`)."""
    return dict(SMOKE)


SMOKE_LEARNER_PRESET = "cpu"
"""Whose learner and levers a variant has at the smoke preset: the default preset's, so that a ``cpu`` lever
(``bc_weight``, a pooled input, a memory in the observation) runs at smoke as it will run, only smaller."""


def smoke_sized(values: dict[str, Any]) -> dict[str, Any]:
    """``values`` (a learner config's fields) with each size at most its :data:`SMOKE_CAPS` value; the fields
    the learner does not have are not added."""
    return {key: min(value, SMOKE_CAPS[key]) if key in SMOKE_CAPS else value for key, value in values.items()}


PRESETS: dict[str, Callable[[], dict[str, Any]]] = {
    "smoke": smoke_preset,
    "cpu": cpu_preset,
    "paper": paper_preset,
}
"""Preset name -> function returning (a copy of) its values on top of the fields' defaults."""
