"""Training aids a learner's settings opt into: a privileged critic and learning from the classical searcher's
demonstrations (cloning, DAgger, the critic's warm-up, demonstrations in replay, the cloning term).

Neither is the paper's (its critic sees what the actor sees and it has no teacher); the ``cpu`` preset uses
both (see :func:`egosearch.rl.presets.cpu_preset`). A learner's settings class that reads one lists its
class among its bases (SAC-DrQ's and recurrent SAC-DrQ's both, PPO's the privileged critic), so its config
has those fields and no other learner's does: a preset's values of them reach only the learners that have
them, and a variant that sets one for another learner is refused in one line. The training loop, the
demonstrations and the cost model read them through :func:`demonstration_settings` and
:func:`critic_reads_state`, which give a learner without the piece its defaults (no teacher, no state).

Each piece names the run-settings field it is listed after (``shown_after``), so Table 2's departures and
``egosearch config show`` list its fields where they were always listed, whatever class declares them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from egosearch.rl.run_settings import Complaint

DEMO_TEACHERS = ("frontier", "frontier_tuned")
"""The classical searchers demonstrations may come from (see ``DemonstrationSettings.demo_teacher``;
``egosearch.rl.demos.TEACHERS`` maps each to its class)."""
DAGGER_STATES = ("all", "contact")
"""What a DAgger round keeps of the states the student reaches (``DemonstrationSettings.dagger_states``)."""


@dataclass
class PrivilegedCriticSettings:
    """An asymmetric critic: the learner's critic (or value network) may read the env's hidden state."""

    shown_after: ClassVar[str] = "curriculum_steps"
    """The run-settings field this piece's fields are listed after (Table 2's departures, ``config show``)."""

    critic_privileged_state: bool = False
    """Paper: False (the critic sees what the actor sees). True ("sac_drq", "sac_drq_recurrent"
    and "ppo" only; for "ppo" the value network reads it): an asymmetric
    actor-critic (Pinto et al. 2018): the critic also reads the env's hidden state (the body's
    and the target's positions, the target in the body's frame, its distance: see
    ``egosearch.sim.env.privileged_state``) beside the observation, as Baisero & Amato 2022 advise
    (history + state, not state alone). The actor, and so every policy and actor file, sees only
    the observation. This CHANGES THE ALGORITHM. TRAINING ONLY: evaluation never uses it. The
    ``cpu`` preset sets it (see :func:`cpu_preset` for the comparison that chose it)."""


@dataclass
class DemonstrationSettings:
    """Learning from the classical searcher's demonstrations, the ``cpu`` preset's (see its
    :func:`egosearch.rl.presets.cpu_preset`): TRAINING ONLY, each a CHANGE OF ALGORITHM (a teacher the
    paper's learner does not have). The actor, its file and every evaluation are as without them."""

    shown_after: ClassVar[str] = "train_height_min"
    """The run-settings field this piece's fields are listed after (Table 2's departures, ``config show``)."""

    demo_episodes: int = 0
    """Paper: 0 (no demonstrations). N > 0: a fresh training first runs the classical frontier searcher
    (``demo_teacher``: by default ``egosearch.searchers.frontier``, untuned; head moving where the body has a
    head) for N episodes of its own training envs and keeps their transitions (``egosearch.rl.demos``,
    seeded by ``seed``), for ``bc_updates``, ``demo_batch_fraction`` and ``bc_weight``. Learning from
    frontier-exploration demonstrations before RL: PIRLNav (Ramrakhya et al., CVPR 2023); demonstrations
    kept in replay: RLPD (Ball et al., ICML 2023). Their collection is part of the training's time. The
    ``cpu`` preset: 1,500 (see :func:`cpu_preset`). At most 100,000 unless the run allows more
    (``--allow-long``; ``egosearch.rl.run_settings.LONG_RUN_BOUNDS``)."""
    demo_teacher: str = "frontier"
    """Ours (with ``demo_episodes`` >= 1): the classical searcher whose episodes are the demonstrations, one
    of :data:`DEMO_TEACHERS`. "frontier", the project's default: the untuned frontier searcher, Table 1's
    classical row (``egosearch.searchers.frontier``). "frontier_tuned": the same searcher tuned on
    training-side sets (``egosearch.searchers.frontier_tuned``, its own bound row; ``egosearch tune`` redoes
    the tuning), the ``cpu`` preset's since the stuck-student redo (it was "frontier" before). Either holds
    its head fixed where the body has none (the head-off variant learns from the head-fixed teacher)."""
    bc_updates: int = 0
    """Paper: 0. PIRLNav's first phase (Ramrakhya et al. 2023: behaviour cloning, then RL fine-tuning):
    before the first env step, this many behaviour-cloning steps of the encoder and the actor on
    ``batch_size`` demonstration transitions each (squared error between the actor's mean action, after
    its tanh, and the teacher's; the random shift as in updates). The warm-up's ``init_steps`` then
    act with the cloned policy instead of at random. The step-0 row of curve.csv is the cloned policy. The
    ``cpu`` preset: 12,000."""
    dagger_rounds: int = 0
    """Paper: 0. DAgger (Ross, Gordon & Bagnell 2011), after ``bc_updates``: this many rounds in which the
    cloned student drives ``dagger_episodes`` training-side episodes (its mean action), the teacher labels
    every state it reaches (the frontier searcher's map updates from whatever it sees), the labelled states
    join the demonstrations for cloning only (their actions are the teacher's, not the ones taken, so RL
    never samples them), and the student is cloned again for ``bc_updates`` steps on all of them, drawn in
    proportion to their sizes (``egosearch.rl.imitation``)."""
    dagger_episodes: int = 0
    """Ours (with ``dagger_rounds``): episodes the student drives in each DAgger round."""
    dagger_states: str = "all"
    """Ours (with ``dagger_rounds``): which of the student's states a round labels and keeps, one of
    :data:`DAGGER_STATES`. "all": every state it reaches (DAgger as Ross et al.). "contact": only the states
    within ``imitation.CONTACT_WINDOW`` steps of a step on which its body ran into something, before or
    after, so the teacher is asked only where the student meets furniture: the part of lever (c) of the
    stuck-student issue that relabels the student's stuck states (``ablations/head_on_dagger_contact.yaml``;
    the clone, before RL, fails stuck in 12-23 % of the stored episodes per height)."""
    critic_warmup_updates: int = 0
    """PIRLNav (Ramrakhya et al. 2023: the critic learns first, the cloned policy frozen, so that
    the first policy steps follow a critic fitted to it): the first this many RL updates train only
    the critic's projection and Q-heads; the encoder, the actor and the temperature stay as cloned. The
    ``cpu`` preset: 2,500."""
    demo_batch_fraction: float = 0.0
    """RLPD (Ball et al. 2023: 0.5, "symmetric sampling"): this fraction of every update's batch is
    drawn from the demonstrations, the rest from the online replay. 0: online only (the paper). The ``cpu``
    preset: 0.5."""
    bc_weight: float = 0.0
    """TD3+BC (Fujimoto & Gu 2021: the actor's loss plus a squared error to the data's action, weighted
    against the critic's scale; their alpha 2.5 is a weight of 1 / 2.5 = 0.4 here), the optional term of
    RLPD-style training: the actor's SAC loss plus ``bc_weight`` x mean |Q| x the squared error
    between its mean action and the teacher's on the batch's demonstration rows. It decays linearly to
    0 over the first ``bc_decay_steps`` env steps, so that RL may leave the teacher. 0: none. The ``cpu``
    preset: 0.4."""
    bc_decay_steps: int = 0
    """Ours (with ``bc_weight``): env steps over which the behaviour-cloning term falls to 0 (to
    ``bc_weight_floor``, when set). The ``cpu`` preset: 100k, half its run."""
    bc_weight_floor: float = 0.0
    """Ours (with ``bc_weight``), 0: the behaviour-cloning term decays to nothing, so after ``bc_decay_steps``
    RL alone moves the student (the ``cpu`` preset, whose curve stops rising there). > 0: the weight never
    falls below this, so the teacher's detours around furniture keep pulling on the actor for the whole run
    (a lever of the stuck-student issue, ``ablations/head_on_cloning_floor.yaml``; RLPD and TD3+BC keep a
    constant weight). At most ``bc_weight``."""

    def own_checks(self: Any, bad: Complaint) -> None:
        """The ranges of the demonstration fields and their rules (``LearnerConfig.validate`` calls it)."""
        for name in ("demo_episodes", "bc_updates", "critic_warmup_updates", "bc_decay_steps", "dagger_rounds",
                     "dagger_episodes"):
            if getattr(self, name) < 0:
                bad(name, "an integer >= 0")
        if not 0.0 <= self.demo_batch_fraction < 1.0:
            bad("demo_batch_fraction", "[0, 1) (the rest of each batch is online)")
        if self.bc_weight < 0:
            bad("bc_weight", ">= 0")
        if self.demo_teacher not in DEMO_TEACHERS:
            bad("demo_teacher", ", ".join(DEMO_TEACHERS))
        uses = {"bc_updates": self.bc_updates > 0, "demo_batch_fraction": self.demo_batch_fraction > 0,
                "bc_weight": self.bc_weight > 0}
        for name, used in uses.items():
            if used and self.demo_episodes == 0:
                # the cpu preset sets them all: name every one that needs turning off with the teacher
                on = [f"{n}: 0" for n in ("bc_updates", "critic_warmup_updates", "demo_batch_fraction", "bc_weight",
                                          "bc_decay_steps") if getattr(self, n)]
                if self.demo_teacher != "frontier":
                    on.append("demo_teacher: frontier")
                bad(name, "0 unless demo_episodes >= 1 (it reads the demonstrations); without demonstrations set "
                    + ", ".join(on))
        if self.demo_teacher != "frontier" and self.demo_episodes == 0:
            bad("demo_teacher", "frontier (the default) unless demo_episodes >= 1 (no demonstrations, no teacher)")
        if self.dagger_rounds and not self.bc_updates:
            bad("dagger_rounds", "0 unless bc_updates >= 1 (each round clones the student again)")
        if bool(self.dagger_rounds) != bool(self.dagger_episodes):
            bad("dagger_episodes", "1..10000 with dagger_rounds >= 1, else 0")
        if self.dagger_states not in DAGGER_STATES:
            bad("dagger_states", ", ".join(DAGGER_STATES))
        if self.dagger_episodes > 10_000:
            bad("dagger_episodes", "1..10000 (a round's episodes stay below the next round's seeds)")
        if self.bc_weight > 0 and self.demo_batch_fraction == 0:
            bad("bc_weight", "0 unless demo_batch_fraction > 0 (the term is taken on the batch's demonstrations)")
        if self.bc_weight > 0 and self.bc_decay_steps == 0:
            bad("bc_decay_steps", ">= 1 with bc_weight > 0 (the env steps over which the term decays)")
        if not 0.0 <= self.bc_weight_floor <= self.bc_weight:
            bad("bc_weight_floor", f"[0, bc_weight={self.bc_weight}] (the weight the cloning term decays to)")
        if self.modular_searcher and self.demo_episodes:
            bad("demo_episodes", "0 with modular_searcher (the demonstrations are the frontier searcher's body steps)")


def demonstration_settings(cfg: Any) -> DemonstrationSettings:
    """``cfg``'s demonstration settings: ``cfg`` itself where its learner learns from demonstrations, the
    defaults (no demonstrations, no cloning) otherwise."""
    return cfg if isinstance(cfg, DemonstrationSettings) else DemonstrationSettings()


def critic_reads_state(cfg: Any) -> bool:
    """Whether ``cfg``'s critic reads the env's privileged state (never for a learner without the piece)."""
    return isinstance(cfg, PrivilegedCriticSettings) and cfg.critic_privileged_state


TRAINING_AIDS: tuple[type, ...] = (PrivilegedCriticSettings, DemonstrationSettings)
"""The pieces, for the config's field order and docstrings (:mod:`egosearch.rl.config`)."""
