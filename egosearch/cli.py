"""``egosearch <command>``: the entry points users and the Snakefile call.

Every command imports what it needs lazily, so ``egosearch --help`` is instant and the report
commands never load torch or the simulator.
"""

from __future__ import annotations

import argparse
import json
import sys


def _cmd_scenarios(args) -> None:
    from egosearch.core.outputs import check_outputs
    from egosearch.sim.scenarios import generate_scenarios, write_scenarios

    check_outputs(files={"--out": args.out})

    if args.n < 1:
        raise ValueError(f"--n={args.n}: a scenario set needs at least 1 scenario")
    if args.homes:
        from dataclasses import replace

        first, sep, stop = args.homes.partition(":")
        if not (sep and first.isdigit() and stop.isdigit() and int(first) < int(stop)):
            raise ValueError(f"--homes={args.homes!r}: expected FIRST:STOP, generated home seeds with FIRST < STOP")
        scenarios = []
        for home in range(int(first), int(stop)):  # --n per home, one id sequence over the group
            # the home's seed joins the set's, so that homes do not repeat each other's draws
            for sc in generate_scenarios(f"home{home}", args.placement, args.height, args.n, args.seed + home):
                scenarios.append(replace(sc, scenario_id=len(scenarios)))
    else:
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


def _make_policy_factory(kind: str, weights: str | None, seed: int, env_id: str | None = None):
    """(make_policy(env), the env id it acts in): ``env_id`` when given, else the policy's own (a
    trained actor's is the one it was trained in). An actor that cannot act in the env id is refused
    here, before any episode."""
    from egosearch.searchers.policies import OraclePolicy, RandomPolicy

    if kind == "oracle":
        return OraclePolicy, env_id or "EgoSearch-v0"
    if kind == "random":
        return (lambda env: RandomPolicy(env.action_space.shape[0], seed=seed)), env_id or "EgoSearch-v0"
    if kind in ("frontier", "frontier_head_off"):
        from egosearch.searchers.frontier import FrontierPolicy

        return FrontierPolicy, env_id or ("EgoSearch-v0" if kind == "frontier" else "EgoSearchNoHead-v0")
    if kind == "actor":
        if not weights:
            raise ValueError("--policy actor needs --weights PATH/actor.pt")
        from egosearch.rl.actor import ActorPolicy

        actor = ActorPolicy(weights)
        env_id = env_id or actor.trained_env_id() or "EgoSearch-v0"
        actor.check_env(env_id)
        return (lambda env: actor), env_id
    raise ValueError(f"--policy={kind!r}; allowed: oracle, random, frontier, frontier_head_off, actor")


def _cmd_evaluate(args) -> None:
    from egosearch.core.outputs import check_outputs

    check_outputs(files={"--out": args.out, "--traces": args.traces})
    _acting_threads(args.threads)
    from egosearch.runs.evaluate import evaluate, write_episodes
    from egosearch.runs.metrics import spl
    from egosearch.sim.envs import ENV_IDS
    from egosearch.sim.scenarios import read_scenarios

    if args.env_id and args.env_id not in ENV_IDS:
        raise ValueError(f"--env-id={args.env_id!r}; allowed: {', '.join(ENV_IDS)}")
    make_policy, env_id = _make_policy_factory(args.policy, args.weights, args.seed, env_id=args.env_id)
    scenarios = read_scenarios(args.scenarios)
    recorder = None
    if args.traces:
        from egosearch.runs.trace import TraceRecorder

        if not args.traces.endswith(".npz"):
            raise ValueError(f"--traces={args.traces!r}: a trace file must end in .npz")
        recorder = TraceRecorder()
    rows = evaluate(env_id, make_policy, scenarios, seed=args.seed, progress=True,
                    desc=f"evaluate {args.policy} on {env_id}", recorder=recorder)
    write_episodes(args.out, rows)
    if recorder is not None:
        print(f"wrote {recorder.write(args.traces)}: {len(recorder.columns['step'])} steps of {len(rows)} episodes")
    rate = sum(r["success"] for r in rows) / len(rows)
    value = spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                [r["path_length"] for r in rows])
    print(f"{args.policy}: success {rate:.3f}  SPL {value:.3f}  over {len(rows)} episodes -> {args.out}")


