"""``egosearch train``: a variant resolved at a learner preset, trained resumably."""

from __future__ import annotations

import json
from pathlib import Path

from egosearch.cli.checks import at_least, check_seed
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.core.staging import publish_run
from egosearch.cost.estimate import training_time_line
from egosearch.envs import observation_kwargs
from egosearch.rl.run_files import CheckpointError, check_same_run
from egosearch.rl.train import train
from egosearch.rl.train_stacked import train_stacked
from egosearch.runs.evaluate import scenario_evaluator
from egosearch.sim.home_pool import curve_homes
from egosearch.variants import check_learner_config, parse_set, resolve_variant


def run(args) -> None:
    if args.stack_seeds is not None:
        run_stacked(args)
        return
    check_outputs(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir})
    check_overwrites(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir}, force=args.force)
    if args.max_wall_s is not None and not args.max_wall_s > 0:
        raise ValueError(f"--max-wall-s must be a positive number of seconds, got {args.max_wall_s}")
    check_seed("--seed", args.seed, numpy_legacy=True)
    at_least("--threads", args.threads, 0, "a number of threads (0: all cores)")
    overrides = {"seed": args.seed, **({"num_threads": args.threads} if args.threads else {})}
    set_overrides = parse_set(args.set)
    resolved = resolve_variant(args.variant, args.preset, overrides, set_overrides)
    check_learner_config(resolved.variant, args.preset, allow_long=args.allow_long, set_overrides=set_overrides)
    env = resolved.train_env
    evaluator = LazyEvaluator(lambda: scenario_evaluator(resolved.env_id, curve_homes(env), env["placement"],
                                                         n=resolved.config.eval_episodes,
                                                         env_kwargs=observation_kwargs(resolved.config.to_dict())))
    if args.work_dir and not args.force:  # the DAG (--force) retrains over its own finished runs
        try:
            check_published_run(Path(args.out_dir), resolved)
        except CheckpointError as err:
            raise ValueError(f"--out-dir: {err}") from None
    line = training_time_line(resolved.config.total_env_steps, args.preset, resolved.config)
    if line:
        print(line, flush=True)
    try:
        summary = train(resolved.env_id, resolved.config, args.work_dir or args.out_dir, env_kwargs=env,
                        evaluate_fn=evaluator, variant=resolved.name, max_wall_s=args.max_wall_s,
                        set_overrides=resolved.set_overrides)
    except CheckpointError as err:
        # another run's folder (variant, preset or seed): the trainer refuses it before writing anything
        raise ValueError(f"{'--work-dir' if args.work_dir else '--out-dir'}: {err}") from None
    finally:
        evaluator.close()
    if args.work_dir and not summary.get("stopped"):
        publish_run(args.work_dir, args.out_dir)
    print(json.dumps(summary))


def check_published_run(out_dir: Path, resolved) -> None:
    """A finished run already in ``out_dir`` is this run's: training in the work folder would publish
    over another run's files, and the trainer, which looks only in the work folder, never sees them."""
    done = out_dir / "done.json"
    if not done.is_file():
        return
    try:
        saved = json.loads(done.read_text())
    except (OSError, ValueError) as err:
        raise CheckpointError(f"cannot read {done} ({type(err).__name__})") from None
    check_same_run("finished run", done, saved, resolved.name, resolved.env_id, resolved.train_env, resolved.config,
                   resolved.set_overrides)


class LazyEvaluator:
    """The curve's evaluator, built at its first call: building it draws its scenarios (seconds),
    which a run the trainer refuses (another run's folder) or finds finished never needs."""

    def __init__(self, make):
        self.make, self.evaluate = make, None

    def __call__(self, policy) -> dict:
        if self.evaluate is None:
            self.evaluate = self.make()
        return self.evaluate(policy)

    def close(self) -> None:
        if self.evaluate is not None:
            self.evaluate.close()


def stacked_seeds(args) -> list[int]:
    """``--stack-seeds``' seeds, checked with the folders it fills (``{seed}`` in each)."""
    try:
        seeds = [int(part) for part in args.stack_seeds.split(",") if part.strip()]
    except ValueError:
        raise ValueError(f"--stack-seeds={args.stack_seeds!r}: comma-separated seeds, e.g. 0,1,2") from None
    if not seeds or len(set(seeds)) != len(seeds):
        raise ValueError(f"--stack-seeds={args.stack_seeds!r}: one or more seeds, none repeated")
    for seed in seeds:
        check_seed("--stack-seeds", seed, numpy_legacy=True)
    if args.seed:
        raise ValueError("--seed and --stack-seeds: give the seeds in --stack-seeds only")
    for option, folder in (("--out-dir", args.out_dir), ("--work-dir", args.work_dir)):
        if folder is not None and "{seed}" not in folder:
            raise ValueError(f"{option}={folder!r}: with --stack-seeds it must hold {{seed}} (one folder per seed), "
                             "e.g. results/paper/train/head_on/seed{seed}")
    return seeds


def run_stacked(args) -> None:
    """``egosearch train --stack-seeds``: the seeds trained in one process, their updates stacked
    (:func:`egosearch.rl.train_stacked.train_stacked`); each seed's folder is the one a separate
    ``egosearch train --seed`` writes."""
    seeds = stacked_seeds(args)
    outs = [args.out_dir.format(seed=s) for s in seeds]
    works = [args.work_dir.format(seed=s) for s in seeds] if args.work_dir else None
    for k, out in enumerate(outs):
        dirs = {"--out-dir": out, "--work-dir": works[k] if works else None}
        check_outputs(dirs=dirs)
        check_overwrites(dirs=dirs, force=args.force)
    if args.max_wall_s is not None and not args.max_wall_s > 0:
        raise ValueError(f"--max-wall-s must be a positive number of seconds, got {args.max_wall_s}")
    at_least("--threads", args.threads, 0, "a number of threads (0: all cores)")
    threads = {"num_threads": args.threads} if args.threads else {}
    set_overrides = parse_set(args.set)
    resolved = [resolve_variant(args.variant, args.preset, {"seed": s, **threads}, set_overrides) for s in seeds]
    check_learner_config(resolved[0].variant, args.preset, allow_long=args.allow_long, set_overrides=set_overrides)
    env = resolved[0].train_env
    evaluators = [LazyEvaluator(lambda r=r: scenario_evaluator(r.env_id, curve_homes(env), env["placement"],
                                                               n=r.config.eval_episodes,
                                                               env_kwargs=observation_kwargs(r.config.to_dict())))
                  for r in resolved]
    if works and not args.force:
        for out, r in zip(outs, resolved):
            try:
                check_published_run(Path(out), r)
            except CheckpointError as err:
                raise ValueError(f"--out-dir: {err}") from None
    try:
        summaries = train_stacked(resolved[0].env_id, [r.config for r in resolved], works or outs, env_kwargs=env,
                                  evaluate_fns=evaluators, variant=resolved[0].name, max_wall_s=args.max_wall_s,
                                  set_overrides=set_overrides)
    except CheckpointError as err:
        raise ValueError(f"{'--work-dir' if works else '--out-dir'}: {err}") from None
    finally:
        for evaluator in evaluators:
            evaluator.close()
    if works and not any(s.get("stopped") for s in summaries):
        for work, out in zip(works, outs):
            publish_run(work, out)
    for summary in summaries:
        print(json.dumps(summary))
