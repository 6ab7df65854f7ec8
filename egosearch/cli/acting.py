"""What the commands that run searches share: the acting threads and the policy a ``--policy`` names."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import torch

from egosearch.cli.checks import at_least, learner_preset_of
from egosearch.envs import ALL_ENV_IDS, env_options
from egosearch.report.workflow_jobs import workflow_config
from egosearch.rl.actor import ActorPolicy
from egosearch.rl.train import torch_threads
from egosearch.searchers import searcher_registry as searchers
from egosearch.searchers.decision_envs import BODY_ENV_IDS


def set_acting_threads(threads: int) -> None:
    """Acting is batch-1 inference, and extra torch threads spin against other jobs: beside two
    training runs, a 2-thread actor ran full-body episodes 14x slower than a 1-thread one.
    Snakemake sets OMP_NUM_THREADS itself; this is the default for hand-run commands."""
    check_threads(threads)
    torch.set_num_threads(torch_threads(threads))


def check_threads(threads: int) -> None:
    # torch refuses a negative count with a traceback
    at_least("--threads", threads, 0, "a number of threads (0: all cores)")


def policy_factory(kind: str, weights: str | None, seed: int, env_id: str | None = None, out: str | None = None,
                   env_kwargs: dict | None = None):
    """(make_policy(env), the env id it acts in, the env's observation options): ``env_id`` when given,
    else the policy's own (a registered searcher's, :mod:`egosearch.searchers.searcher_registry`; a trained actor's
    is the one it was trained in), and the options a trained actor's file records with ``env_kwargs`` (the
    caller's, :data:`egosearch.envs.OBSERVATION_OPTIONS`) on top. An actor that cannot act in the env id
    with those options is refused here, before any episode, and so are weights given to a policy that has
    none; an actor trained at another learner preset than the results ``out`` is written beside gets a
    note."""
    given = dict(env_kwargs or {})
    if kind in searchers.SEARCHERS:
        if weights:
            # a searcher that is not learned would run and the weights be ignored without a word
            raise ValueError(f"--weights={weights} is only read with --policy {searchers.ACTOR}, not --policy {kind}: "
                             "drop one of them")
        searcher = searchers.get(kind)
        check_searcher_env(kind, env_id)
        unread = [name for name in given if name not in searcher.observation_options]
        if unread:
            reads = (f"it reads only {', '.join(searcher.observation_options)}" if searcher.observation_options
                     else "it reads no observation option: it acts on the env's own state, not on the policy's "
                          "observation")
            raise ValueError(f"--env-option {unread[0]}: --policy {kind} would ignore it ({reads}); leave "
                             "--env-option out, or give it with --policy actor")
        return searcher.maker(seed), env_id or searcher.env_id, given
    if kind == searchers.ACTOR:
        if not weights:
            raise ValueError("--policy actor needs --weights PATH/actor.pt")
        actor = ActorPolicy(weights)
        trained = actor.trained_env_id()
        note_preset(weights, actor, reference_preset(out))
        options = {**actor.env_kwargs, **given}
        if trained in BODY_ENV_IDS and env_id in (None, BODY_ENV_IDS[trained]):
            # a modular searcher's decisions act step by step in the body env (ModularPolicy), so that
            # traces, the video and the replanner see every body step
            from egosearch.searchers.modular import ModularPolicy  # local: it loads the physics

            return (lambda env: ModularPolicy(actor, env)), BODY_ENV_IDS[trained], given
        env_id = env_id or trained or "EgoSearch-v0"
        actor.check_env(env_id, options)
        return (lambda env: actor), env_id, options
    raise ValueError(f"--policy={kind!r}; allowed: {', '.join(searchers.names())}, {searchers.ACTOR}")


def check_searcher_env(kind: str, env_id: str | None) -> None:
    """A registered searcher named by its head runs in an env of that head, and every registered searcher
    acts at the body's steps: in another env it would search otherwise than its name says, and its rows
    would be read under that name (a head-off searcher's with a moving head)."""
    if env_id is None or kind not in searchers.SEARCHERS or env_id not in ALL_ENV_IDS:
        return
    if env_options(env_id).modular:
        raise ValueError(f"--env-id={env_id} takes a modular searcher's decisions, and --policy {kind} acts at every "
                         "body step: give a body env (EgoSearch-v0 or EgoSearchNoHead-v0), or leave --env-id out")
    wanted, head = searchers.get(kind).head, env_options(env_id).head
    if wanted is not None and wanted != head:
        # the same searcher with the other head, where one is registered (the same policy factory)
        factory = searchers.get(kind).factory
        others = [s.name for s in searchers.SEARCHERS.values() if s.head == head and s.factory == factory]
        hint = f", or use --policy {others[0]}" if others else ""
        raise ValueError(f"--env-id={env_id} {'moves' if head else 'fixes'} the head, and --policy {kind} is the "
                         f"searcher with the head {'moving' if wanted else 'fixed'}: its rows would be read under "
                         f"that name; leave --env-id out{hint}")


STORED_PRESET = "cpu"
"""The learner preset of the stored results (Table 1, compare, Figure 7)."""


def reference_preset(out: str | None) -> str:
    """The learner preset of the results an output is read beside: the one of the
    ``results/<preset>/`` folder it is written into (the DAG's jobs), else the stored results'."""
    parts = Path(os.path.abspath(out)).parts if out else ()
    presets = workflow_config()["presets"]
    for folder, preset in zip(parts[-3::-1], parts[-2::-1]):  # the innermost results/<preset>/ first
        if folder == "results" and preset in presets:
            return presets[preset]["learner"]
    return STORED_PRESET


def note_preset(weights: str, actor: ActorPolicy, reference: str = STORED_PRESET) -> None:
    """One note line when the actor was not trained at the ``reference`` learner preset: a smoke
    actor's rows look like any other's, and beside the cpu results they would pass for a poor variant."""
    if not isinstance(actor.config, dict):
        return
    preset, how = learner_preset_of(actor.config, actor.variant)
    if preset not in (None, reference):
        print(f"note: {weights} was trained at the {preset} learner preset ({how}), not at {reference}: do not "
              f"read its results beside the {reference} preset's", file=sys.stderr)
