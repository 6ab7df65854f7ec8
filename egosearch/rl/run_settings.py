"""The run settings: what every learner and the training loop share (paper 4.2 and Table 2).

:class:`RunSettings` holds the settings of a training run that every learner's config carries: the
observation and the data (image size, frame history, replay, discount, env steps, batch), the envs and
their training-only aids, the loop's schedule (warm-up, updates, evaluations, checkpoints, logs) and where
the run is placed on the machine (``cuda_graph`` is read on a GPU by SAC+CURL and the stacked update,
``compile`` by SAC+CURL only). The privileged critic and the demonstrations are not here: they are pieces
a learner's settings opt into (:mod:`egosearch.rl.training_aids`). Each learner's own
settings (its networks, optimisers and losses) live beside it (:mod:`egosearch.rl.sac_curl_settings`,
:mod:`egosearch.rl.sac_drq_settings`, :mod:`egosearch.rl.sac_drq_recurrent_settings`,
:mod:`egosearch.rl.ppo_settings`, built from :mod:`egosearch.rl.network_settings`), and
:mod:`egosearch.rl.config` composes the two into a learner's config. Each field carries its own docstring
saying where the value comes from: "Table 2" (the paper, Appendix A), "CURL" (the defaults of the
reference code of Srinivas et al. 2020) or "ours".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from egosearch.sim.body import IMAGE_SIZE  # the env's frames: one source

Complaint = Callable[[str, str], None]
"""``bad(field, allowed)``: raises the one-line ``ValueError`` of a value out of range."""

CURRICULUM_START_RADIUS = 1.0
"""The default of :attr:`RunSettings.curriculum_start_radius` (the name ``curriculum_steps``' docstring, which the
stored Table 2 pages quote, gives it)."""
CURRICULUM_END_RADIUS = 12.0
"""The default of :attr:`RunSettings.curriculum_end_radius`."""
DISTANCE_REWARDS = ("distance", "progress", "geodesic")
"""Forms of r_d (the env's ``egosearch.sim.env.DISTANCE_REWARDS``; ``tests/test_rl_sac.py``'s
``test_the_configs_forms_of_r_d_are_the_envs`` keeps them equal)."""
LONG_RUN_BOUNDS = {
    "total_env_steps": (20_000_000, "env steps (about 27x Table 2's 750,000)"),
    "eval_episodes": (10_000, "episodes a curve point (the most scenarios of one set, `egosearch scenarios --n`)"),
    "demo_episodes": (100_000, "demonstration episodes (about 67x the cpu preset's 1,500)"),
}
"""The most a training may ask for (``total_env_steps``, ``eval_episodes``, ``demo_episodes``) without
``--allow-long`` (``egosearch train``, ``demos``, ``evaluate --curve-of``, ``variant check``) or ``--config
allow_long=true`` (the workflow): beyond them a run takes weeks on any machine, so a value past one is taken
for a typo (an extra zero) and refused before any work (:func:`egosearch.variants.check_run_length`)."""
ALLOW_LONG_ENV = "EGOSEARCH_ALLOW_LONG"
"""Set to 1 in the environment, it allows what ``--allow-long`` allows: the workflow sets it for its jobs under
``--config allow_long=true`` (their command lines stay the same, so stored jobs are not rerun)."""
DECISIONS, BODY_STEPS = "decisions", "body steps"
"""What one env step of a training counts (:attr:`RunSettings.env_step_unit`)."""


@dataclass
class RunSettings:
    """The settings every learner and the training loop share."""

    # ---- Table 2: observation and data -------------------------------------------------
    image_size: int = IMAGE_SIZE
    """Table 2 "Image Size" 100x100: side (px) of the depth frames the env renders and the
    replay buffer stores. It must be the env's, ``egosearch.sim.body.IMAGE_SIZE``: a config that
    differs is one line when it is loaded (``tests/test_rl_sac.py``)."""
    frame_history: int = 5
    """Table 2 "Image History Buffer Size" (K of paper 4.1): depth frames stacked as channels."""
    head_history: int = 1
    """Table 2 "Head History Buffer Size": past head-joint changes in the proprioception; with
    1 the env's proprio is (q_p, q_y, last dq_p, last dq_y), i.e. 2 * (1 + head_history) values.
    Informational for the learner: it is checked against the env's proprio size."""
    replay_capacity: int = 100_000
    """Table 2 "Replay buffer": transitions kept (FIFO)."""
    gamma: float = 0.99
    """Table 2 "Discount rate gamma"."""
    total_env_steps: int = 750_000
    """Table 2 "Number of training steps" 0.75M: environment steps (simulation samples, paper
    4.2: "0.75 million simulation samples"), not gradient updates. The ``cpu`` preset trains 200k body
    steps, the 2-core budget's (see :func:`cpu_preset`); a modular searcher (``modular_searcher``) counts
    decisions of several body steps instead (``head_on_modular``: 30k)."""
    batch_size: int = 32
    """Table 2 "Batch-size": transitions per gradient update (also the CURL negatives + 1)."""

    # ---- the learner, the envs and their training-only aids (the cpu preset's departures) ----
    algorithm: str = "sac_curl"
    """Paper 4.2 / Table 2: "sac_curl" = SAC + CURL (:mod:`egosearch.rl.sac_curl`).
    "sac_drq" = ours, after DrQ-v2 (Yarats et al. 2021): SAC with ONE conv encoder trained by
    the critic only, random-shift augmentation, no contrastive loss and no target encoder
    (:mod:`egosearch.rl.sac_drq`); an update costs ~3 conv passes instead of CURL's ~9. This
    CHANGES THE ALGORITHM: the cpu preset uses it, the paper preset never.
    "sac_drq_recurrent" = ours, SAC-DrQ with a GRU memory in the actor and a separate one in the
    critic, trained on replayed sequences with burn-in (:mod:`egosearch.rl.sac_drq_recurrent`;
    Ni et al. 2022, Kapturowski et al. 2019): a recurrent policy, which CHANGES THE ALGORITHM
    further (the paper's policy sees only the last ``frame_history`` frames); no preset uses it,
    a variant sets it. Every "sac_drq" field applies to it as well but ``critic_layer_norm`` and the
    reconstruction decoder's (``encoder_aux_loss``, ``encoder_aux_weight``); it adds its own memory fields.
    "ppo" = ours, PPO (Schulman et al. 2017) on SAC-DrQ's actor, with a separate value network
    (:mod:`egosearch.rl.ppo`): an on-policy learner, which CHANGES THE ALGORITHM (the paper's is
    SAC + CURL); no preset uses it, a variant sets it (see the "ppo_*" fields)."""
    num_envs: int = 1
    """Ours (CURL: 1): environments stepped in lockstep in one process, their actions computed
    in one batched forward pass (acting cost per env step falls ~N-fold). Each env has its own
    replay ring of ``replay_capacity / num_envs`` transitions; ``total_env_steps`` counts the
    steps of all envs."""
    n_step: int = 1
    """CURL: 1 (one-step TD targets). DrQ-v2: 3. Rewards summed over up to ``n_step`` steps of
    one episode with the target bootstrapped gamma^n later (sampled from the replay)."""
    target_memory: bool = False
    """Paper: False (the observation is depth, the target mask and the head's pose). True: the
    policy trains, and so is evaluated, in the ``*Memory-v0`` env of its variant's id
    (EgoSearch-v0 -> EgoSearchMemory-v0, EgoSearchNoHead-v0 -> EgoSearchNoHeadMemory-v0), whose
    observation also carries where the target was last seen, by the searcher's own odometry, and
    the steps since (``egosearch.sim.env``): the same as naming that id in the variant file. This
    CHANGES THE OBSERVATION, for the actor and at evaluation too. The ``cpu`` preset sets it, with
    ``obs_downsample`` 2 (see :func:`cpu_preset` for the comparison that chose them); the paper
    preset never."""
    modular_searcher: bool = False
    """Paper: False (the policy acts at every body step: its steps, turns and head). True: a modular
    searcher (SemExp, Chaplot et al. NeurIPS 2020; the modular pipeline of Gervet et al. 2023; the stored
    ``head_on_modular`` pair, the ``cpu`` preset's before it learned at every body step, see
    :func:`cpu_preset`): the policy trains, and so is evaluated, in the ``*Modular-v0`` env of
    its variant's head (EgoSearch-v0 -> EgoSearchModular-v0, EgoSearchNoHead-v0 ->
    EgoSearchNoHeadModular-v0; ``egosearch.searchers.modular``): it decides only where to explore (a
    point on its own floor map, walked to as the nearest reachable frontier) and how to sweep the head,
    at most every 10 body steps, and the frontier searcher maps, plans and walks the body. Its
    observation adds that map. So the env steps of ``total_env_steps`` and every schedule count
    decisions. This CHANGES WHAT IS LEARNED AND THE OBSERVATION, at evaluation too (the claims about
    the body's steps cannot be read on it); the same as naming that id in the variant file. Not with
    ``target_memory`` (the frontier searcher remembers where it saw the target) nor demonstrations."""
    train_distance_reward: str = "distance"
    """Paper eq. 2 text: "distance" = r_d is minus the distance to the target while it is seen.
    "progress" = the decrease of that distance since the last step while seen (Savva et al.
    2019's form, which the paper cites; potential-based shaping as in habitat-lab). "geodesic" =
    the decrease of the geodesic distance to where the target counts as found, at every step,
    seen or not (habitat-lab's DistanceToGoalReward), with the collision term unclipped (the
    paper's stops growing at 30 collisions): a CHANGE OF THE REWARD, the ``cpu`` preset's since
    the stuck-student redo (``ablations/head_on_geodesic_finetune.yaml`` screened it on three seeds;
    before it the preset took "progress"). TRAINING ONLY: evaluation always scores the paper's task
    (success, SPL), whatever the training reward. A variant's ``train_env: distance_reward``
    takes precedence."""
    curriculum_steps: int = 0
    """Paper: 0 (no curriculum). Otherwise a start-distance curriculum after the reverse
    curriculum of Florensa et al. 2017, simplified: training episodes start within a radius of
    the target that grows linearly from ``CURRICULUM_START_RADIUS`` (1 m) to
    ``CURRICULUM_END_RADIUS`` (12 m, the whole home) over the first this many env steps; after
    that, starts are drawn from the whole home as in the paper. TRAINING ONLY: evaluation always
    uses the stored scenarios."""
    curriculum_start_radius: float = CURRICULUM_START_RADIUS
    """Ours (the paper has no curriculum): the radius (m) around the target within which training episodes start
    at the first env step of a curriculum; read only with ``curriculum_steps`` > 0."""
    curriculum_end_radius: float = CURRICULUM_END_RADIUS
    """Ours: the radius (m) the curriculum's start radius has grown to at env step ``curriculum_steps``: more than
    any home's extent, so that the last starts are the whole home's; read only with ``curriculum_steps`` > 0."""

    train_height_min: float = 1.0
    """Paper 4.1: 1.0, i.e. the camera height of a training episode is drawn from [1.0, 1.8] m
    (plus the per-step noise). Otherwise training heights are drawn from [this, 1.8] m. The
    paper's Section 5 names randomising the abstract model's height as the way to cover
    characters of other heights; its learner transfers from [1.0, 1.8] m down to the 0.45 m
    camera of Table 1, the smaller learner of the cpu preset did not (its searches at 0.45 m
    collided twice as often as at 1.05 m), so the cpu preset trains at every Table 1 height.
    TRAINING ONLY: evaluation uses the stored scenarios' fixed heights."""

    # ---- training loop (CURL defaults or ours) ------------------------------------------
    init_steps: int = 1000
    """CURL: environment steps of uniformly random actions before the first update."""
    update_every: int = 1
    """Ours (CURL: 1): gradient updates happen after every ``update_every``-th env step."""
    updates_per_step: int = 1
    """Ours (CURL: 1): gradient updates done each time updates are due; the update-to-data
    ratio is ``updates_per_step / update_every``."""
    eval_every: int = 10_000
    """Ours: environment steps between evaluations (a row of curve.csv each; the ``cpu`` preset: 20k)."""
    eval_episodes: int = 10
    """Ours (CURL: 10): deterministic episodes of the default evaluation, the same held-out scenarios at every
    point. The ``cpu`` preset reads 100, so that Figure 6 can resolve a rise of 0.10 on 3 seeds (at 30 the stored
    pair's rise was +0.06 [-0.20, +0.29]; the redo of ablations/head_on_curve100.yaml). At most 10,000 unless the
    run allows more (``--allow-long``; :data:`LONG_RUN_BOUNDS`)."""
    log_every: int = 1_000
    """Ours: environment steps between rows of train.csv / progress-bar refreshes."""
    actor_snapshot_every: int = 0
    """Ours: environment steps between actor snapshots, ``actor_<N>k.pt`` beside ``actor.pt`` (actor-only weights,
    about 1.2 MB each; never a checkpoint or replay), so that a policy half-way through training can be read on the
    stored sets; 0: none. The ``cpu`` preset and the memory levers keep one every 50k (the actors at 50k, 100k,
    150k and 200k)."""
    checkpoint_every: int = 10_000
    """Ours: environment steps between resumable checkpoints (atomic writes). A checkpoint ends every env's
    episode, so that a resumed run equals one that was not stopped: the ``cpu`` preset checkpoints every 20k."""
    seed: int = 1
    """Ours: seeds torch, numpy, python's random, the env and its action space."""

    # ---- implementation (ours; they do not change the algorithm) ------------------------
    device: str = "auto"
    """Ours: "auto" = CUDA when available, else CPU; or any torch device string."""
    num_threads: int = 0
    """Ours: torch CPU threads; 0 = every core this process may run on."""
    channels_last: bool = True
    """Ours: run the convs in channels-last memory layout (same math, faster oneDNN kernels), in
    every learner. For SAC-DrQ at 50 px the gain on the 2-core CPU is small and noisy (short real
    trainings, not a stored benchmark); results differ only by float rounding."""
    compile: bool = False
    """Ours, read by SAC+CURL only: ``torch.compile`` its encoders and MLPs. Off: measured on the 2-core CPU it costs
    ~20 s of compilation and gives no speed-up (the convs and GEMMs already run as oneDNN / MKL
    kernels near the CPU's peak; see ``egosearch.rl.bench_learner``). May help on a GPU."""
    cuda_graph: bool = False
    """Ours: on a GPU, record the SAC+CURL update as CUDA graphs (one per pattern of the update's
    steps) and replay them, instead of launching its hundreds of small kernels from Python one by
    one (``egosearch.rl.cuda_graph``). The same math, with capturable Adam; the random numbers
    come from torch's CUDA generator at other offsets than an eager update's. Used only where it
    applies: algorithm sac_curl on CUDA without ``compile``; the other learners and the CPU ignore
    it. The ``paper`` preset turns it on: on an H200 both the update and a paper-preset training
    ran several times faster with it (docs/gpu.md gives the stored measurement)."""
    keep_checkpoint: bool = False
    """Ours: keep the last checkpoint (agent + optimisers + replay) after training finishes;
    by default it is deleted once actor.pt and done.json are written (replay buffers are large
    and must never be committed)."""

    # -------------------------------------------------------------------------------------
    def own_checks(self, bad: Complaint) -> None:
        """The run settings' ranges and the rules between them (``LearnerConfig.validate`` calls it)."""
        for name in ("image_size", "frame_history", "replay_capacity", "total_env_steps", "batch_size",
                     "update_every", "updates_per_step", "eval_every", "eval_episodes", "log_every",
                     "checkpoint_every", "num_envs", "n_step"):
            if getattr(self, name) < 1:
                bad(name, "an integer >= 1")
        for name in ("head_history", "init_steps", "seed", "num_threads", "curriculum_steps", "actor_snapshot_every"):
            if getattr(self, name) < 0:
                bad(name, "an integer >= 0")
        if self.image_size != IMAGE_SIZE:
            bad("image_size", f"{IMAGE_SIZE} (the env renders {IMAGE_SIZE} x {IMAGE_SIZE} frames: "
                "egosearch.sim.body.IMAGE_SIZE)")
        if self.train_distance_reward not in DISTANCE_REWARDS:
            bad("train_distance_reward", ", ".join(DISTANCE_REWARDS))
        if self.modular_searcher and self.target_memory:
            bad("target_memory", "False with modular_searcher (the frontier searcher remembers the target itself)")
        if self.num_envs > self.replay_capacity:
            bad("num_envs", f"1..replay_capacity={self.replay_capacity}")
        # Updates fall on the multiples of update_every from the last warm-up step on (train._Run.update):
        # a run that ends before the first of them saves the random initial actor as if it were trained.
        first_update = -(-max(self.init_steps, 1) // self.update_every) * self.update_every
        if self.total_env_steps < first_update:
            bad("total_env_steps", f">= {first_update}, the env step of the first update (after init_steps="
                f"{self.init_steps} random steps, an update every {self.update_every} steps): fewer train no update")
        if not 0.0 < self.curriculum_start_radius <= self.curriculum_end_radius:
            bad("curriculum_start_radius", f"(0, curriculum_end_radius={self.curriculum_end_radius}] m")
        if not 0.3 <= self.train_height_min <= 1.8:
            bad("train_height_min", "[0.3, 1.8] m (training heights are drawn from [this, 1.8] m)")
        if not 0.0 < self.gamma <= 1.0:
            bad("gamma", "(0, 1]")
        if self.batch_size > self.replay_capacity:
            bad("batch_size", f"1..replay_capacity={self.replay_capacity}")
        if not (self.device == "auto" or self.device == "cpu" or self.device.startswith("cuda")
                or self.device == "mps"):
            bad("device", "auto, cpu, cuda, cuda:N or mps")

    def start_radius(self, env_steps: int) -> float | None:
        """The curriculum's start radius (m) at ``env_steps``; None once it is over (or off)."""
        if env_steps >= self.curriculum_steps:
            return None
        frac = env_steps / self.curriculum_steps
        return self.curriculum_start_radius + frac * (self.curriculum_end_radius - self.curriculum_start_radius)

    @property
    def env_step_unit(self) -> str:
        """What one env step of a training with this config is: "decisions" (a modular searcher's; up to
        10 body steps and the walker's planning each) or "body steps". Rates of the two never mix."""
        return DECISIONS if self.modular_searcher else BODY_STEPS
