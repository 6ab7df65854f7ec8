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


def _acting_threads(threads: int) -> None:
    """Acting is batch-1 inference, and extra torch threads spin against other jobs: beside two
    training runs, a 2-thread actor ran full-body episodes 14x slower than a 1-thread one.
    Snakemake sets OMP_NUM_THREADS itself; this is the default for hand-run commands."""
    import torch

    from egosearch.rl.train import torch_threads

    torch.set_num_threads(torch_threads(threads))


def _make_policy_factory(kind: str, weights: str | None, seed: int):
    """(make_policy(env), the env id it acts in): a trained actor knows its own env id."""
    from egosearch.policies import OraclePolicy, RandomPolicy

    if kind == "oracle":
        return OraclePolicy, "EgoSearch-v0"
    if kind == "random":
        return (lambda env: RandomPolicy(env.action_space.shape[0], seed=seed)), "EgoSearch-v0"
    if kind == "actor":
        if not weights:
            raise ValueError("--policy actor needs --weights PATH/actor.pt")
        from egosearch.rl.train import ActorPolicy

        actor = ActorPolicy(weights)
        return (lambda env: actor), actor.env_id or "EgoSearch-v0"
    raise ValueError(f"--policy={kind!r}; allowed: oracle, random, actor")


def _cmd_evaluate(args) -> None:
    _acting_threads(args.threads)
    from egosearch.evaluate import evaluate, write_episodes
    from egosearch.metrics import spl
    from egosearch.scenarios import read_scenarios

    scenarios = read_scenarios(args.scenarios)
    make_policy, env_id = _make_policy_factory(args.policy, args.weights, args.seed)
    env_id = args.env_id or env_id
    rows = evaluate(env_id, make_policy, scenarios, seed=args.seed, progress=True,
                    desc=f"evaluate {args.policy} on {env_id}")
    write_episodes(args.out, rows)
    rate = sum(r["success"] for r in rows) / len(rows)
    value = spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                [r["path_length"] for r in rows])
    print(f"{args.policy}: success {rate:.3f}  SPL {value:.3f}  over {len(rows)} episodes -> {args.out}")


def _cmd_train(args) -> None:
    from egosearch.evaluate import scenario_evaluator
    from egosearch.rl.config import load_config
    from egosearch.rl.train import train
    from egosearch.variants import load_variant

    variant = load_variant(args.variant)
    overrides = {**variant.config, "seed": args.seed}
    if args.threads:
        overrides["num_threads"] = args.threads
    cfg = load_config(args.profile, overrides)
    env = variant.train_env
    evaluator = scenario_evaluator(variant.env_id, env["layout"], env["placement"], n=cfg.eval_episodes)
    try:
        summary = train(variant.env_id, cfg, args.work_dir or args.out_dir, env_kwargs=env, evaluate_fn=evaluator,
                        variant=variant.name)
    finally:
        evaluator.close()
    if args.work_dir:
        from egosearch.staging import publish_run

        publish_run(args.work_dir, args.out_dir)
    print(json.dumps(summary))


def _cmd_fullbody(args) -> None:
    _acting_threads(args.threads)
    from egosearch.motion.replan import evaluate_fullbody, parse_setting, write_fullbody
    from egosearch.scenarios import read_scenarios

    method, m, mg = parse_setting(args.setting)
    make_policy, env_id = _make_policy_factory(args.policy, args.weights, args.seed)
    scenarios = read_scenarios(args.scenarios)[: args.limit or None]
    rows = evaluate_fullbody(env_id, make_policy, scenarios, method=method, mg_name=mg, M=m, T=args.T,
                             seed=args.seed, progress=True)
    write_fullbody(args.out, rows)
    rate = sum(r["success"] for r in rows) / len(rows)
    print(f"{args.setting} ({args.policy}): success {rate:.3f} over {len(rows)} episodes -> {args.out}")


def _group_curves(paths: list[str]) -> dict[str, list[str]]:
    """``.../train/{variant}/seed{seed}/curve.csv`` grouped by variant, in first-seen order."""
    from pathlib import Path

    groups: dict[str, list[str]] = {}
    for path in paths:
        groups.setdefault(Path(path).parent.parent.name, []).append(path)
    return groups