def _cmd_train(args) -> None:
    from egosearch.core.outputs import check_outputs
    from egosearch.rl.config import load_config
    from egosearch.rl.train import train
    from egosearch.runs.evaluate import scenario_evaluator
    from egosearch.variants import load_variant

    check_outputs(dirs={"--out-dir": args.out_dir, "--work-dir": args.work_dir})
    if args.max_wall_s is not None and not args.max_wall_s > 0:
        raise ValueError(f"--max-wall-s must be a positive number of seconds, got {args.max_wall_s}")
    variant = load_variant(args.variant)
    overrides = {**variant.config, "seed": args.seed}
    if args.threads:
        overrides["num_threads"] = args.threads
    cfg = load_config(args.profile, overrides)
    env = variant.train_env
    from egosearch.sim.envs import observed_env_id
    from egosearch.sim.home_pool import curve_homes

    env_id = observed_env_id(variant.env_id, cfg.target_memory)
    evaluator = scenario_evaluator(env_id, curve_homes(env), env["placement"], n=cfg.eval_episodes)
    try:
        summary = train(env_id, cfg, args.work_dir or args.out_dir, env_kwargs=env, evaluate_fn=evaluator,
                        variant=variant.name, max_wall_s=args.max_wall_s)
    finally:
        evaluator.close()
    if args.work_dir and not summary.get("stopped"):
        from egosearch.core.staging import publish_run

        publish_run(args.work_dir, args.out_dir)
    print(json.dumps(summary))


def _cmd_fullbody(args) -> None:
    from egosearch.core.outputs import check_outputs

    check_outputs(files={"--out": args.out})
    _acting_threads(args.threads)
    from egosearch.motion.replan import evaluate_fullbody, parse_setting, write_fullbody
    from egosearch.sim.scenarios import read_scenarios

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


def _report_outputs(args) -> None:
    """Every path a report writes, checked before it reads anything."""
    from egosearch.core.outputs import check_outputs

    check_outputs(files={"--out": getattr(args, "out", None), "--out-csv": getattr(args, "out_csv", None),
                         "--readme": None if args.what != "readme" or args.check else args.readme},
                  dirs={"--out-dir": getattr(args, "out_dir", None)},
                  prefixes={"--out-prefix": getattr(args, "out_prefix", None)})


def _cmd_report(args) -> None:
    from egosearch.report import cli as report

    _report_outputs(args)

    if args.what == "table1":
        report.cmd_table1(args.files, args.out_prefix, variant=args.variant, bounds=args.bounds)
    elif args.what == "table2":
        from egosearch.rl.config import departure_rows, load_config, table2_rows

        cfg = load_config(args.profile)
        report.cmd_table2(table2_rows(cfg), args.out_prefix, departure_rows(cfg))
    elif args.what == "fig6":
        report.cmd_fig6(_group_curves(args.files), args.out_prefix, random_files=args.random)
    elif args.what == "fig7":
        report.cmd_fig7(args.files, args.out_prefix, planner=args.planner)
    elif args.what == "budget":
        from egosearch.report.budget import budget_figure, budget_frame

        runs: dict[str, list[tuple[str, str]]] = {}
        for spec in args.run:
            setting, sep, files = spec.partition("=")
            curve, sep2, evals = files.partition(":")
            if not (sep and sep2 and setting and curve and evals):
                raise ValueError(f"--run {spec!r}: expected SETTING=CURVE_CSV:EVAL_CSV")
            runs.setdefault(setting, []).append((curve, evals))
        for path in budget_figure(budget_frame(runs), args.out_prefix, chosen=args.chosen):
            print(f"wrote {path}")
    elif args.what == "generalise":
        from egosearch.report.generalise import generalise_report

        trained_on = dict(item.partition("=")[::2] for item in args.trained_on)
        for path in generalise_report(args.files, args.bounds, args.out_prefix, trained_on, args.generated,
                                      reference=args.reference):
            print(f"wrote {path}")
    elif args.what == "fresh":
        from egosearch.report.fresh import fresh_report

        for path in fresh_report(args.stored, args.fresh, args.out_prefix, args.variant, args.fresh_seed):
            print(f"wrote {path}")
    elif args.what == "pathlength":
        report.cmd_pathlength(args.files, args.scenarios, _success_radius(), args.out_prefix, out_csv=args.out_csv,
                              bounds=args.bounds or [])
    elif args.what == "compare":
        report.cmd_compare(args.reference, args.candidate, args.out, reference_name="reference",
                           candidate_name="candidate")
    elif args.what == "behaviour":
        from egosearch.report.behaviour import behaviour_report

        for path in behaviour_report(args.files, args.out_prefix, head_on=args.head_on, head_off=args.head_off):
            print(f"wrote {path}")
    elif args.what == "searches":
        from egosearch.report.searches import searches_report

        for path in searches_report(args.files, args.out_dir, seed=args.seed):
            print(f"wrote {path}")
    elif args.what == "provenance":
        from egosearch.report.provenance import write_provenance

        record = write_provenance(args.profile, args.results, args.out, note=args.note or "")
        # The same line whether the record was rewritten or kept (no stored file changed): the
        # workflow commits this log, and a rerun that changes nothing must leave it as it was.
        print(f"{args.out}: sha256 of {len(record['files'])} stored files, {len(record['jobs'])} jobs, "
              f"{record['wall_s_all_jobs_summed']} s summed")
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
        from egosearch.report.readme import pages, update_pages, update_readme

        if args.readme:
            checked = [args.readme]
            stale = [] if update_readme(args.readme, args.profile, check=args.check) else checked
        else:
            checked, stale = pages("."), update_pages(".", args.profile, check=args.check)
            if not checked:
                raise ValueError("no README.md and no docs/*.md here: run it in the project's root, or give --readme")
        names = ", ".join(str(page) for page in (stale or checked))
        if not stale:
            print(f"{names}: results blocks match results/{args.profile} and paper_figs/{args.profile}")
        elif args.check:
            raise ValueError(f"{names} out of date with the stored results; "
                             f"run `egosearch report readme --profile {args.profile}`")
        else:
            print(f"rewrote the results blocks of {names} from the {args.profile} results")


