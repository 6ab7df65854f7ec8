"""``egosearch report <REPORT>``: tables, figures, comparisons and provenance from result CSVs.

Never loads torch: the report layer reads files only; Table 2 reads the learner config (plain data).
One report per function; :data:`REPORTS` maps each ``REPORT`` name to it.
"""

from __future__ import annotations

import sys
from pathlib import Path

from egosearch.core.outputs import check_outputs
from egosearch.report import cli as report
from egosearch.report.behaviour import behaviour_report
from egosearch.report.budget import budget_figure, budget_frame
from egosearch.report.fresh import fresh_report
from egosearch.report.generalise import generalise_report
from egosearch.report.provenance import check_stored, verify, write_provenance
from egosearch.report.readme import pages, update_pages, update_readme
from egosearch.report.searches import searches_report
from egosearch.report.workflow_jobs import bound_eval_files, variants_of_all, workflow_config, workflow_heights
from egosearch.rl.config import departure_rows, load_config, table2_rows


def run(args) -> None:
    check_report_outputs(args)
    REPORTS[args.what](args)


def check_report_outputs(args) -> None:
    """Every path a report writes, checked before it reads anything."""
    check_outputs(files={"--out": getattr(args, "out", None), "--out-csv": getattr(args, "out_csv", None),
                         "--readme": None if args.what != "readme" or args.check else args.readme},
                  dirs={"--out-dir": getattr(args, "out_dir", None)},
                  prefixes={"--out-prefix": getattr(args, "out_prefix", None)})


def curves_by_variant(paths: list[str]) -> dict[str, list[str]]:
    """``.../train/{variant}/seed{seed}/curve.csv`` grouped by variant, in first-seen order."""
    groups: dict[str, list[str]] = {}
    for path in paths:
        groups.setdefault(Path(path).parent.parent.name, []).append(path)
    return groups


def success_radius() -> float:
    """Distance (m) from a target's centre to the body's axis within which success is possible: success is
    measured from the body's surface (egosearch.sim.scenarios.SUCCESS_DISTANCE), so the body's radius adds."""
    # local: the simulator's modules load trimesh (~2 s); only the path-length reports need the body's size
    from egosearch.sim.agent import AgentSpec
    from egosearch.sim.scenarios import SUCCESS_DISTANCE

    return SUCCESS_DISTANCE + AgentSpec().body_radius


def _table1(args) -> None:
    report.cmd_table1(args.files, args.out_prefix, variant=args.variant, bounds=args.bounds)


def _table2(args) -> None:
    cfg = load_config(args.profile)
    report.cmd_table2(table2_rows(cfg), args.out_prefix, departure_rows(cfg))


def _fig6(args) -> None:
    report.cmd_fig6(curves_by_variant(args.files), args.out_prefix, random_files=args.random)


def _fig7(args) -> None:
    report.cmd_fig7(args.files, args.out_prefix, planner=args.planner)


def _budget(args) -> None:
    runs: dict[str, list[tuple[str, str]]] = {}
    for spec in args.run:
        setting, sep, files = spec.partition("=")
        curve, sep2, evals = files.partition(":")
        if not (sep and sep2 and setting and curve and evals):
            raise ValueError(f"--run {spec!r}: expected SETTING=CURVE_CSV:EVAL_CSV")
        runs.setdefault(setting, []).append((curve, evals))
    for path in budget_figure(budget_frame(runs), args.out_prefix, chosen=args.chosen):
        print(f"wrote {path}")


def _generalise(args) -> None:
    trained_on = dict(item.partition("=")[::2] for item in args.trained_on)
    for path in generalise_report(args.files, args.bounds, args.out_prefix, trained_on, args.generated,
                                  reference=args.reference):
        print(f"wrote {path}")


def _fresh(args) -> None:
    for path in fresh_report(args.stored, args.fresh, args.out_prefix, args.variant, args.fresh_seed):
        print(f"wrote {path}")


def _pathlength(args) -> None:
    report.cmd_pathlength(args.files, args.scenarios, success_radius(), args.out_prefix, out_csv=args.out_csv,
                          bounds=args.bounds or [])


def _compare(args) -> None:
    report.cmd_compare(args.reference, args.candidate, args.out, reference_name="reference",
                       candidate_name="candidate")


def _behaviour(args) -> None:
    for path in behaviour_report(args.files, args.out_prefix, head_on=args.head_on, head_off=args.head_off):
        print(f"wrote {path}")


def _searches(args) -> None:
    for path in searches_report(args.files, args.out_dir, seed=args.seed):
        print(f"wrote {path}")


def _provenance(args) -> None:
    record = write_provenance(args.profile, args.results, args.out, note=args.note or "")
    # The same line whether the record was rewritten or kept (no stored file changed): the
    # workflow commits this log, and a rerun that changes nothing must leave it as it was.
    print(f"{args.out}: sha256 of {len(record['files'])} stored files, {len(record['jobs'])} jobs, "
          f"{record['wall_s_all_jobs_summed']} s summed")


def _regenerate(args) -> None:
    regenerate(args.profile, args.variant)


def _verify(args) -> None:
    results = f"results/{args.profile}"
    ok, problems = verify(results)
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        raise ValueError(f"{len(problems)} stored file(s) of {results} differ from the sha256 list of "
                         f"{results}/provenance.json ({ok} match)")
    print(f"{results}: all {ok} stored files match the sha256 recorded in {results}/provenance.json")


def _readme(args) -> None:
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


REPORTS = {"table1": _table1, "table2": _table2, "fig6": _fig6, "fig7": _fig7, "budget": _budget,
           "generalise": _generalise, "fresh": _fresh, "pathlength": _pathlength, "compare": _compare,
           "behaviour": _behaviour, "searches": _searches, "provenance": _provenance, "regenerate": _regenerate,
           "verify": _verify, "readme": _readme}
"""Each ``egosearch report`` sub-command (its parser: :func:`egosearch.cli.parsers.add_report`)."""


def regenerate(profile: str, reference: str | None) -> None:
    """Tables and figures from the CSVs already in results/<profile>/: seconds, no training. The
    variants and the reference come from the workflow config, as in the DAG, so regenerating gives
    the files `snakemake all` would."""
    # local: only regenerate reads a variant, and the variants layer loads gymnasium's registry
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
    bounds = [p for p in bound_eval_files(results, config["homes"], config["placements"], workflow_heights(config))
              if Path(p).exists()]
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
            report.cmd_pathlength(variant_evals, scenarios, success_radius(), figs / f"pathlength_{variant}",
                                  out_csv=results / "pathlength" / f"{variant}.csv", bounds=bounds)
    learner = config["profiles"][profile]["learner"]
    learner_cfg = load_config(learner)
    report.cmd_table2(table2_rows(learner_cfg), figs / "table2", departure_rows(learner_cfg))
