"""``egosearch train``: a variant resolved at a learner profile, trained resumably."""

from __future__ import annotations

import json

from egosearch.core.outputs import check_outputs
from egosearch.core.staging import publish_run
from egosearch.rl.train import train
from egosearch.runs.evaluate import scenario_evaluator
from egosearch.sim.home_pool import curve_homes
from egosearch.variants import resolve_variant


def run(args) -> None:
    check_outputs(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir})
    if args.max_wall_s is not None and not args.max_wall_s > 0:
        raise ValueError(f"--max-wall-s must be a positive number of seconds, got {args.max_wall_s}")
    overrides = {"seed": args.seed, **({"num_threads": args.threads} if args.threads else {})}
    resolved = resolve_variant(args.variant, args.profile, overrides)
    env = resolved.train_env
    evaluator = scenario_evaluator(resolved.env_id, curve_homes(env), env["placement"],
                                   n=resolved.config.eval_episodes)
    try:
        summary = train(resolved.env_id, resolved.config, args.work_dir or args.out_dir, env_kwargs=env,
                        evaluate_fn=evaluator, variant=resolved.name, max_wall_s=args.max_wall_s)
    finally:
        evaluator.close()
    if args.work_dir and not summary.get("stopped"):
        publish_run(args.work_dir, args.out_dir)
    print(json.dumps(summary))
