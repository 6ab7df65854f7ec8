"""``egosearch train``: a variant resolved at a learner profile, trained resumably."""

from __future__ import annotations

import json
from pathlib import Path

from egosearch.cli.checks import at_least, check_seed
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.core.staging import publish_run
from egosearch.cost.estimate import training_time_line
from egosearch.rl.run_files import CheckpointError, check_same_run
from egosearch.rl.train import train
from egosearch.runs.evaluate import scenario_evaluator
from egosearch.sim.home_pool import curve_homes
from egosearch.variants import resolve_variant


def run(args) -> None:
    check_outputs(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir})
    check_overwrites(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir}, force=args.force)
    if args.max_wall_s is not None and not args.max_wall_s > 0:
        raise ValueError(f"--max-wall-s must be a positive number of seconds, got {args.max_wall_s}")
    check_seed("--seed", args.seed, numpy_legacy=True)
    at_least("--threads", args.threads, 0, "a number of threads (0: all cores)")
    overrides = {"seed": args.seed, **({"num_threads": args.threads} if args.threads else {})}
    resolved = resolve_variant(args.variant, args.profile, overrides)
    env = resolved.train_env
    evaluator = LazyEvaluator(lambda: scenario_evaluator(resolved.env_id, curve_homes(env), env["placement"],
                                                         n=resolved.config.eval_episodes))
    if args.work_dir and not args.force:  # the DAG (--force) retrains over its own finished runs
        try:
            check_published_run(Path(args.out_dir), resolved)
        except CheckpointError as err:
            raise ValueError(f"--out-dir: {err}") from None
    line = training_time_line(resolved.config.total_env_steps, args.profile, resolved.config)
    if line:
        print(line, flush=True)
    try:
        summary = train(resolved.env_id, resolved.config, args.work_dir or args.out_dir, env_kwargs=env,
                        evaluate_fn=evaluator, variant=resolved.name, max_wall_s=args.max_wall_s)
    except CheckpointError as err:
        # another run's folder (variant, profile or seed): the trainer refuses it before writing anything
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
    check_same_run("finished run", done, saved, resolved.name, resolved.env_id, resolved.train_env, resolved.config)


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