def _success_radius() -> float:
    """Distance (m) from a target's centre to the body's axis within which success is possible: success is
    measured from the body's surface (egosearch.sim.scenarios.SUCCESS_DISTANCE), so the body's radius adds."""
    from egosearch.sim.agent import AgentSpec
    from egosearch.sim.scenarios import SUCCESS_DISTANCE

    return SUCCESS_DISTANCE + AgentSpec().body_radius


def _regenerate(profile: str, reference: str | None) -> None:
    """Tables and figures from the CSVs already in results/<profile>/: seconds, no training. The
    variants and the reference come from the workflow config, as in the DAG, so regenerating gives
    the files `snakemake all` would."""
    from pathlib import Path

    from egosearch.core.outputs import check_outputs
    from egosearch.report import cli as report
    from egosearch.report.provenance import check_stored
    from egosearch.report.readme import variants_of_all, workflow_config
    from egosearch.report.tables import BOUNDS
    from egosearch.rl.config import departure_rows, load_config, table2_rows
    from egosearch.sim.home_pool import curve_homes
    from egosearch.variants import load_variant

    config = workflow_config()
    if profile not in config["profiles"]:
        raise ValueError(f"--profile={profile!r}; allowed: {', '.join(config['profiles'])}")
    reference = reference or config["reference_variant"]
    results, figs = Path("results") / profile, Path("paper_figs") / profile
    check_outputs(dirs={"the figures folder": figs, "the path-length folder": results / "pathlength"})
    # Table 1's homes only, as the DAG's rules: eval/ also holds the generalisation groups
    homes = set(config["homes"])
    evals = sorted(str(p) for p in (results / "eval" / reference).glob("seed*/*/*/h*.csv")
                   if Path(p).parts[-3] in homes)
    curves = {v: sorted(str(p) for p in (results / "train" / v).glob("seed*/curve.csv"))
              for v in variants_of_all(config)}
    curves = {v: paths for v, paths in curves.items() if paths}
    fullbody = sorted(str(p) for p in (results / "fullbody").glob("*/seed*.csv"))
    fullbody_oracle = sorted(str(p) for p in (results / "fullbody_oracle").glob("*/seed*.csv"))
    bounds = sorted(str(p) for b in BOUNDS for p in (results / "eval" / b).glob("seed*/*/*/h*.csv")
                    if Path(p).parts[-3] in homes)
    # Figure 6's random level: the cells the reference is evaluated in while training (as in the DAG).
    train_env = load_variant(reference).train_env
    fig6_random = [p for p in bounds if Path(p).parts[-5] == "random" and Path(p).parts[-2] == train_env["placement"]
                   and Path(p).parts[-3] in curve_homes(train_env)]
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
    scenarios = sorted(str(p) for home in homes for p in (results / "scenarios" / home).glob("*/h*.csv"))
    for variant in variants_of_all(config):
        variant_evals = sorted(str(p) for p in (results / "eval" / variant).glob("seed*/*/*/h*.csv")
                               if Path(p).parts[-3] in homes)
        if variant_evals and scenarios:
            report.cmd_pathlength(variant_evals, scenarios, _success_radius(), figs / f"pathlength_{variant}",
                                  out_csv=results / "pathlength" / f"{variant}.csv", bounds=bounds)
    learner = config["profiles"][profile]["learner"]
    learner_cfg = load_config(learner)
    report.cmd_table2(table2_rows(learner_cfg), figs / "table2", departure_rows(learner_cfg))


