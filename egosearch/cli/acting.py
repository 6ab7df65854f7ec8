"""What the commands that run searches share: the acting threads and the policy a ``--policy`` names."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import torch

from egosearch.cli.checks import at_least, learner_profile_of
from egosearch.report.workflow_jobs import workflow_config
from egosearch.rl.actor import ActorPolicy
from egosearch.rl.train import torch_threads
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.searchers.frontier_tuned import FrontierTunedPolicy
from egosearch.searchers.policies import OraclePolicy, RandomPolicy
from egosearch.sim.envs import (
    ALL_ENV_IDS,
    BODY_ENV_IDS,
    ENV_IDS,
    MODULAR_ENV_IDS,
    MODULAR_FLOORS,
    REFERENCE_SEARCHERS,
    modular_decision_dim,
)


def set_acting_threads(threads: int) -> None:
    """Acting is batch-1 inference, and extra torch threads spin against other jobs: beside two
    training runs, a 2-thread actor ran full-body episodes 14x slower than a 1-thread one.
    Snakemake sets OMP_NUM_THREADS itself; this is the default for hand-run commands."""
    check_threads(threads)
    torch.set_num_threads(torch_threads(threads))


def check_threads(threads: int) -> None:
    # torch refuses a negative count with a traceback
    at_least("--threads", threads, 0, "a number of threads (0: all cores)")


MODULAR_RANDOM = {floor: BODY_ENV_IDS[env] for env, floor in MODULAR_FLOORS.items()}
"""The body env each modular floor walks in (:data:`egosearch.sim.envs.MODULAR_FLOORS`)."""


FRONTIER_SEARCHERS = {"frontier": FrontierPolicy, "frontier_head_off": FrontierPolicy,
                      "frontier_tuned": FrontierTunedPolicy, "frontier_tuned_head_off": FrontierTunedPolicy}
"""The classical searchers by name: the untuned one (Table 1's classical rows) and the one tuned on
training-side sets (a bound row of its own); each ``*_head_off`` holds the head fixed (its env has none)."""


def policy_factory(kind: str, weights: str | None, seed: int, env_id: str | None = None, out: str | None = None):
    """(make_policy(env), the env id it acts in): ``env_id`` when given, else the policy's own (a
    trained actor's is the one it was trained in). An actor that cannot act in the env id is refused
    here, before any episode, and so are weights given to a policy that has none; an actor trained at
    another learner profile than the results ``out`` is written beside gets a note."""
    if weights and kind in REFERENCE_SEARCHERS:
        # the oracle, random and frontier searchers would run and the weights be ignored without a word
        raise ValueError(f"--weights={weights} is only read with --policy actor, not --policy {kind}: drop one of "
                         "them")
    check_searcher_env(kind, env_id)
    if kind == "oracle":
        return OraclePolicy, env_id or "EgoSearch-v0"
    if kind == "random":
        return (lambda env: RandomPolicy(env.action_space.shape[0], seed=seed)), env_id or "EgoSearch-v0"
    if kind in FRONTIER_SEARCHERS:
        head_env = "EgoSearchNoHead-v0" if kind.endswith("_head_off") else "EgoSearch-v0"
        return FRONTIER_SEARCHERS[kind], env_id or head_env
    if kind in MODULAR_RANDOM:
        from egosearch.searchers.modular import ModularPolicy  # local: it loads the physics

        def random_decisions(env):
            head = env.unwrapped.spec_agent.head
            return ModularPolicy(RandomPolicy(modular_decision_dim(head), seed=seed), env)

        return random_decisions, env_id or MODULAR_RANDOM[kind]
    if kind == "actor":
        if not weights:
            raise ValueError("--policy actor needs --weights PATH/actor.pt")
        actor = ActorPolicy(weights)
        trained = actor.trained_env_id()
        note_profile(weights, actor, reference_profile(out))
        if trained in BODY_ENV_IDS and env_id in (None, BODY_ENV_IDS[trained]):
            # a modular searcher's decisions act step by step in the body env (ModularPolicy), so that
            # traces, the video and the replanner see every body step
            from egosearch.searchers.modular import ModularPolicy  # local: it loads the physics

            return (lambda env: ModularPolicy(actor, env)), BODY_ENV_IDS[trained]
        env_id = env_id or trained or "EgoSearch-v0"
        actor.check_env(env_id)
        return (lambda env: actor), env_id
    raise ValueError(f"--policy={kind!r}; allowed: oracle, random, {', '.join(FRONTIER_SEARCHERS)}, "
                     f"{', '.join(MODULAR_RANDOM)}, actor")


HEAD_OF_SEARCHER = {"frontier": True, "frontier_head_off": False, "frontier_tuned": True,
                    "frontier_tuned_head_off": False, "modular_random": True, "modular_random_head_off": False}
"""Whether each reference searcher that is named by its head moves the head (the env decides it)."""


def check_searcher_env(kind: str, env_id: str | None) -> None:
    """A reference searcher named by its head runs in an env of that head, and every reference searcher
    acts at the body's steps: in another env it would search otherwise than its name says, and its rows
    would be read under that name (a head-off searcher's with a moving head)."""
    if env_id is None or kind not in REFERENCE_SEARCHERS or env_id not in ALL_ENV_IDS:
        return
    if env_id in MODULAR_ENV_IDS:
        raise ValueError(f"--env-id={env_id} takes a modular searcher's decisions, and --policy {kind} acts at every "
                         "body step: give a body env (EgoSearch-v0 or EgoSearchNoHead-v0), or leave --env-id out")
    wanted, head = HEAD_OF_SEARCHER.get(kind), ENV_IDS[env_id]["head"]
    if wanted is not None and wanted != head:
        other = kind.removesuffix("_head_off") if not wanted else f"{kind}_head_off"
        raise ValueError(f"--env-id={env_id} {'moves' if head else 'fixes'} the head, and --policy {kind} is the "
                         f"searcher with the head {'moving' if wanted else 'fixed'}: its rows would be read under "
                         f"that name; leave --env-id out, or use --policy {other}")


STORED_PROFILE = "cpu"
"""The learner profile of the stored results (Table 1, compare, Figure 7)."""


def reference_profile(out: str | None) -> str:
    """The learner profile of the results an output is read beside: the one of the
    ``results/<profile>/`` folder it is written into (the DAG's jobs), else the stored results'."""
    parts = Path(os.path.abspath(out)).parts if out else ()
    profiles = workflow_config()["profiles"]
    for folder, profile in zip(parts[-3::-1], parts[-2::-1]):  # the innermost results/<profile>/ first
        if folder == "results" and profile in profiles:
            return profiles[profile]["learner"]
    return STORED_PROFILE


def note_profile(weights: str, actor: ActorPolicy, reference: str = STORED_PROFILE) -> None:
    """One note line when the actor was not trained at the ``reference`` learner profile: a smoke
    actor's rows look like any other's, and beside the cpu results they would pass for a poor variant."""
    if not isinstance(actor.config, dict):
        return
    profile, how = learner_profile_of(actor.config, actor.variant)
    if profile not in (None, reference):
        print(f"note: {weights} was trained at the {profile} learner profile ({how}), not at {reference}: do not "
              f"read its results beside the {reference} profile's", file=sys.stderr)
