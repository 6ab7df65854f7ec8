"""``egosearch demos``: the frontier searcher's transitions in a variant's training homes."""

from __future__ import annotations

import json

from egosearch.cli.checks import at_least, check_seed, check_suffix
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.rl.demos import collect_demonstrations, summary_path
from egosearch.variants import resolve_variant


def run(args) -> None:
    check_suffix("--out", args.out, (".replay.npz",), "a demonstrations file (git-ignored: hundreds of MB)")
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out, "--out (summary)": str(summary_path(args.out))}, force=args.force)
    at_least("--episodes", args.episodes, 1, "a number of episodes")
    check_seed("--seed", args.seed)
    resolved = resolve_variant(args.variant, args.profile, {"seed": args.seed})
    summary = collect_demonstrations(resolved.env_id, resolved.config, resolved.train_env, args.episodes, args.out,
                                     seed=args.seed)
    print(json.dumps(summary))