def _cmd_video(args) -> None:
    from egosearch.core.outputs import check_outputs

    check_outputs(files={"--out": args.out, "--still": args.still})
    _acting_threads(args.threads)
    from egosearch.motion.video import NotACleanSuccess, clean_successes, write_search_video
    from egosearch.sim.scenarios import read_scenarios

    scenarios = {sc.scenario_id: sc for sc in read_scenarios(args.scenarios)}
    candidates = []
    if args.first_success:
        import pandas as pd

        candidates = [i for i in clean_successes(pd.read_csv(args.first_success), args.min_steps) if i in scenarios]
        if not candidates:
            print(f"note: no episode of {args.first_success} succeeded in >= {args.min_steps} steps with no "
                  f"penetrating pose; filming scenario {args.scenario_id} instead")
    if not candidates and args.scenario_id not in scenarios:
        raise ValueError(f"--scenario-id={args.scenario_id} is not in {args.scenarios}")
    make_policy, env_id = _make_policy_factory(args.policy, args.weights, args.seed)
    row = None
    # Seeded as `egosearch fullbody` seeds scenario k (--seed + k), the film replays the CSV's episode;
    # should the replay differ, the film takes the next candidate rather than show a penetration.
    for scenario_id in candidates:
        try:
            row = write_search_video(scenarios[scenario_id].layout, args.character, make_policy,
                                     scenarios[scenario_id], args.out, still_path=args.still, M=args.M, T=args.T,
                                     seed=args.seed + scenario_id, env_id=env_id, require_clean=True)
            break
        except NotACleanSuccess as err:
            print(f"note: the replay differs from {args.first_success}: {err}; trying the next scenario")
    if row is None:
        if candidates:
            raise ValueError(f"no episode of {args.first_success} replayed as a success with no penetrating pose")
        scenario = scenarios[args.scenario_id]
        row = write_search_video(scenario.layout, args.character, make_policy, scenario, args.out,
                                 still_path=args.still, M=args.M, T=args.T, seed=args.seed + args.scenario_id,
                                 env_id=env_id)
    print(f"{args.character}: scenario {row['scenario_id']}, success {row['success']} in {row['steps']} steps, "
          f"{row['penetrations']} penetrating pose(s) -> {args.out}, {args.still}")


def _cmd_bench(args) -> None:
    from egosearch.core.outputs import check_outputs
    from egosearch.sim import bench

    check_outputs(files={"--out": args.out}, dirs={"--out-dir": args.out_dir})
    if args.what == "gpu" and not args.out_dir:
        raise ValueError("bench gpu needs --out-dir (the paper-profile training's folder)")
    if args.what == "gpu" and not args.seconds > 0:
        raise ValueError(f"--seconds must be a positive number, got {args.seconds}")
    if not args.baseline_seconds >= 0:
        raise ValueError(f"--baseline-seconds must be a number >= 0, got {args.baseline_seconds}")

    def run() -> dict:
        if args.what == "env":
            return bench.bench_env(args.layout, frames=args.frames, steps=args.steps)
        if args.what == "homes":
            return bench.bench_homes()
        if args.what == "gpu":
            from egosearch.rl.bench import gpu_check

            return gpu_check(args.seconds, args.out_dir, overrides={"cuda_graph": True} if args.cuda_graph else None,
                             baseline_seconds=args.baseline_seconds)
        from egosearch.rl.bench import bench_learner

        return bench_learner()

    options = f" --layout {args.layout} --frames {args.frames} --steps {args.steps}" if args.what == "env" else ""
    if args.what == "gpu":
        options = f" --seconds {args.seconds:g}" + (" --cuda-graph" if args.cuda_graph else "") + (
            f" --baseline-seconds {args.baseline_seconds:g}" if args.baseline_seconds else "")
    record = bench.recorded(f"egosearch bench {args.what}{options}", run)
    result = record["result"]
    if args.out:
        from pathlib import Path

        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out} (other processes used {record['other_load_cores']} cores meanwhile)",
              file=sys.stderr)
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:>28}: {value}")