def _cmd_report(args) -> None:
    from egosearch.report import cli as report

    if args.what == "table1":
        report.cmd_table1(args.files, args.out_prefix, variant=args.variant, bounds=args.bounds)
    elif args.what == "table2":
        from egosearch.rl.config import load_config, table2_rows

        report.cmd_table2(table2_rows(load_config(args.profile)), args.out_prefix)
    elif args.what == "fig6":
        report.cmd_fig6(_group_curves(args.files), args.out_prefix, random_files=args.random)
    elif args.what == "fig7":
        report.cmd_fig7(args.files, args.out_prefix, planner=args.planner)
    elif args.what == "compare":
        if not args.reference or not args.candidate:
            raise ValueError("compare needs --reference CSV... and --candidate CSV...")
        report.cmd_compare(args.reference, args.candidate, args.out, reference_name="reference",
                           candidate_name="candidate")
    elif args.what == "provenance":
        from egosearch.report.provenance import write_provenance

        record = write_provenance(args.profile, args.results, args.out, note=args.note or "")
        print(f"wrote {args.out}: {len(record['jobs'])} jobs, {record['wall_s_all_jobs_summed']} s summed")
    elif args.what == "regenerate":
        _regenerate(args.profile, args.variant)
    elif args.what == "verify":
        from egosearch.report.provenance import verify

        results = f"results/{args.profile}"
        ok, problems = verify(results)
        for problem in problems:
            print(problem, file=sys.stderr)
        if problems:
            raise ValueError(f"{len(problems)} stored file(s) of {results} differ from the sha256 list of "
                             f"{results}/provenance.json ({ok} match)")
        print(f"{results}: all {ok} stored files match the sha256 recorded in {results}/provenance.json")
    elif args.what == "readme":
        from egosearch.report.readme import update_readme

        if update_readme(args.readme, args.profile, check=args.check):
            print(f"{args.readme}: results blocks match results/{args.profile} and paper_figs/{args.profile}")
        elif args.check:
            raise ValueError(f"{args.readme} is out of date with the stored results; "
                             f"run `egosearch report readme --profile {args.profile}`")
        else:
            print(f"rewrote the results blocks of {args.readme} from the {args.profile} results")


def _regenerate(profile: str, reference: str | None) -> None:
    """Tables and figures from the CSVs already in results/<profile>/: seconds, no training. The
    variants and the reference come from the workflow config, as in the DAG, so regenerating gives
    the files `snakemake all` would."""
    from pathlib import Path

    from egosearch.report import cli as report
    from egosearch.report.provenance import check_stored
    from egosearch.report.readme import variants_of_all, workflow_config
    from egosearch.report.tables import BOUNDS
    from egosearch.rl.config import load_config, table2_rows
    from egosearch.variants import load_variant

    config = workflow_config()
    if profile not in config["profiles"]:
        raise ValueError(f"--profile={profile!r}; allowed: {', '.join(config['profiles'])}")
    reference = reference or config["reference_variant"]
    results, figs = Path("results") / profile, Path("paper_figs") / profile
    evals = sorted(str(p) for p in (results / "eval" / reference).glob("seed*/*/*/h*.csv"))
    curves = {v: sorted(str(p) for p in (results / "train" / v).glob("seed*/curve.csv"))
              for v in variants_of_all(config)}
    curves = {v: paths for v, paths in curves.items() if paths}
    fullbody = sorted(str(p) for p in (results / "fullbody").glob("*/seed*.csv"))
    fullbody_oracle = sorted(str(p) for p in (results / "fullbody_oracle").glob("*/seed*.csv"))
    bounds = sorted(str(p) for b in BOUNDS for p in (results / "eval" / b).glob("seed*/*/*/h*.csv"))
    # Figure 6's random level: the cells of the scheme the reference is evaluated in while training (as in the DAG).
    train_placement = load_variant(reference).train_env["placement"]
    fig6_random = [p for p in bounds if Path(p).parts[-2] == train_placement and Path(p).parts[-5] == "random"]
    if not (evals or curves or fullbody or fullbody_oracle):
        raise FileNotFoundError(f"no stored results under {results}/ (eval, train or fullbody)")
    read = [*evals, *bounds, *(p for paths in curves.values() for p in paths), *fullbody, *fullbody_oracle]
    if check_stored(read, require_record=True):
        print(f"note: {results}/provenance.json has no sha256 list: the stored files are used unverified")
    figs.mkdir(parents=True, exist_ok=True)
    if evals:
        report.cmd_table1(evals, figs / "table1", variant=reference, bounds=bounds)
    if curves:
        report.cmd_fig6(curves, figs / "fig6", random_files=fig6_random)
    if fullbody:
        report.cmd_fig7(fullbody, figs / "fig7")
    if fullbody_oracle:
        report.cmd_fig7(fullbody_oracle, figs / "fig7_oracle", planner="oracle")
    learner = config["profiles"][profile]["learner"]
    report.cmd_table2(table2_rows(load_config(learner)), figs / "table2")


