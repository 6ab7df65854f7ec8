"""Several seeds of one variant trained in one process, their updates stacked
(:mod:`egosearch.rl.stacked`; issue 47, item 4).

``train_stacked(env_id, cfgs, out_dirs)`` runs one :class:`egosearch.rl.train.LiveRun` per seed:
each has its own envs, replay, CSV logs, evaluator, checkpoint and actor files in its own folder,
written exactly as :func:`egosearch.rl.train.train` writes them (the same paths,
``results/<preset>/train/<variant>/seed<k>/``, and the same formats), and each draws from its own
random streams (:class:`egosearch.rl.stacked.SeedStreams`: every torch, numpy and python draw of seed
``k``, acting, sampling and the update's, is made from seed ``k``'s states, which its checkpoint
saves). Only the gradient updates are one stacked model. The seeds step in lockstep, so they share
every checkpoint's step, and a seed's checkpoint is a separate run's: killing the process and
running the same call again resumes every seed (as ``train`` does; a seed already finished is left
out of the stack). What runs per seed, in turn: imitation before RL, acting, env steps, evaluations.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import torch

from egosearch.core.allocator import keep_freed_memory
from egosearch.envs import observation_kwargs, observed_env_id
from egosearch.rl.config import LearnerConfig
from egosearch.rl.stacked import SeedStreams, StackingError, check_stackable, stack_agents
from egosearch.rl.train import LiveRun, default_evaluator, open_run, torch_threads
from egosearch.rl.train_env import make_train_env, train_env_kwargs

Evaluator = Callable[[Any], dict]


def same_but_seed(cfgs: list[LearnerConfig]) -> None:
    """Refuse configs that differ in anything but their seed (the stack is one architecture and one
    schedule), or that repeat a seed."""
    plain = [{k: v for k, v in cfg.to_dict().items() if k != "seed"} for cfg in cfgs]
    different = sorted({k for p in plain[1:] for k in p if p[k] != plain[0].get(k)})
    if different:
        raise StackingError("stacked seeds must share their config but for the seed; these differ: "
                            + ", ".join(different))
    seeds = [cfg.seed for cfg in cfgs]
    if len(set(seeds)) != len(seeds):
        raise StackingError(f"a seed is repeated: {seeds}")


def train_stacked(env_id: str, cfgs: list[LearnerConfig], out_dirs: list[str | Path], env_kwargs: dict | None = None,
                  evaluate_fns: list[Evaluator] | None = None, *, variant: str | None = None, progress: bool = True,
                  on_step: Callable[[int], None] | None = None, max_wall_s: float | None = None,
                  set_overrides: dict | None = None) -> list[dict]:
    """Train (or resume) seed ``cfgs[k].seed`` into ``out_dirs[k]`` for every k, the updates stacked;
    returns each seed's summary, as :func:`egosearch.rl.train.train` returns it (``"stopped": True``
    after ``max_wall_s``). ``evaluate_fns[k]`` evaluates seed k's policy (default: one
    :func:`egosearch.rl.train.default_evaluator` each). ``on_step(env_steps)`` is called after every
    round of env steps (tests use it to interrupt the process). ``set_overrides``: the command line's ``--set``
    fields, as :func:`egosearch.rl.train.train` records and checks them."""
    if not cfgs or len(cfgs) != len(out_dirs) or (evaluate_fns is not None and len(evaluate_fns) != len(cfgs)):
        raise ValueError("one config, one out_dir (and one evaluator, if any) per seed")
    cfgs = [cfg.validate() for cfg in cfgs]
    same_but_seed(cfgs)
    check_stackable(cfgs[0])
    env_id = observed_env_id(env_id, cfgs[0].target_memory, cfgs[0].modular_searcher)
    env_kwargs = dict(env_kwargs or {})
    variant = variant or env_id
    dirs = [Path(d) for d in out_dirs]
    opened = [open_run(env_id, cfg, d, env_kwargs, variant, set_overrides) for cfg, d in zip(cfgs, dirs)]
    summaries: list[dict | None] = [done for done, _ in opened]
    todo = [k for k, (done, _) in enumerate(opened) if done is None]
    if not todo:
        return [s for s in summaries if s is not None]
    steps = {int(opened[k][1]["env_steps"]) if opened[k][1] is not None else 0 for k in todo}
    if len(steps) > 1:
        raise StackingError("the seeds' checkpoints are at different env steps "
                            f"({sorted(steps)}): stacked seeds step together; train them separately")

    cfg = cfgs[todo[0]]
    threads_before = torch.get_num_threads()
    torch.set_num_threads(torch_threads(cfg.num_threads))
    keep_freed_memory()
    envs: list[list] = []
    own = [evaluate_fns is None] * len(cfgs)
    evaluators = list(evaluate_fns) if evaluate_fns is not None else [
        default_evaluator(env_id, {**env_kwargs, **observation_kwargs(c.to_dict())}, c.eval_episodes) for c in cfgs]
    try:
        for _ in todo:
            envs.append([make_train_env(env_id, train_env_kwargs(cfg, env_kwargs)) for _ in range(cfg.num_envs)])
        done = _train_stacked([cfgs[k] for k in todo], [dirs[k] for k in todo], envs, env_id, env_kwargs, variant,
                              [opened[k][1] for k in todo], [evaluators[k] for k in todo], on_step, max_wall_s,
                              progress, set_overrides)
        for k, summary in zip(todo, done):
            summaries[k] = summary
        return [s for s in summaries if s is not None]
    finally:
        for seed_envs in envs:
            for env in seed_envs:
                env.close()
        for evaluate, mine in zip(evaluators, own):
            if mine:
                evaluate.close()
        torch.set_num_threads(threads_before)


def _train_stacked(cfgs: list[LearnerConfig], dirs: list[Path], envs: list[list], env_id: str, env_kwargs: dict,
                   variant: str, ckpts: list[dict | None], evaluators: list[Evaluator],
                   on_step: Callable[[int], None] | None, max_wall_s: float | None, progress: bool,
                   set_overrides: dict | None = None) -> list[dict]:
    """The loop of :func:`egosearch.rl.train.train`'s ``_train``, the seeds in turn for everything
    but the updates, which are stacked."""
    runs: list[LiveRun] = []
    streams: SeedStreams | None = None
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=cfgs[0].total_env_steps, unit="step", dynamic_ncols=True, mininterval=1.0,
                   desc=f"{variant} seeds {','.join(str(c.seed) for c in cfgs)} stacked")
    write = bar.write if bar is not None else functools.partial(print, flush=True)
    for cfg, d, seed_envs, ckpt in zip(cfgs, dirs, envs, ckpts):
        # LiveRun seeds the global generators and builds the agent as a separate run does; what
        # they hold after it (a resumed run: the checkpoint's states) becomes this seed's stream
        run = LiveRun(seed_envs, env_id, cfg, d, env_kwargs, variant, ckpt, set_overrides=set_overrides)
        run.say = lambda line, seed=cfg.seed: write(f"[seed {seed}] {line}")
        streams = streams or SeedStreams(run.device)
        streams.capture()
        runs.append(run)
    assert streams is not None
    try:
        return _loop(runs, streams, cfgs, evaluators, on_step, max_wall_s, bar)
    finally:
        if bar is not None:
            bar.close()


def _loop(runs: list[LiveRun], streams: SeedStreams, cfgs: list[LearnerConfig], evaluators: list[Evaluator],
          on_step: Callable[[int], None] | None, max_wall_s: float | None, bar: Any) -> list[dict]:
    """Imitation and the step-0 evaluation seed by seed, then the rounds: every seed's env steps in
    turn, the stacked updates, then each seed's logs, evaluations and checkpoints."""
    last_rows: list[dict | None] = [None] * len(runs)
    for k, run in enumerate(runs):
        with streams.stream(k):
            run.open_progress(False)
            run.start_clock()
            if run.step == 0 and run.curve.rows() == 0:
                run.imitate()
                run.write_start_actor()
                last_rows[k] = run.evaluate(evaluators[k])
    # stacked after imitation: the clones' weights are where the stacked parameters start
    stack = stack_agents([run.agent for run in runs], streams)
    cfg, first = cfgs[0], runs[0]
    if bar is not None:
        bar.update(first.step)  # a resumed run's steps so far
    t_start = time.perf_counter()
    while first.step < cfg.total_env_steps:
        before = first.step
        for k, run in enumerate(runs):
            with streams.stream(k):
                live = run.envs[: cfg.total_env_steps - run.step]
                run.step_and_store(live, run.actions(live))
        for _ in range(max(run.updates_due(before) for run in runs)):
            batches = []
            for k, run in enumerate(runs):
                with streams.stream(k):
                    batches.append(run.sample())
            for run, metrics in zip(runs, stack.update(batches)):
                run.record(metrics)
        checkpoint = first.crossed(cfg.checkpoint_every, before)
        stop = (max_wall_s is not None and first.step < cfg.total_env_steps
                and time.perf_counter() - t_start >= max_wall_s)
        if checkpoint or stop:
            stack.sync_members()  # the stacked optimiser states into each seed's agent state
        for k, run in enumerate(runs):
            with streams.stream(k):
                last_rows[k] = run.log_evaluate_checkpoint(before, evaluators[k], checkpoint) or last_rows[k]
        if bar is not None:
            bar.update(first.step - before)
        if on_step is not None:
            on_step(first.step)
        if stop:
            summaries = []
            for k, run in enumerate(runs):
                with streams.stream(k):
                    run.save_checkpoint()
                    summaries.append({**run.stopped(), "stacked_seeds": [c.seed for c in cfgs]})
            return summaries
    stack.sync_members()
    summaries = []
    for k, run in enumerate(runs):
        with streams.stream(k):
            summaries.append(run.finish(last_rows[k]))
    return summaries