def _cmd_pictures(args) -> None:
    from egosearch.core.outputs import check_outputs
    from egosearch.sim.pictures import make_pictures

    check_outputs(dirs={"--out-dir": args.out_dir})

    for path in make_pictures(args.layout, args.out_dir, seed=args.seed):
        print(path)


def _cmd_variant(args) -> None:
    from egosearch.variants import check_learner_config, load_variant, new_variant

    if args.what == "new":
        from egosearch.core.outputs import check_outputs
        from egosearch.variants import ABLATIONS_DIR

        check_outputs(dirs={"the variants folder": ABLATIONS_DIR})
        path = new_variant(args.name, template=args.template)
        print(f"wrote {path}: edit it, then `snakemake --cores 2 compare --config variant={args.name}`")
        return
    for name in args.names:
        variant = load_variant(name)
        for profile in args.profile:
            check_learner_config(variant, profile)
        print(f"{variant.path}: valid at the {', '.join(args.profile)} learner profile(s)")


def _report_parsers(sub) -> None:
    """One sub-command per report, each with its own options and ``--help``."""
    p = sub.add_parser("report", help="tables, figures, comparisons and provenance from result CSVs")
    reports = p.add_subparsers(dest="what", required=True, metavar="REPORT")
    profile = dict(default="cpu", help="profile: smoke, cpu or paper (default: cpu)")
    prefix = "output path without extension, or a folder (writes {})"

    r = reports.add_parser("table1", help="Table 1 (success per height and placement) from evaluation CSVs")
    r.add_argument("files", nargs="+", help="evaluation CSVs of one variant: .../{variant}/seed{seed}/{layout}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md, .csv and .tex"))
    r.add_argument("--variant", help="the variant of the files (default: read from their paths)")
    r.add_argument("--bounds", nargs="*", help="evaluation CSVs of the random searcher and the oracle "
                                               "(.../eval/{random,oracle}/...): rows that bound the policy")

    r = reports.add_parser("table2", help="Table 2 (learner settings) from a learner profile")
    r.add_argument("--profile", **profile)
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md and .tex"))

    r = reports.add_parser("fig6", help="Figure 6 (success vs env steps) from training curves")
    r.add_argument("files", nargs="+", help="curve.csv files: .../train/{variant}/seed{seed}/curve.csv")
    r.add_argument("--random", nargs="*", help="evaluation CSVs of the random searcher: its level, dashed")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))

    r = reports.add_parser("fig7", help="Figure 7 (SPL and attempts per method) from full-body CSVs")
    r.add_argument("files", nargs="+", help="full-body CSVs: .../{setting}/seed{seed}.csv")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))
    r.add_argument("--planner", default="actor", choices=("actor", "oracle"),
                   help="which planner drove the full-body runs (oracle figures say so in a title)")

    r = reports.add_parser("budget", help="the budget study: success at one cell vs env steps and core-hours")
    r.add_argument("--run", action="append", required=True, metavar="SETTING=CURVE_CSV:EVAL_CSV",
                   help="one training run of a setting: its curve.csv and its per-episode CSV at the cell "
                        "(repeat per seed and setting)")
    r.add_argument("--chosen", help="the setting the profile uses (drawn filled)")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))

    r = reports.add_parser("compare", help="a candidate variant vs the reference: difference, 95%% CI, p per cell "
                                           "and per shortest-path bin")
    r.add_argument("--reference", nargs="+", required=True, help="the reference variant's evaluation CSVs")
    r.add_argument("--candidate", nargs="+", required=True, help="the candidate variant's evaluation CSVs")
    r.add_argument("--out", help="write the comparison to this CSV (and the split by shortest path ℓ, every cell "
                                 "pooled, to <out stem>_by_length.csv) as well as printing them")

    r = reports.add_parser("pathlength", help="success by shortest path ℓ and by detour, with two-level intervals")
    r.add_argument("files", nargs="+", help="evaluation CSVs of one variant: .../{variant}/seed{seed}/{home}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--scenarios", nargs="+", required=True, help="the scenario sets they ran: .../scenarios/{home}/"
                                                                 "{placement}/h{height}.csv")
    r.add_argument("--bounds", nargs="*", help="the reference searchers' evaluation CSVs on the same scenarios "
                                               "(.../eval/{random,frontier,oracle}/...): a line each")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md, .png and .pdf"))
    r.add_argument("--out-csv", help="the numbers (default: <out-prefix>.csv)")

    r = reports.add_parser("generalise", help="trained-on x evaluated-on: normalised scores per group of homes")
    r.add_argument("files", nargs="+", help="evaluation CSVs of the policies: .../{variant}/seed{seed}/{group}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--bounds", nargs="+", required=True, help="the random searcher's and the oracle's evaluation "
                                                              "CSVs on the same groups")
    r.add_argument("--generated", help="the variant trained in generated homes (its gap to its training split)")
    r.add_argument("--reference", help="the variant trained in the paper homes: the generated-homes variant's "
                                       "score there is read against it")
    r.add_argument("--trained-on", nargs="*", default=[], metavar="VARIANT=HOMES",
                   help="what each variant trained in, for the labels")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".csv, .md and .png"))

    r = reports.add_parser("fresh", help="the reference on its stored scenario sets against fresh sets of the same "
                                         "cells: is a gain tuned to the stored sets?")
    r.add_argument("--stored", nargs="+", required=True, help="evaluation CSVs on the stored sets: .../{variant}/"
                                                              "seed{seed}/{home}/{placement}/h{height}.csv")
    r.add_argument("--fresh", nargs="+", required=True, help="the same actors' evaluation CSVs on the fresh sets")
    r.add_argument("--variant", default="head_on", help="the variant, for the caption (default: head_on)")
    r.add_argument("--fresh-seed", type=int, help="the fresh sets' scenario seed, for the caption")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".csv and .md"))

    traces = "trace files of `egosearch evaluate --traces`: .../{variant}/seed{seed}/{layout}/{placement}/h{height}.npz"
    r = reports.add_parser("behaviour", help="how the policies search, from per-step traces, and the paper's "
                                             "behaviour sentences (Section 6.3, Figure 6) read against them")
    r.add_argument("files", nargs="+", help=traces)
    r.add_argument("--head-on", default="head_on", help="the variant that moves its head (default: head_on)")
    r.add_argument("--head-off", default="head_off", help="the variant without head movement (default: head_off)")
    r.add_argument("--out-prefix", required=True,
                   help=prefix.format("_episodes.csv, .csv, .md, _claims.csv and _claims.md"))

    r = reports.add_parser("searches", help="top-down pictures of chosen searches and a gaze heatmap per cell, "
                                            "from per-step traces")
    r.add_argument("files", nargs="+", help=traces)
    r.add_argument("--seed", type=int, default=0, help="the seed whose files give the pictured searches (default 0)")
    r.add_argument("--out-dir", required=True, help="folder of the PNGs")

    r = reports.add_parser("provenance", help="commit, machine, date and job wall times of a results folder")
    r.add_argument("--profile", **profile)
    r.add_argument("--results", default="results/cpu", help="the results folder (default: results/cpu)")
    r.add_argument("--out", required=True, help="the provenance JSON to write")
    r.add_argument("--note", help="free text kept in the record (e.g. how the run was resumed)")

    r = reports.add_parser("regenerate", help="every table and figure from the stored CSVs of a profile (seconds)")
    r.add_argument("--profile", **profile)
    r.add_argument("--variant", help="the variant of Table 1 (default: the workflow config's reference_variant)")

    r = reports.add_parser("verify", help="check every stored result file against the sha256 in its provenance")
    r.add_argument("--profile", **profile)

    r = reports.add_parser("readme", help="rewrite the generated blocks of the README and the docs pages from the "
                                          "stored results")
    r.add_argument("--profile", **profile)
    r.add_argument("--readme", help="the one page whose marked blocks are rewritten (default: README.md and every "
                                    "docs/*.md page of the current folder)")
    r.add_argument("--check", action="store_true", help="only check that the blocks are up to date (exit 2 if not)")
    p.set_defaults(func=_cmd_report)


