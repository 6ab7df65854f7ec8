"""``egosearch demos``: the frontier searcher's transitions in a variant's training homes."""

from __future__ import annotations

import json

from egosearch.cli.checks import at_least, check_seed, check_suffix
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.rl.demos import collect_demonstrations, summary_path
from egosearch.rl.run_settings import LONG_RUN_BOUNDS
from egosearch.variants import check_learner_config, long_runs_allowed, parse_set, resolve_variant


def run(args) -> None:
    check_suffix("--out", args.out, (".replay.npz",), "a demonstrations file (git-ignored: hundreds of MB)")
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out, "--out (summary)": str(summary_path(args.out))}, force=args.force)
    if args.episodes is not None:
        at_least("--episodes", args.episodes, 1, "a number of episodes")
        bound, what = LONG_RUN_BOUNDS["demo_episodes"]
        if args.episodes > bound and not long_runs_allowed(args.allow_long):
            raise ValueError(f"--episodes={args.episodes} is out of range; allowed: <= {bound:,} {what}, the "
                             "documented bound; --allow-long allows more")
    check_seed("--seed", args.seed)
    set_overrides = parse_set(args.set)
    resolved = resolve_variant(args.variant, args.preset, {"seed": args.seed}, set_overrides)
    if args.episodes is None:
        check_learner_config(resolved.variant, args.preset, allow_long=args.allow_long, set_overrides=set_overrides)
    episodes = args.episodes if args.episodes is not None else resolved.config.demo_episodes
    if episodes < 1:
        raise ValueError(f"--variant={args.variant} at the {args.preset} preset learns from no demonstrations "
                         "(its demo_episodes is 0): give --episodes N to collect them anyway")
    if resolved.config.modular_searcher:
        # its training could not read them (demo_episodes must be 0 there), and collecting them fails
        # half-way with numpy's reshape error: a decision is not a body step
        raise ValueError(f"--variant={args.variant} at the {args.preset} preset is a modular searcher (its env step "
                         "is a decision, not a body step): demonstrations are the frontier searcher's body steps, "
                         "which it cannot learn from; give a variant that acts at every body step (e.g. "
                         "head_on_from_scratch)")
    summary = collect_demonstrations(resolved.env_id, resolved.config, resolved.train_env, episodes, args.out,
                                     seed=args.seed, variant=resolved.name)
    print(json.dumps(summary))
