"""What the commands that run searches share: the acting threads and the policy a ``--policy`` names."""

from __future__ import annotations

import torch

from egosearch.rl.actor import ActorPolicy
from egosearch.rl.train import torch_threads
from egosearch.searchers.frontier import FrontierPolicy
from egosearch.searchers.policies import OraclePolicy, RandomPolicy


def set_acting_threads(threads: int) -> None:
    """Acting is batch-1 inference, and extra torch threads spin against other jobs: beside two
    training runs, a 2-thread actor ran full-body episodes 14x slower than a 1-thread one.
    Snakemake sets OMP_NUM_THREADS itself; this is the default for hand-run commands."""
    torch.set_num_threads(torch_threads(threads))


def policy_factory(kind: str, weights: str | None, seed: int, env_id: str | None = None):
    """(make_policy(env), the env id it acts in): ``env_id`` when given, else the policy's own (a
    trained actor's is the one it was trained in). An actor that cannot act in the env id is refused
    here, before any episode."""
    if kind == "oracle":
        return OraclePolicy, env_id or "EgoSearch-v0"
    if kind == "random":
        return (lambda env: RandomPolicy(env.action_space.shape[0], seed=seed)), env_id or "EgoSearch-v0"
    if kind in ("frontier", "frontier_head_off"):
        return FrontierPolicy, env_id or ("EgoSearch-v0" if kind == "frontier" else "EgoSearchNoHead-v0")
    if kind == "actor":
        if not weights:
            raise ValueError("--policy actor needs --weights PATH/actor.pt")
        actor = ActorPolicy(weights)
        env_id = env_id or actor.trained_env_id() or "EgoSearch-v0"
        actor.check_env(env_id)
        return (lambda env: actor), env_id
    raise ValueError(f"--policy={kind!r}; allowed: oracle, random, frontier, frontier_head_off, actor")
