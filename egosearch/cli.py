"""``egosearch <command>``: the entry points users and the Snakefile call.

Every command imports what it needs lazily, so ``egosearch --help`` is instant and the report
commands never load torch or the simulator.
"""

from __future__ import annotations

import argparse
import json
import sys


def _cmd_scenarios(args) -> None:
    from egosearch.scenarios import generate_scenarios, write_scenarios

    scenarios = generate_scenarios(args.layout, args.placement, args.height, args.n, args.seed,
                                   progress=True)
    write_scenarios(args.out, scenarios)
    print(f"wrote {len(scenarios)} scenarios to {args.out}")


def _make_policy_factory(kind: str, weights: str | None, seed: int):
    from egosearch.policies import OraclePolicy, RandomPolicy

    if kind == "oracle":
        return OraclePolicy
    if kind == "random":
        return lambda env: RandomPolicy(env.action_space.shape[0], seed=seed)
    if kind == "actor":
        if not weights:
            raise SystemExit("error: --policy actor needs --weights PATH/actor.pt")
        from egosearch.rl.train import ActorPolicy

        return lambda env: ActorPolicy(weights)
    raise SystemExit(f"error: --policy={kind!r}; allowed: oracle, random, actor")


def _cmd_evaluate(args) -> None:
    from egosearch.evaluate import evaluate, write_episodes
    from egosearch.metrics import spl
    from egosearch.scenarios import read_scenarios

    scenarios = read_scenarios(args.scenarios)
    rows = evaluate(args.env_id, _make_policy_factory(args.policy, args.weights, args.seed),
                    scenarios, seed=args.seed, progress=True, desc=f"evaluate {args.policy}")
    write_episodes(args.out, rows)
    rate = sum(r["success"] for r in rows) / len(rows)
    value = spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                [r["path_length"] for r in rows])
    print(f"{args.policy}: success {rate:.3f}  SPL {value:.3f}  over {len(rows)} episodes -> {args.out}")


def _cmd_bench(args) -> None:
    from egosearch import bench

    if args.what == "env":
        result = bench.bench_env(args.layout, frames=args.frames, steps=args.steps)
    else:
        from egosearch.rl.bench import bench_learner

        result = bench_learner()
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:>28}: {value}")


def _cmd_pictures(args) -> None:
    from egosearch.pictures import make_pictures

    for path in make_pictures(args.layout, args.out_dir, seed=args.seed):
        print(path)


def build_parser() -> argparse.ArgumentParser:
    from egosearch.scene.layouts import LAYOUT_NAMES
    from egosearch.scene.placement import PLACEMENT_SCHEMES

    parser = argparse.ArgumentParser(prog="egosearch", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("scenarios", help="generate a fixed scenario set as CSV")
    p.add_argument("--layout", default="kitchen_living", help=f"{', '.join(LAYOUT_NAMES)} or home<seed>")
    p.add_argument("--placement", default="everywhere", choices=PLACEMENT_SCHEMES)
    p.add_argument("--height", type=float, default=1.65, help="camera height (m)")
    p.add_argument("--n", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True)
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("evaluate", help="run a policy over a scenario CSV -> per-episode CSV")
    p.add_argument("--scenarios", required=True)
    p.add_argument("--policy", default="actor", help="actor, oracle or random")
    p.add_argument("--weights", help="actor.pt written by training (for --policy actor)")
    p.add_argument("--env-id", default="EgoSearch-v0")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True)
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("bench", help="speed benchmarks: env (sensor + physics) or learner")
    p.add_argument("what", choices=("env", "learner"))
    p.add_argument("--layout", default="kitchen_living")
    p.add_argument("--frames", type=int, default=3000)
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_bench)

    p = sub.add_parser("pictures", help="top-down map, placement examples, first/third-person frame")
    p.add_argument("--layout", default="kitchen_living")
    p.add_argument("--out-dir", default="paper_figs/world")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=_cmd_pictures)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except (ValueError, FileNotFoundError) as err:
        # Bad input gets one line, not a traceback.
        print(f"egosearch {args.command}: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
