"""``egosearch report <REPORT>``: tables, figures, comparisons and provenance from result CSVs.

Never loads torch: the report layer reads files only; Table 2 reads the learner config (plain data).
One report per function; :data:`REPORTS` maps each ``REPORT`` name to it.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import re
import sys
from pathlib import Path

from egosearch.cli.checks import at_least, check_npz_files, check_text_files
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.report import commands as report
from egosearch.report.behaviour import behaviour_report, check_pairs, parse_pair, parse_trace_path
from egosearch.report.budget import budget_figure, budget_frame
from egosearch.report.data import parse_eval_path
from egosearch.report.figures import CURVE_LEVELS_DIR, fig6_levels
from egosearch.report.fresh import fresh_report
from egosearch.report.generalise import generalise_report
from egosearch.report.pathlength import by_length_path
from egosearch.report.provenance import check_stored, verify, write_provenance
from egosearch.report.readme import pages, update_pages, update_readme
from egosearch.report.searches import searches_report
from egosearch.report.tables import stuck_path
from egosearch.report.workflow_jobs import (
    bound_eval_files,
    preset_seeds,
    variants_of_all,
    workflow_config,
    workflow_heights,
)
from egosearch.rl.config import departure_rows, load_variant_config, table2_rows
from egosearch.scene.layouts import EASY_LAYOUTS, LAYOUT_NAMES
from egosearch.searchers import searcher_registry as searchers


def run(args) -> None:
    check_report_outputs(args)
    check_report_inputs(args)
    REPORTS[args.what](args)


PREFIX_FILES = {"table1": ("table1", (".csv", ".md", ".tex")), "table2": ("table2", (".md", ".tex")),
                "fig6": ("fig6", (".png", ".pdf", ".csv")), "fig7": ("fig7", (".png", ".pdf", ".csv")),
                "budget": ("budget", (".csv", ".png", ".pdf")), "pathlength": ("pathlength", (".md", ".png", ".pdf")),
                "generalise": ("generalise", (".csv", ".md", ".png")), "fresh": ("fresh", (".csv", ".md")),
                "behaviour": ("behaviour", ("_episodes.csv", ".csv", ".md", "_claims.csv", "_claims.md")),
                "failures": ("failures", (".csv", "_stuck.csv", ".md")),
                "memory-window": ("memory_window", (".csv", ".md", ".png", ".pdf"))}
"""Per report with ``--out-prefix``: the name it takes in a folder given as the prefix, and what it
adds to the prefix for each file it writes (as the report modules name them)."""


def prefix_files(what: str, out_prefix: str, out_csv: str | None = None) -> list[Path]:
    """The files ``egosearch report <what> --out-prefix <out_prefix>`` writes (pathlength's numbers
    only when ``out_csv``, its ``--out-csv``, does not take them elsewhere)."""
    default, endings = PREFIX_FILES[what]
    path = Path(out_prefix)
    base = path / default if (out_prefix.endswith(("/", os.sep)) or path.is_dir()) else path
    if what == "fresh":  # fresh names its files with with_suffix, which replaces a dotted tail
        return [base.with_suffix(ending) for ending in endings]
    files = [base.with_name(base.name + ending) for ending in endings]
    if what == "pathlength" and not out_csv:
        files.append(base.with_name(base.name + ".csv"))
    return files


TRACE_REPORTS = ("behaviour", "searches", "failures")
"""The reports that read per-step trace files (``.npz``), each beside its episodes CSV."""


def report_inputs(args) -> dict[str, list[str]]:
    """``{option: the files it names}`` of the reports that read files; for a report of traces, also the
    episodes CSV beside each trace (the trace rule's other output): an output never lands on one."""
    if args.what == "budget":
        return {"--run": [f for spec in args.run for f in spec.partition("=")[2].split(":") if f]}
    if args.what in TRACE_REPORTS:
        beside = [str(Path(f).with_suffix(".csv")) for f in args.files if f.endswith(".npz")]
        return {"the input files": args.files, "the traces' episodes CSVs": [f for f in beside if os.path.isfile(f)]}
    names = {"files": "the input files", "bounds": "--bounds", "levels": "--levels", "reference": "--reference",
             "searchers": "--searchers", "students": "--students",
             "candidate": "--candidate", "spread": "--spread", "scenarios": "--scenarios", "stored": "--stored",
             "fresh": "--fresh"}
    out = {}
    for name, option in names.items():
        value = getattr(args, name, None)
        if isinstance(value, list):
            out[option] = value
    return out


PREFIX_TAILS = (".csv", ".md", ".tex", ".png", ".pdf")
"""What a report adds to its ``--out-prefix`` for the files it writes: a prefix ending in one writes x.csv.csv."""


def check_prefix(what: str, out_prefix: str | None) -> None:
    """An ``--out-prefix`` is a path to which the report adds its files' endings (:data:`PREFIX_FILES`): an
    empty one would write hidden files (``.csv``) where the command runs, and one that ends in an ending
    itself (``failures.csv``) files named ``failures.csv.csv``."""
    if out_prefix is None or what not in PREFIX_FILES:
        return
    default, endings = PREFIX_FILES[what]
    adds = f"{what} adds " + (f"{', '.join(endings[:-1])} and {endings[-1]}" if len(endings) > 1 else endings[0])
    if not out_prefix.strip():
        raise ValueError(f"--out-prefix={out_prefix!r} is empty; allowed: a path to which {adds} (e.g. "
                         f"paper_figs/cpu/{default})")
    tail = Path(out_prefix).suffix
    if what != "fresh" and tail in PREFIX_TAILS:  # fresh replaces a dotted tail (its own check)
        raise ValueError(f"--out-prefix={out_prefix} ends in {tail}, and {adds} to it "
                         f"({prefix_files(what, out_prefix)[0]}); allowed: the prefix without {tail}, "
                         f"{out_prefix[: -len(tail)]}")


def check_report_outputs(args) -> None:
    """Every path a report writes, checked before it reads anything."""
    out_prefix = getattr(args, "out_prefix", None)
    check_prefix(args.what, out_prefix)
    check_outputs(files={"--out": getattr(args, "out", None), "--out-csv": getattr(args, "out_csv", None),
                         "--readme": None if args.what != "readme" or args.check else args.readme},
                  dirs={"--out-dir": getattr(args, "out_dir", None)},
                  prefixes={"--out-prefix": out_prefix})
    if args.what in ("regenerate", "readme", "verify"):
        # regenerate and readme rewrite the stored tables, figures and pages by design: they are the DAG's
        # jobs run by hand (regenerate writes what `snakemake all` would), so no stored file is refused
        return
    out = getattr(args, "out", None)
    files = {"--out": [out, by_length_path(out)] if args.what == "compare" and out else out}
    if args.what == "pathlength" and args.out_csv:
        files["--out-csv"] = args.out_csv
    written = [] if out_prefix is None else prefix_files(args.what, out_prefix, getattr(args, "out_csv", None))
    check_overwrites(files=files, prefixes={"--out-prefix": (out_prefix, written)},
                     dirs={"--out-dir": getattr(args, "out_dir", None)}, inputs=report_inputs(args),
                     force=args.force)


def _bounds_hint(option: str, path: str) -> str:
    """What ``--bounds`` takes, said where one of its paths is missing: a searcher's name is its most
    likely typo (``--bounds frontier``)."""
    if option != "--bounds":
        return ""
    pattern = "results/<preset>/eval/{}/seed<N>/<home>/<placement>/h<height>.csv"
    if path in searchers.SEARCHERS:
        return f"; --bounds takes evaluation CSV paths, not a searcher's name: {path}'s are {pattern.format(path)}"
    return (f"; --bounds takes the evaluation CSV paths of the searchers ({', '.join(searchers.bounds())}): "
            f"{pattern.format('<searcher>')}")


def check_report_inputs(args) -> None:
    """The input files are files of their kind, and every option names something they hold: a report
    otherwise fails half-way with pandas' or numpy's words, or draws an empty row without a word."""
    for option, paths in report_inputs(args).items():
        missing = [path for path in paths if not os.path.exists(path)]
        if missing:
            # before the path is parsed: a missing file would be told the pattern of the paths it has
            more = f" ({len(missing) - 1} more missing too)" if len(missing) > 1 else ""
            raise FileNotFoundError(f"{option}: {missing[0]} not found{more}{_bounds_hint(option, missing[0])}")
    if args.what in ("behaviour", "searches", "failures"):
        check_npz_files("the input files", args.files)
    else:
        for option, paths in report_inputs(args).items():
            check_text_files(option, paths)
    INPUT_CHECKS.get(args.what, lambda _: None)(args)


def _variants(paths: list[str], parse) -> list[str]:
    return list(dict.fromkeys(parse(path)["variant"] for path in paths))


def _check_generalise(args) -> None:
    variants = _variants(args.files, parse_eval_path)
    shown = ", ".join(variants)
    for item in args.trained_on:
        variant, sep, homes = item.partition("=")
        if not (sep and variant and homes):
            raise ValueError(f"--trained-on {item!r}: expected VARIANT=HOMES (e.g. head_on=paper_homes)")
        if variant not in variants:
            raise ValueError(f"--trained-on {item!r}: {variant!r} is none of the files' variants ({shown})")
    for option, value in (("--generated", args.generated), ("--reference", args.reference)):
        if value is not None and value not in variants:
            raise ValueError(f"{option}={value!r} is none of the files' variants ({shown}): its rows would be "
                             "left out without a word")
    if args.reference is not None and args.generated is None:
        raise ValueError("--reference is read only with --generated (the variant read against it)")


def _check_behaviour(args) -> None:
    check_pairs([parse_pair(p) for p in args.pairs], _variants(args.files, parse_trace_path))


def _check_searches(args) -> None:
    at_least("--seed", args.seed, 0, "a seed")
    where = [parse_trace_path(path) for path in args.files]
    seeds = sorted({w["seed"] for w in where})
    if args.seed not in seeds:
        raise ValueError(f"--seed={args.seed}: no trace file of seed {args.seed} among the files (their seeds: "
                         f"{', '.join(map(str, seeds))}), so no search would be pictured")
    for path, w in zip(args.files, where, strict=True):
        if not (w["layout"] in (*LAYOUT_NAMES, *EASY_LAYOUTS) or re.fullmatch(r"home\d+", w["layout"])):
            raise ValueError(f"{path}: the home {w['layout']!r} of its path is unknown; allowed: "
                             f"{', '.join((*LAYOUT_NAMES, *EASY_LAYOUTS))} or home<seed>")


def _check_fresh(args) -> None:
    at_least("--fresh-seed", args.fresh_seed, 0, "a scenario seed")
    stored = {Path(p).resolve(): p for p in args.stored}
    both = [p for p in args.fresh if Path(p).resolve() in stored]
    if both:
        raise ValueError(f"{both[0]} is both a --stored and a --fresh file: the check reads evaluations on two "
                         "different scenario sets")
    if not args.force:
        stored_content = {_sha256(path): path for path in args.stored}
        for path in args.fresh:
            same = stored_content.get(_sha256(path))
            if same is not None:
                raise ValueError(f"--fresh: {path} has the same content as the --stored {same} (a copy?): the check "
                                 "reads evaluations on two different scenario sets; pass --force when they did give "
                                 "the same episodes")
    written = prefix_files("fresh", args.out_prefix)
    wanted = Path(args.out_prefix)
    if written[0].parent == wanted.parent and written[0].stem != wanted.name:
        raise ValueError(f"--out-prefix={args.out_prefix}: fresh would write {written[0]} (it replaces what "
                         "follows a dot in the name); use a prefix without a dot in its name")


def _check_budget(args) -> None:
    settings, seen = [], set()
    for spec in args.run:
        setting, sep, files = spec.partition("=")
        curve, sep2, evals = files.partition(":")
        if not (sep and sep2 and setting and curve and evals):
            raise ValueError(f"--run {spec!r}: expected SETTING=CURVE_CSV:EVAL_CSV")
        key = (Path(curve).resolve(), Path(evals).resolve())
        if key in seen:
            raise ValueError(f"--run {spec!r}: that run is given twice; each --run is one seed's run")
        seen.add(key)
        settings.append(setting)
    if args.chosen is not None and args.chosen not in settings:
        raise ValueError(f"--chosen={args.chosen!r} is none of the --run settings "
                         f"({', '.join(dict.fromkeys(settings))})")


def _check_compare(args) -> None:
    """A candidate whose actors trained at another learner preset than the reference's (a smoke run
    in a cpu results folder) is refused: its rows would read as a worse variant. The preset is read
    from each actor's ``config.json``, found beside the evaluation as the DAG lays them out. A candidate
    file with the same content as a reference file (a copy) is refused without ``--force``: a table of
    +0.000 would read as a result."""
    sides = {option: actor_presets(files) for option, files in (("--reference", args.reference),
                                                                 ("--candidate", args.candidate))}
    for file, (preset, config) in sides["--candidate"].items():
        reference = {p for p, _ in sides["--reference"].values()} - {preset}
        if reference:
            raise ValueError(f"--candidate: {file} was evaluated from an actor trained at the {preset} learner "
                             f"preset ({config}), the reference's at {', '.join(sorted(reference))}: compare "
                             "variants trained at one preset")
    if not args.force:
        reference_by_content = {_sha256(path): path for path in args.reference}
        for path in args.candidate:
            same = reference_by_content.get(_sha256(path))
            if same is not None and Path(same).resolve() != Path(path).resolve():  # one path: refused below
                raise ValueError(f"--candidate: {path} has the same content as the reference's {same} (a copy?): "
                                 "every difference would be 0; compare two different variants, or pass --force "
                                 "when they did give the same episodes")


def _sha256(path: str) -> str:
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def actor_presets(files: list[str]) -> dict[str, tuple[str, Path]]:
    """``{evaluation file: (its actor's learner preset, the actor's config.json)}`` for the files
    whose actor's run folder, ``<results>/train/<variant>/seed<N>/``, is there to tell it."""
    # local: reading a run's preset loads the variants layer (gymnasium's registry)
    import json

    from egosearch.cli.checks import learner_preset_of

    out, known = {}, {}
    for file in files:
        try:
            where = parse_eval_path(file)
        except ValueError:
            continue
        parts = Path(file).parts
        if len(parts) < 7 or parts[-6] != "eval":
            continue
        config = Path(*parts[:-6], "train", where["variant"], f"seed{where['seed']}", "config.json")
        if config not in known:
            try:
                record = json.loads(config.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                known[config] = None
            else:
                preset, _ = (learner_preset_of(record["config"], record.get("variant"))
                              if isinstance(record, dict) and isinstance(record.get("config"), dict) else (None, ""))
                known[config] = preset
        if known[config] is not None:
            out[file] = (known[config], config)
    return out


def _check_failures(args) -> None:
    """Each trace is one method's, seed's and cell's, laid out as the workflow lays them
    (``.../<method>/seed<N>/<home>/<placement>/h<height>.npz``: the method is the fifth part from the end),
    of one preset, given once, and holds episodes; each ``--stuck-read`` method once."""
    # local: the simulator's body sizes are plain data, but its package is the CLI's to load
    from egosearch.report.failures import check_trace_file
    from egosearch.report.tables import PLACEMENT_LABELS
    from egosearch.sim.body import HEIGHT_RANGE

    seen, presets = {}, {}
    for path in args.files:
        where = parse_trace_path(path)
        if where["placement"] not in PLACEMENT_LABELS:
            raise ValueError(f"{path}: its placement folder {where['placement']!r} is none of "
                             f"{', '.join(PLACEMENT_LABELS)}; expected .../<method>/seed<N>/<home>/<placement>/"
                             "h<height>.npz, as the workflow lays traces out")
        if not HEIGHT_RANGE[0] <= where["height"] <= HEIGHT_RANGE[1]:
            raise ValueError(f"{path}: height {where['height']:g} m is outside [{HEIGHT_RANGE[0]}, {HEIGHT_RANGE[1]}] "
                             "m, the camera heights a trace can have")
        key = tuple(where[k] for k in ("variant", "seed", "layout", "placement", "height"))
        if key in seen:
            both = (f"{path} is given twice" if Path(path).resolve() == Path(seen[key]).resolve() else
                    f"{path} and {seen[key]} are both {key[0]}'s trace of seed {key[1]} in {key[2]}, {key[3]}, "
                    f"{key[4]:g} m")
            raise ValueError(f"the input files: {both}: give each trace once (its episodes would count twice)")
        seen[key] = path
        parts = Path(path).resolve().parts
        for folder, preset, traces in zip(parts, parts[1:], parts[2:]):
            if folder == "results" and traces == "traces":
                presets.setdefault(preset, path)
        if len(presets) > 1:
            (one, first), (other, second) = list(presets.items())[:2]
            raise ValueError(f"the input files mix presets: {first} is {one}'s, {second} is {other}'s; a failure "
                             "table reads one preset's traces")
    for method in args.stuck_read:
        if args.stuck_read.count(method) > 1:
            raise ValueError(f"--stuck-read: {method} is given twice; each method's section is written once")
    for path in args.files:
        check_trace_file(path)


INPUT_CHECKS = {"generalise": _check_generalise, "behaviour": _check_behaviour, "searches": _check_searches,
                "fresh": _check_fresh, "budget": _check_budget, "compare": _check_compare,
                "failures": _check_failures}


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
    from egosearch.sim.body import AgentSpec
    from egosearch.sim.scenarios import SUCCESS_DISTANCE

    return SUCCESS_DISTANCE + AgentSpec().body_radius


def _table1(args) -> None:
    report.cmd_table1(args.files, args.out_prefix, variant=args.variant, bounds=args.bounds,
                      learning_adds=args.learning_adds)


def _table2(args) -> None:
    cfg = load_variant_config(args.preset)  # what a variant that pins nothing trains there (smoke: the cpu learner)
    report.cmd_table2(table2_rows(cfg), args.out_prefix, departure_rows(cfg))


def _fig6(args) -> None:
    check_fig6_files(args.files, args.levels or [])
    report.cmd_fig6(curves_by_variant(args.files), args.out_prefix, level_files=args.levels)


def check_fig6_files(curves: list[str], levels: list[str]) -> None:
    """Each curve and each level once (a level given twice was drawn twice; a curve twice failed as "a scenario
    appears twice for the same seed"), and each level on the scenarios of a variant the curves draw (its file is
    ``.../eval_curve/SEARCHER/VARIANT.csv``): another variant's would be read on other episodes."""
    from egosearch.report.figures import level_searcher

    for option, paths, what in (("the curve files", curves, "each seed's curve once"),
                                ("--levels", levels, "each searcher's level once")):
        seen: dict[Path, str] = {}
        for path in paths:
            if Path(path).resolve() in seen:
                raise ValueError(f"{option}: {path} is given twice; give {what}")
            seen[Path(path).resolve()] = path
    variants = list(curves_by_variant(curves))
    searchers_seen: dict[str, str] = {}
    for path in levels:
        searcher, variant = level_searcher(path), Path(path).stem
        if searcher in searchers_seen:
            raise ValueError(f"--levels: {searchers_seen[searcher]} and {path} are both {searcher}'s level; give "
                             "each searcher's level once")
        searchers_seen[searcher] = path
        if variant not in variants:
            raise ValueError(f"--levels: {path} is {searcher}'s level on {variant}'s curve scenarios, and the curves "
                             f"are {', '.join(variants)}'s; give the level of a variant they draw (.../"
                             f"{CURVE_LEVELS_DIR}/{searcher}/{variants[0]}.csv)")


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
    if args.out is None:
        report.cmd_compare(args.reference, args.candidate, None, reference_name="reference",
                           candidate_name="candidate", spread_files=args.spread)
        return
    # The comparison writes its CSV before the ℓ split checks that both sides ran the same scenarios:
    # both go to temporary files, moved into place only when every check passed, and what it prints
    # waits with them, so that a refused comparison is one line and leaves no file.
    out, by_length, stuck = Path(args.out), by_length_path(args.out), stuck_path(args.out)
    tmp = out.with_name(f".tmp{os.getpid()}.{out.name}")
    tmp_by_length, tmp_stuck = by_length_path(tmp), stuck_path(tmp)
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed):
            report.cmd_compare(args.reference, args.candidate, tmp, reference_name="reference",
                               candidate_name="candidate", spread_files=args.spread)
        os.replace(tmp, out)
        os.replace(tmp_by_length, by_length)
        os.replace(tmp_stuck, stuck)
        if args.aggregate:
            from egosearch.report.aggregate import aggregate_report, format_aggregate
            from egosearch.report.data import cells_from_paths
            print(format_aggregate(aggregate_report(cells_from_paths(args.reference), cells_from_paths(args.candidate),
                                                    args.aggregate)), file=printed)
            print(f"wrote {args.aggregate}", file=printed)
    finally:
        for path in (tmp, tmp_by_length, tmp_stuck):
            path.unlink(missing_ok=True)
    print(printed.getvalue().replace(str(tmp_by_length), str(by_length)).replace(str(tmp_stuck), str(stuck))
          .replace(str(tmp), str(out)), end="")


def _behaviour(args) -> None:
    for path in behaviour_report(args.files, args.out_prefix, pairs=[parse_pair(p) for p in args.pairs]):
        print(f"wrote {path}")


def _searches(args) -> None:
    for path in searches_report(args.files, args.out_dir, seed=args.seed):
        print(f"wrote {path}")


def _provenance(args) -> None:
    record = write_provenance(args.preset, args.results, args.out, note=args.note or "")
    # The same line whether the record was rewritten or kept (no stored file changed): the
    # workflow commits this log, and a rerun that changes nothing must leave it as it was.
    print(f"{args.out}: sha256 of {len(record['files'])} stored files, {len(record['jobs'])} jobs, "
          f"{record['wall_s_all_jobs_summed']} s summed")


def _regenerate(args) -> None:
    if args.variant:
        # local: the variants layer loads gymnasium's registry
        from egosearch.variants import load_variant

        try:
            load_variant(args.variant)
        except ValueError as err:
            raise ValueError(f"--variant: {err}") from None
    regenerate(args.preset, args.variant)


def _verify(args) -> None:
    results = f"results/{args.preset}"
    ok, problems = verify(results)
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        raise ValueError(f"{len(problems)} stored file(s) of {results} differ from the sha256 list of "
                         f"{results}/provenance.json ({ok} match)")
    print(f"{results}: all {ok} stored files match the sha256 recorded in {results}/provenance.json")


def _readme(args) -> None:
    if args.readme and not Path(args.readme).is_file():
        raise FileNotFoundError(f"--readme: {args.readme} not found; a page of marked blocks (README.md, docs/*.md)")
    if args.readme:
        checked = [args.readme]
        stale = [] if update_readme(args.readme, args.preset, check=args.check) else checked
    else:
        checked, stale = pages("."), update_pages(".", args.preset, check=args.check)
        if not checked:
            raise ValueError("no README.md and no docs/*.md here: run it in the project's root, or give --readme")
    names = ", ".join(str(page) for page in (stale or checked))
    if not stale:
        print(f"{names}: results blocks match results/{args.preset} and paper_figs/{args.preset}")
    elif args.check:
        raise ValueError(f"{names} out of date with the stored results; "
                         f"run `egosearch report readme --preset {args.preset}`")
    else:
        print(f"rewrote the results blocks of {names} from the {args.preset} results")


def _failures(args) -> None:
    from egosearch.report.failures import failure_markdown, failure_table
    from egosearch.report.stuck_contacts import stuck_contacts, stuck_markdown

    by_method: dict[str, list[str]] = {}
    for path in args.files:
        if not path.endswith(".npz"):
            raise ValueError(f"{path}: a per-step trace (.npz) expected")
        by_method.setdefault(Path(path).parts[-5], []).append(path)
    unknown = [m for m in args.stuck_read if m not in by_method]
    if unknown:
        raise ValueError(f"--stuck-read: {unknown[0]} has no trace among the input files ({', '.join(by_method)})")
    csv, stuck_csv, md = prefix_files("failures", args.out_prefix)  # a folder as the prefix: failures.csv in it
    df = failure_table(by_method, csv)
    text = "# How each searcher fails\n\n" + failure_markdown(df, str(csv))
    contacts = stuck_contacts({m: by_method[m] for m in args.stuck_read}, stuck_csv)
    for method in args.stuck_read:
        text += f"\n## What `{method}` is stuck against\n\n" + stuck_markdown(contacts, method, str(stuck_csv))
    md.write_text(text, encoding="utf-8")
    print(f"wrote {csv}, {stuck_csv} and {md} ({len(by_method)} searchers, {len(df)} cells)")


def _memory_window(args) -> None:
    from egosearch.report.memory_window import memory_window_inputs, memory_window_report

    searchers, students = memory_window_inputs(args.searchers, args.students)
    for path in memory_window_report(searchers, students, args.out_prefix):
        print(f"wrote {path}")


def _null_screen(args) -> None:
    import json

    from egosearch.report.calibration import SIMULATIONS
    from egosearch.report.data import cells_from_paths
    from egosearch.report.null_screen import null_screen, seed_spread_summary

    files = cells_from_paths(args.files)
    variants = _variants(args.files, parse_eval_path)
    if len(variants) != 1:
        raise ValueError(f"null-screen: the files are of {len(variants)} variants ({', '.join(variants)}); give one")
    if args.simulations is not None and args.simulations < 1:
        raise ValueError(f"--simulations={args.simulations}: must be 1 or more")
    # results/<preset>/eval/<variant>/seed<N>/<home>/<placement>/h<height>.csv
    results = Path(args.files[0]).resolve().parents[5]
    record = json.loads((results / "provenance.json").read_text(encoding="utf-8"))
    summary = seed_spread_summary(files, record, variants[0], n_sims=args.simulations or SIMULATIONS)
    df = null_screen(files, args.out)
    called = df[(df["metric"] == "success")]
    print(f"null screen of {variants[0]} ({summary['n_seeds']} seeds, {df['screen'].nunique()} screens, each pair's "
          f"spread from the seeds on neither side: a consistency check): "
          f"{int((called['scenarios_verdict'].isin(['lower', 'higher'])).sum())} success cells called different "
          f"before the seed spread counted, {int(called['verdict'].isin(['lower', 'higher']).sum())} after; "
          f"wrote {args.out}")
    worst = summary["worst_setting"]
    print(f"simulated false-positive rate of the screen's test ({summary['simulations']:,} screens per setting): "
          f"highest {worst['rate']:.3f} ({worst['law']} seeds, {worst['truth']} spread, rho {worst['rho']:g}, "
          f"{worst['n_candidate']} candidate seed(s)); every setting and cell at or below "
          f"{summary['level_claim']:g}: {'yes' if summary['level_holds'] else 'NO'}")
    Path(args.summary).write_text(json.dumps(summary, indent=1, default=float) + "\n", encoding="utf-8")
    print(f"recommended screen_seeds: {summary['recommended_screen_seeds']} (detects "
          f"{summary['detectable_at_recommended']:.3f} at {summary['power_cell'][0]} m with 80% power; "
          f"{summary['seeds_per_day']} seeds fit in a day of {summary['day_hours']:g} h); wrote {args.summary}")


def _reread_screens(args) -> None:
    from egosearch.report.reread import reread_screens

    results = Path("results") / args.preset
    if not (results / "compare").is_dir():
        raise FileNotFoundError(f"{results / 'compare'}: no stored comparisons (run it in the project's root)")
    df = reread_screens(results / "compare", results / "eval", args.out)
    read = df[df["metric"] == "success"]
    before, after = (int(read[column].isin(["higher", "lower"]).sum()) for column in ("old_verdict", "verdict"))
    print(f"{df['screen'].nunique()} stored screens read again: {before} success cells were called different, "
          f"{after} are now; wrote {args.out}")


REPORTS = {"table1": _table1, "table2": _table2, "fig6": _fig6, "fig7": _fig7, "budget": _budget,
           "generalise": _generalise, "fresh": _fresh, "pathlength": _pathlength, "compare": _compare,
           "behaviour": _behaviour, "searches": _searches, "provenance": _provenance, "regenerate": _regenerate,
           "verify": _verify, "readme": _readme, "null-screen": _null_screen, "failures": _failures,
           "reread-screens": _reread_screens, "memory-window": _memory_window}
"""Each ``egosearch report`` sub-command (its parser: :func:`egosearch.cli.parsers.add_report`)."""


def regenerate(preset: str, reference: str | None) -> None:
    """Tables and figures from the CSVs already in results/<preset>/: seconds, no training. The
    variants and the reference come from the workflow config, as in the DAG, so regenerating gives
    the files `snakemake all` would. A file rewritten with the bytes it had keeps its file time:
    Snakemake then sees nothing new, and `snakemake all` after it has nothing to do."""
    folders = [Path("paper_figs") / preset, Path("results") / preset / "pathlength"]
    before = {path: (path.read_bytes(), path.stat()) for folder in folders if folder.is_dir()
              for path in folder.rglob("*") if path.is_file()}
    _regenerate_files(preset, reference)
    for path, (data, stat) in before.items():
        if path.is_file() and path.read_bytes() == data:
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def _regenerate_files(preset: str, reference: str | None) -> None:
    config = workflow_config()
    if preset not in config["presets"]:
        raise ValueError(f"--preset={preset!r}; allowed: {', '.join(config['presets'])}")
    reference = reference or config["reference_variant"]
    results, figs = Path("results") / preset, Path("paper_figs") / preset
    check_outputs(dirs={"the figures folder": figs, "the path-length folder": results / "pathlength"})
    # Table 1's homes only, as the DAG's rules: eval/ also holds the generalisation groups
    homes = set(config["homes"])
    # the preset's seeds only: the reference's spread seeds beyond them (snakemake seed_spread) are no
    # part of Table 1, Figure 6 or the path-length tables, as in the DAG
    seeds = {f"seed{s}" for s in preset_seeds(config, preset)}
    evals = sorted(str(p) for p in (results / "eval" / reference).glob("seed*/*/*/h*.csv")
                   if Path(p).parts[-3] in homes and Path(p).parts[-4] in seeds)
    curves = {v: sorted(str(p) for p in (results / "train" / v).glob("seed*/curve.csv") if p.parts[-2] in seeds)
              for v in variants_of_all(config)}
    curves = {v: paths for v, paths in curves.items() if paths}
    fullbody = sorted(str(p) for p in (results / "fullbody").glob("*/seed*.csv"))
    fullbody_oracle = sorted(str(p) for p in (results / "fullbody_oracle").glob("*/seed*.csv"))
    bounds = [p for p in bound_eval_files(results, config["homes"], config["placements"], workflow_heights(config))
              if Path(p).exists()]
    # Figure 6's levels: the searchers on the scenarios of the reference's curve (as in the DAG).
    level_files = [str(p) for p in (results / CURVE_LEVELS_DIR / name / f"{reference}.csv" for name in fig6_levels())
                   if p.exists()]
    adds = results / "compare" / f"{reference}_vs_its_start.csv"
    if not (evals or curves or fullbody or fullbody_oracle):
        raise FileNotFoundError(f"no stored results under {results}/ (eval, train or fullbody)")
    read = [*evals, *bounds, *level_files, *(p for paths in curves.values() for p in paths), *fullbody,
            *fullbody_oracle, *([str(adds)] if adds.exists() else [])]
    if check_stored(read, require_record=True):
        print(f"note: {results}/provenance.json has no sha256 list: the stored files are used unverified")
    figs.mkdir(parents=True, exist_ok=True)
    if evals:
        report.cmd_table1(evals, figs / "table1", variant=reference, bounds=bounds,
                          learning_adds=adds if adds.exists() else None)
    if curves:
        report.cmd_fig6(curves, figs / "fig6", level_files=level_files)
    if fullbody:
        report.cmd_fig7(fullbody, figs / "fig7")
    if fullbody_oracle:
        report.cmd_fig7(fullbody_oracle, figs / "fig7_oracle", planner="oracle")
    scenarios = sorted(str(p) for home in homes for p in (results / "scenarios" / home).glob("*/h*.csv"))
    for variant in variants_of_all(config):
        variant_evals = sorted(str(p) for p in (results / "eval" / variant).glob("seed*/*/*/h*.csv")
                               if Path(p).parts[-3] in homes and Path(p).parts[-4] in seeds)
        if variant_evals and scenarios:
            report.cmd_pathlength(variant_evals, scenarios, success_radius(), figs / f"pathlength_{variant}",
                                  out_csv=results / "pathlength" / f"{variant}.csv", bounds=bounds)
    learner = config["presets"][preset]["learner"]
    learner_cfg = load_variant_config(learner)
    report.cmd_table2(table2_rows(learner_cfg), figs / "table2", departure_rows(learner_cfg))