def build_parser() -> argparse.ArgumentParser:
    from egosearch.scene.layouts import LAYOUT_NAMES
    from egosearch.scene.placement import PLACEMENT_SCHEMES
    from egosearch.sim.agent import EVAL_HEIGHTS, HEIGHT_RANGE

    parser = argparse.ArgumentParser(prog="egosearch", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    layouts = f"{', '.join(LAYOUT_NAMES)} or home<seed> (a generated home)"
    threads = "torch threads for acting (default 1; 0: all cores)"
    policy_seed = "seed of the random policy and of the env's per-step noise (default 0)"

    p = sub.add_parser("scenarios", help="generate a fixed scenario set as CSV")
    p.add_argument("--layout", default="kitchen_living", help=f"home: {layouts}")
    p.add_argument("--placement", default="everywhere", choices=PLACEMENT_SCHEMES,
                   help="where targets may be: every support surface, or none inside low cabinets")
    p.add_argument("--height", type=float, default=1.65,
                   help=f"camera height (m): any value in [{HEIGHT_RANGE[0]}, {HEIGHT_RANGE[1]}] is a valid "
                        f"experiment; Table 1 uses {', '.join(f'{h:g}' for h in EVAL_HEIGHTS)} (default 1.65)")
    p.add_argument("--n", type=int, default=100, help="number of scenarios (per home with --homes; default 100)")
    p.add_argument("--homes", default=None, metavar="FIRST:STOP",
                   help="instead of --layout: generated homes home<FIRST> ... home<STOP-1>, --n scenarios each, "
                        "in one set (the generalisation benchmark's groups)")
    p.add_argument("--seed", type=int, default=0, help="seed of the set: the same seed gives the same rows")
    p.add_argument("--out", required=True, help="the scenario CSV to write")
    p.set_defaults(func=_cmd_scenarios)

    p = sub.add_parser("evaluate", help="run a policy over a scenario CSV -> per-episode CSV")
    p.add_argument("--scenarios", required=True, help="a scenario CSV written by `egosearch scenarios`")
    p.add_argument("--policy", default="actor", help="actor (with --weights), oracle (privileged: knows the "
                                                     "target), random, or frontier / frontier_head_off (the "
                                                     "classical searcher, head moving or fixed)")
    p.add_argument("--weights", help="actor.pt written by `egosearch train` (for --policy actor)")
    p.add_argument("--env-id", help="default: the actor's own env id; EgoSearch-v0 for oracle/random/frontier, "
                                    "EgoSearchNoHead-v0 for frontier_head_off")
    p.add_argument("--seed", type=int, default=0, help=policy_seed)
    p.add_argument("--out", required=True, help="the per-episode CSV to write (one row per scenario)")
    p.add_argument("--traces", metavar="FILE.npz", help="also write every step of every episode (pose, head, action, "
                                                        "what the camera's centre looks at, distances) to this "
                                                        "compressed file (egosearch.runs.trace)")
    p.add_argument("--threads", type=int, default=1, help=threads)
    p.set_defaults(func=_cmd_evaluate)

    p = sub.add_parser("train", help="train a variant's search policy with SAC+CURL (resumable)")
    p.add_argument("--variant", required=True, help="a file stem in ablations/ (head_on, head_off, ...)")
    p.add_argument("--profile", default="cpu", help="learner profile: smoke, cpu or paper (default: cpu)")
    p.add_argument("--seed", type=int, default=0, help="training seed (default 0)")
    p.add_argument("--threads", type=int, default=0, help="torch threads (0: all cores)")
    p.add_argument("--out-dir", required=True, help="run folder: actor.pt, curve.csv, train.csv, checkpoint; "
                                                    "rerun with the same folder to resume")
    p.add_argument("--work-dir", help="train (and resume) here, and copy the files to --out-dir only once the run "
                                      "is complete (the DAG does: a killed job never leaves a partial output)")
    p.add_argument("--max-wall-s", type=float, help="stop after this many seconds with a checkpoint written (inside "
                                                    "a cluster's time limit); the same command resumes it")
    p.set_defaults(func=_cmd_train)

    p = sub.add_parser("variant", help="create a variant file in ablations/ from a template, or check variants")
    variants = p.add_subparsers(dest="what", required=True, metavar="ACTION")
    v = variants.add_parser("new", help="write ablations/NAME.yaml, a copy of a template with name: NAME")
    v.add_argument("name", help="the new variant's name (letters, digits, _ and -)")
    v.add_argument("--from", dest="template", default="head_on", help="the variant to copy (default: head_on)")
    v = variants.add_parser("check", help="check variant files, learner config included, before running them")
    v.add_argument("names", nargs="+", help="variant names (files in ablations/) or paths of .yaml files")
    v.add_argument("--profile", nargs="+", default=["smoke", "cpu", "paper"],
                   help="learner profiles to check the config against (default: all three)")
    p.set_defaults(func=_cmd_variant)

    p = sub.add_parser("fullbody", help="full-body search (Algorithm 1 or a baseline) -> per-episode CSV")
    p.add_argument("--setting", required=True,
                   help="ours-M<M>-<mg>, one_step_short-<mg>, one_step_long-<mg> or noisy_search-<mg>; "
                        "<mg>: humanoid_phase, humanoid_matching or fetch")
    p.add_argument("--policy", default="actor",
                   help="the planner: actor (with --weights), or oracle (privileged: knows the target) or random")
    p.add_argument("--weights", help="actor.pt of the search policy (for --policy actor)")
    p.add_argument("--scenarios", required=True, help="a scenario CSV written by `egosearch scenarios`")
    p.add_argument("--limit", type=int, default=0, help="use the first N scenarios (0: all)")
    p.add_argument("--T", type=int, default=20, help="planning horizon (default 20)")
    p.add_argument("--seed", type=int, default=0, help=policy_seed)
    p.add_argument("--out", required=True, help="the per-episode CSV to write")
    p.add_argument("--threads", type=int, default=1, help=threads)
    p.set_defaults(func=_cmd_fullbody)

    p = sub.add_parser("bench", help="speed benchmarks: env (sensor + physics), homes (building one) or learner")
    p.add_argument("what", choices=("env", "homes", "learner", "gpu"),
                   help="env: sensor frames/s and env steps/s on one core; homes: a generated home's build time "
                        "against a training episode; learner: SAC+CURL updates/s; gpu: the learner benchmarks and "
                        "a paper-profile training of --seconds on this machine's GPU (results/paper/gpu_check)")
    p.add_argument("--layout", default="kitchen_living", help=f"env: the home ({layouts})")
    p.add_argument("--frames", type=int, default=3000, help="env: sensor frames to time (default 3000)")
    p.add_argument("--steps", type=int, default=3000, help="env: env steps to time (default 3000)")
    p.add_argument("--seconds", type=float, default=150.0, help="gpu: the training's wall time (default 150)")
    p.add_argument("--out-dir", help="gpu: the training's folder (curve.csv, train.csv, config.json, checkpoint)")
    p.add_argument("--cuda-graph", action="store_true",
                   help="gpu: train with the update recorded as CUDA graphs (learner.cuda_graph=true, which the "
                        "paper profile sets anyway)")
    p.add_argument("--baseline-seconds", type=float, default=0.0,
                   help="gpu: also train this long with the update launched eagerly (cuda_graph false; in "
                        "<out-dir>/baseline), for the ratio on one machine")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", help="also write the result as JSON with the command, date, commit, CPU and the machine's "
                                 "load (e.g. results/cpu/bench/learner.json, which the docs' Speed page reads)")
    p.set_defaults(func=_cmd_bench)

    p = sub.add_parser("video", help="a video of one full-body search: first-person depth + third-person view")
    p.add_argument("--character", default="humanoid_phase", help="humanoid_phase, humanoid_matching or fetch")
    p.add_argument("--scenarios", required=True, help="a scenario CSV written by `egosearch scenarios`")
    p.add_argument("--scenario-id", type=int, default=0, help="the scenario_id of the row to search (default 0)")
    p.add_argument("--first-success", metavar="FULLBODY_CSV",
                   help="film the first scenario (by scenario_id) that succeeded in this full-body CSV of the same "
                        "settings with no penetrating pose, in at least --min-steps steps (instead of --scenario-id, "
                        "which is filmed when none did)")
    p.add_argument("--min-steps", type=int, default=0,
                   help="--first-success: the fewest steps of a filmed episode (default 0)")
    p.add_argument("--policy", default="actor", help="actor (with --weights), oracle or random")
    p.add_argument("--weights", help="actor.pt of the search policy")
    p.add_argument("--M", type=int, default=5, help="steps executed per plan")
    p.add_argument("--T", type=int, default=20, help="planning horizon")
    p.add_argument("--seed", type=int, default=0,
                   help="scenario k's episode is seeded with this + k, as `egosearch fullbody` seeds it (default 0)")
    p.add_argument("--out", required=True, help=".mp4 or .gif")
    p.add_argument("--still", required=True, help=".png of the moment the target is found")
    p.add_argument("--threads", type=int, default=1, help=threads)
    p.set_defaults(func=_cmd_video)

    _report_parsers(sub)

    p = sub.add_parser("pictures", help="top-down map, placement examples, first/third-person frame")
    p.add_argument("--layout", default="kitchen_living", help=f"home: {layouts}")
    p.add_argument("--out-dir", default="paper_figs/world", help="folder of the PNGs (default: paper_figs/world)")
    p.add_argument("--seed", type=int, default=0, help="seed of the placement examples (default 0)")
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