def _cmd_video(args) -> None:
    _acting_threads(args.threads)
    from egosearch.motion.video import write_search_video
    from egosearch.scenarios import read_scenarios

    scenarios = {sc.scenario_id: sc for sc in read_scenarios(args.scenarios)}
    if args.scenario_id not in scenarios:
        raise ValueError(f"--scenario-id={args.scenario_id} is not in {args.scenarios}")
    scenario = scenarios[args.scenario_id]
    make_policy, env_id = _make_policy_factory(args.policy, args.weights, args.seed)
    row = write_search_video(scenario.layout, args.character, make_policy, scenario, args.out,
                             still_path=args.still, M=args.M, T=args.T, seed=args.seed, env_id=env_id)
    print(f"{args.character}: success {row['success']} in {row['steps']} steps -> {args.out}, {args.still}")


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
    p.add_argument("--env-id", help="default: the actor's own env id; EgoSearch-v0 for oracle/random")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True)
    p.add_argument("--threads", type=int, default=1, help="torch threads for acting (0: all cores)")
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("train", help="train a variant's search policy with SAC+CURL (resumable)")
    p.add_argument("--variant", required=True, help="a file stem in ablations/ (head_on, head_off, ...)")
    p.add_argument("--profile", default="cpu", help="smoke, cpu or paper")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=0, help="torch threads (0: all cores)")
    p.add_argument("--out-dir", required=True)
    p.add_argument("--work-dir", help="train (and resume) here, and copy the files to --out-dir only once the run "
                                      "is complete (the DAG does: a killed job never leaves a partial output)")
    p.set_defaults(func=_cmd_train)

    p = sub.add_parser("fullbody", help="full-body search (Algorithm 1 or a baseline) -> per-episode CSV")
    p.add_argument("--setting", required=True,
                   help="ours-M<M>-<mg>, one_step_short-<mg>, one_step_long-<mg> or noisy_search-<mg>")
    p.add_argument("--policy", default="actor",
                   help="the planner: actor (with --weights), or oracle (privileged: knows the target) or random")
    p.add_argument("--weights", help="actor.pt of the search policy (for --policy actor)")
    p.add_argument("--scenarios", required=True)
    p.add_argument("--limit", type=int, default=0, help="use the first N scenarios (0: all)")
    p.add_argument("--T", type=int, default=20, help="planning horizon")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True)
    p.add_argument("--threads", type=int, default=1, help="torch threads for acting (0: all cores)")
    p.set_defaults(func=_cmd_fullbody)

    p = sub.add_parser("bench", help="speed benchmarks: env (sensor + physics) or learner")
    p.add_argument("what", choices=("env", "learner"))
    p.add_argument("--layout", default="kitchen_living")
    p.add_argument("--frames", type=int, default=3000)
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_bench)

    p = sub.add_parser("video", help="a video of one full-body search: first-person depth + third-person view")
    p.add_argument("--character", default="humanoid_phase", help="humanoid_phase, humanoid_matching or fetch")
    p.add_argument("--scenarios", required=True)
    p.add_argument("--scenario-id", type=int, default=0)
    p.add_argument("--policy", default="actor", help="actor (with --weights), oracle or random")
    p.add_argument("--weights", help="actor.pt of the search policy")
    p.add_argument("--M", type=int, default=5, help="steps executed per plan")
    p.add_argument("--T", type=int, default=20, help="planning horizon")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True, help=".mp4 or .gif")
    p.add_argument("--still", required=True, help=".png of the moment the target is found")
    p.add_argument("--threads", type=int, default=1, help="torch threads for acting (0: all cores)")
    p.set_defaults(func=_cmd_video)

    p = sub.add_parser("report", help="tables, figures, comparisons and provenance from result CSVs")
    p.add_argument("what", choices=("table1", "table2", "fig6", "fig7", "compare", "provenance", "regenerate",
                                    "readme", "verify"))
    p.add_argument("files", nargs="*", help="input CSVs (table1: evaluation CSVs; fig6: curve.csv; fig7: full-body)")
    p.add_argument("--out-prefix", help="output path without extension")
    p.add_argument("--bounds", nargs="*", help="table1: evaluation CSVs of the random searcher and the oracle")
    p.add_argument("--random", nargs="*", help="fig6: evaluation CSVs of the random searcher (a dashed level)")
    p.add_argument("--variant", help="table1/regenerate: the variant of the evaluation CSVs (regenerate: default "
                                     "the config's reference)")
    p.add_argument("--profile", default="cpu", help="table2/provenance/regenerate/readme: smoke, cpu or paper")
    p.add_argument("--reference", nargs="*", help="compare: the reference variant's evaluation CSVs")
    p.add_argument("--candidate", nargs="*", help="compare: the new variant's evaluation CSVs")
    p.add_argument("--results", default="results/cpu", help="provenance: the results folder")
    p.add_argument("--out", help="compare/provenance: output file")
    p.add_argument("--note", help="provenance: free text kept in the record (e.g. how the run was resumed)")
    p.add_argument("--planner", default="actor", choices=("actor", "oracle"),
                   help="fig7: which planner drove the full-body runs (oracle figures say so in a title)")
    p.add_argument("--readme", default="README.md", help="readme: the file whose marked results blocks are rewritten")
    p.add_argument("--check", action="store_true", help="readme: only check that the blocks are up to date")
    p.set_defaults(func=_cmd_report)

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
