"""The command line's parsers: one small function per command, each adding its sub-parser.

Standard library and plain scene data only, so that ``egosearch --help`` is instant; each command's
body lives in ``egosearch/cli/<command>.py``, imported only when that command runs.
"""

from __future__ import annotations

from egosearch.rl.learner_registry import LEARNERS as REGISTERED_LEARNERS
from egosearch.rl.presets import PRESETS
from egosearch.scene.layouts import EASY_LAYOUTS, LAYOUT_NAMES
from egosearch.scene.placement import PLACEMENT_SCHEMES
from egosearch.searchers import searcher_registry as searchers
from egosearch.sim.body import EVAL_HEIGHTS, HEIGHT_RANGE
from egosearch.sim.observation_options import option_names

LAYOUTS = (f"{', '.join(LAYOUT_NAMES)} (the paper's homes), {', '.join(EASY_LAYOUTS)} (a small home for tests) "
           "or home<seed> (a generated home)")
THREADS = "torch threads for acting (default 1; 0: all cores)"
MAX_SCENARIOS = 10_000
"""Most scenarios in one set: about 4 minutes at the ~40 scenarios/s of a paper home (a Table 1 cell has 200)."""
MAX_HOMES = 1_000
"""Most generated homes in one set (each is built once: about a second)."""
POLICY_SEED = "seed of the random policy and of the env's per-step noise, >= 0 (default 0)"
FORCE = ("overwrite stored results (files git tracks under results/ or paper_figs/): the DAG's own jobs pass it; "
         "without it such a file is refused")
LEARNERS = "the preset's learner (SAC-DrQ at cpu, SAC+CURL at smoke and paper)"


OLD_PRESET_FLAG = "--profile"
"""The old name of ``--preset``, kept working for one release (until egosearch 0.2): Snakemake's ``--profile`` is
a folder of its options (``profiles/``), a different thing."""
OLD_PRESET_NOTE = ("egosearch: note: --profile is the old name of --preset (the learner preset: smoke, cpu or paper; "
                   "not Snakemake's --profile); it works until egosearch 0.2")


def add_preset(p, **kwargs) -> None:
    """``--preset``, and its old name (:data:`OLD_PRESET_FLAG`) as an alias."""
    kwargs["help"] = kwargs.get("help", "") + f" ({OLD_PRESET_FLAG}: its old name, until egosearch 0.2)"
    p.add_argument("--preset", OLD_PRESET_FLAG, dest="preset", **kwargs)


def uses_old_preset_flag(argv: list[str]) -> bool:
    """Whether the command line spells ``--preset`` by its old name (then :data:`OLD_PRESET_NOTE` is printed)."""
    return any(arg == OLD_PRESET_FLAG or arg.startswith(OLD_PRESET_FLAG + "=") for arg in argv)


def add_force(p, also: str = "") -> None:
    p.add_argument("--force", action="store_true", help=FORCE + also)


def add_allow_long(p) -> None:
    p.add_argument("--allow-long", action="store_true",
                   help="allow a run past the documented bounds (total_env_steps 20,000,000, eval_episodes 10,000, "
                        "demo_episodes 100,000: egosearch.rl.run_settings.LONG_RUN_BOUNDS), refused without it as a "
                        "likely typo; EGOSEARCH_ALLOW_LONG=1 in the environment does the same (the workflow's "
                        "--config allow_long=true sets it for its jobs)")


def add_scenarios(sub) -> None:
    p = sub.add_parser("scenarios", help="generate a fixed scenario set as CSV")
    p.add_argument("--layout", help=f"home: {LAYOUTS} (default kitchen_living; not with --homes)")
    p.add_argument("--placement", default="everywhere", choices=PLACEMENT_SCHEMES,
                   help="where targets may be: every support surface, or none inside low cabinets")
    p.add_argument("--height", type=float, default=1.65,
                   help=f"camera height (m): any value in [{HEIGHT_RANGE[0]}, {HEIGHT_RANGE[1]}] is a valid "
                        f"experiment; Table 1 uses {', '.join(f'{h:g}' for h in EVAL_HEIGHTS)} (default 1.65)")
    p.add_argument("--n", type=int, default=100,
                   help=f"number of scenarios, 1 to {MAX_SCENARIOS} (per home with --homes; default 100)")
    p.add_argument("--homes", default=None, metavar="FIRST:STOP",
                   help="instead of --layout: generated homes home<FIRST> ... home<STOP-1>, --n scenarios each, "
                        f"in one set (the generalisation benchmark's groups); at most {MAX_HOMES} homes and "
                        f"{MAX_SCENARIOS} scenarios in all")
    p.add_argument("--seed", type=int, default=0, help="seed of the set, >= 0: the same seed gives the same rows")
    p.add_argument("--out", required=True, help="the scenario CSV to write")
    add_force(p)


def policy_help() -> str:
    """``egosearch evaluate --policy``'s choices: ``actor`` and every registered searcher (neighbours with the
    same help said together)."""
    groups: list[tuple[list[str], str]] = []
    for s in searchers.SEARCHERS.values():
        if groups and s.help and groups[-1][1] == s.help:
            groups[-1][0].append(s.name)
        else:
            groups.append(([s.name], s.help))
    words = [" / ".join(names) + (f" ({about})" if about else "") for names, about in groups]
    return ", ".join([f"{searchers.ACTOR} (with --weights)", *words[:-1]]) + (f", or {words[-1]}" if words else "")


def env_id_help() -> str:
    """``--env-id``'s defaults: the env each registered searcher acts in."""
    by_env: dict[str, list[str]] = {}
    for s in searchers.SEARCHERS.values():
        by_env.setdefault(s.env_id, []).append(s.name)
    return "default: the actor's own env id; " + "; ".join(f"{env} for {', '.join(names)}"
                                                         for env, names in by_env.items())


def add_evaluate(sub) -> None:
    p = sub.add_parser("evaluate", help="run a policy over a scenario CSV -> per-episode CSV")
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--scenarios", help="a scenario CSV written by `egosearch scenarios`")
    which.add_argument("--curve-of", metavar="VARIANT",
                       help="instead of --scenarios: the held-out scenarios VARIANT's training curve is evaluated on "
                            "at --preset, each episode seeded as the curve's (Figure 6's levels; the CSV gains the "
                            "home and height, as scenario ids restart in each)")
    add_preset(p, default="cpu", help="with --curve-of: the learner preset (default: cpu)")
    p.add_argument("--policy", default="actor", help=policy_help())
    p.add_argument("--weights", help="actor.pt written by `egosearch train` (for --policy actor only)")
    p.add_argument("--env-id", help=env_id_help())
    p.add_argument("--env-option", action="append", metavar="KEY=true|false",
                   help=f"an observation option of the env ({', '.join(option_names())}), repeatable; default: the "
                        "ones a trained actor's file records (an actor that does not fit the options given is refused)")
    p.add_argument("--seed", type=int, help=POLICY_SEED + " (not with --curve-of, whose episodes are seeded as the "
                                            "curve's)")
    p.add_argument("--out", required=True, help="the per-episode CSV to write (one row per scenario)")
    p.add_argument("--traces", metavar="FILE.npz", help="also write every step of every episode (pose, head, action, "
                                                        "what the camera's centre looks at, distances) to this "
                                                        "compressed file (egosearch.runs.trace)")
    p.add_argument("--threads", type=int, default=1, help=THREADS)
    add_allow_long(p)
    add_force(p)


VARIANT_HELP = ("a variant: a file stem in ablations/ (head_on, head_off, ...) or the path of a variant file "
                "(e.g. my_variants/x.yaml; its name: must equal the file's stem)")
SET_HELP = ("override one config field, repeatable (e.g. --set batch_size=64 --set actor_lr=1e-4): checked as a "
            "variant file's config: is (the field, its type, its range), on top of the variant's values")


def add_train(sub) -> None:
    about = f"train a variant's search policy with {LEARNERS} (resumable)"
    p = sub.add_parser("train", help=about, description=about)
    p.add_argument("--variant", required=True, help=VARIANT_HELP)
    add_preset(p, default="cpu", help="learner preset: smoke, cpu or paper (default: cpu)")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help=SET_HELP + "; recorded in the run's config.json as `set`, and a resume refuses other ones")
    p.add_argument("--seed", type=int, default=0, help="training seed (default 0)")
    p.add_argument("--threads", type=int, default=0, help="torch threads (0: all cores; default 0)")
    p.add_argument("--out-dir", required=True, help="run folder: actor.pt, curve.csv, train.csv, checkpoint; "
                                                    "rerun with the same folder to resume")
    p.add_argument("--work-dir", help="train (and resume) here, and copy the files to --out-dir only once the run "
                                      "is complete (the DAG does: a killed job never leaves a partial output)")
    p.add_argument("--max-wall-s", type=float, help="stop after this many seconds with a checkpoint written (inside "
                                                    "a cluster's time limit); the same command resumes it")
    p.add_argument("--stack-seeds", metavar="SEEDS",
                   help="train these seeds (comma-separated, e.g. 0,1,2) in one process, their updates stacked as one "
                        "model (sac_curl, sac_drq; docs/gpu.md); --out-dir (and --work-dir) must then hold {seed}, "
                        "e.g. results/paper/train/head_on/seed{seed}; replaces --seed")
    add_allow_long(p)
    add_force(p)


def add_demos(sub) -> None:
    about = ("run the frontier searcher in a variant's training homes and store its transitions "
             "(demonstrations for imitation and RL)")
    p = sub.add_parser("demos", help=about, description=about)
    p.add_argument("--variant", required=True, help=VARIANT_HELP + ": its training homes, heights and observation")
    p.add_argument("--set", action="append", metavar="FIELD=VALUE",
                   help=SET_HELP + " (the training's own --set: its demo_episodes, its observation)")
    add_preset(p, default="cpu", help="learner preset whose observation is stored: smoke, cpu or "
                                                    "paper (default: cpu)")
    p.add_argument("--episodes", type=int, help="demonstration episodes (default: the variant's demo_episodes at "
                   "--preset, what its training collects)")
    p.add_argument("--seed", type=int, default=0, help="seed of the episodes (default 0)")
    p.add_argument("--out", required=True, metavar="FILE.replay.npz",
                   help="the transitions (git-ignored); a summary goes beside it as FILE.json")
    add_allow_long(p)
    add_force(p)


def add_config(sub) -> None:
    about = "a learner's whole config: every field, its value, where the value comes from, the file declaring it"
    p = sub.add_parser("config", help=about, description=about)
    actions = p.add_subparsers(dest="action", required=True)
    show = actions.add_parser("show", help=about, description=about)
    show.add_argument("algorithm", choices=list(REGISTERED_LEARNERS), help="the learner (LearnerConfig.algorithm)")
    add_preset(show, default="cpu", choices=list(PRESETS),
                      help="learner preset: smoke, cpu or paper (default: cpu)")
    show.add_argument("--variant", help=VARIANT_HELP + ": its config overrides shown on top, its env_id and "
                                        "train_env above the fields")
    show.add_argument("--set", action="append", metavar="FIELD=VALUE", help=SET_HELP + ", shown on top of the variant")
    show.add_argument("--full", action="store_true", help="each field's whole docstring, not its first sentence")
    about_page = "write docs/config.md: every learner's fields, paper and cpu values, declaring class and docstring"
    page = actions.add_parser("page", help=about_page, description=about_page)
    page.add_argument("--out", default="docs/config.md", metavar="FILE.md", help="where (default: docs/config.md)")


def add_tune(sub) -> None:
    about = ("redo the tuned frontier searcher's tuning (frontier_tuned): candidates on a training-side fit split, "
             "the chosen one checked on a held-out split, never on a stored set; resumable")
    p = sub.add_parser("tune", help=about, description=about)
    p.add_argument("--out", required=True, metavar="DIR",
                   help="the episodes of every candidate (DIR/SPLIT/HEAD_MODE/CANDIDATE.csv) and DIR/record.json; "
                        "rerun with the same DIR to resume")
    p.add_argument("--limit", type=int, default=0,
                   help="a quick run: the first N scenarios of each cell only, N >= 1 (0: the full splits, 540 "
                        "scenarios each, 90 a cell; about 13,000 episodes in all)")
    add_force(p)


def add_variant(sub) -> None:
    p = sub.add_parser("variant", help="create a variant file in ablations/ from a template, or check variants")
    variants = p.add_subparsers(dest="what", required=True, metavar="ACTION")
    v = variants.add_parser("new", help="write ablations/NAME.yaml, a copy of a template with name: NAME")
    v.add_argument("name", help="the new variant's name (letters, digits, _ and -)")
    v.add_argument("--from", dest="template", default="head_on", help="the variant to copy (default: head_on)")
    v = variants.add_parser("check", help="check variant files, learner config included, before running them")
    v.add_argument("names", nargs="+", help="variant names (files in ablations/) or paths of .yaml files")
    add_preset(v, nargs="+", default=["smoke", "cpu", "paper"],
                   help="learner presets to check the config against (default: all three)")
    add_allow_long(v)


def add_fullbody(sub) -> None:
    p = sub.add_parser("fullbody", help="full-body search (Algorithm 1 or a baseline) -> per-episode CSV")
    p.add_argument("--setting", required=True,
                   help="ours-M<M>-<mg>, one_step_short-<mg>, one_step_long-<mg> or noisy_search-<mg>; "
                        "<mg>: humanoid_phase, humanoid_matching or fetch")
    p.add_argument("--policy", default="actor",
                   help="the planner: actor (with --weights), or oracle (privileged: knows the target) or random")
    p.add_argument("--weights", help="actor.pt of the search policy (for --policy actor)")
    p.add_argument("--scenarios", required=True, help="a scenario CSV written by `egosearch scenarios`")
    p.add_argument("--limit", type=int, default=0, help="use the first N scenarios, N >= 0 (0: all)")
    p.add_argument("--T", type=int, default=20, help="planning horizon, >= 1 and >= M (default 20)")
    p.add_argument("--seed", type=int, default=0, help=POLICY_SEED)
    p.add_argument("--out", required=True, help="the per-episode CSV to write")
    p.add_argument("--threads", type=int, default=1, help=THREADS)
    add_force(p)


def add_bench(sub) -> None:
    about = ("speed benchmarks: env (sensor + physics), homes (building one), learner, gpu (needs CUDA) or stacked "
             "(seeds' updates stacked)")
    p = sub.add_parser("bench", help=about, description=about)
    p.add_argument("what", choices=("env", "homes", "learner", "gpu", "stacked"),
                   help="env: sensor frames/s and env steps/s on one core; homes: a generated home's build time "
                        f"against a training episode; learner: updates/s of {LEARNERS}, and of SAC+CURL at Table "
                        "2's sizes; gpu (needs CUDA): the learner benchmarks and a paper-preset training of "
                        "--seconds on this machine's GPU (results/paper/gpu_check); stacked: --seeds seeds' updates "
                        "stacked as one model against their separate updates, at the cpu preset")
    p.add_argument("--layout", help=f"env: the home ({LAYOUTS}; default kitchen_living)")
    p.add_argument("--seeds", type=int, help="stacked: the seeds stacked, >= 2 (default 3)")
    p.add_argument("--memory-levers", action="store_true",
                   help="learner: also time the cpu preset's short training with each memory lever's observation "
                        "(the options `bench env` times) beside the plain one, two rounds alternating, and print what "
                        "each costs a training against it (six more short trainings)")
    p.add_argument("--frames", type=int, help="env: sensor frames to time, >= 1 (default 3000)")
    p.add_argument("--steps", type=int, help="env: env steps to time, >= 1 (default 3000)")
    p.add_argument("--seconds", type=float, help="gpu: the training's wall time, > 0 (default 150)")
    p.add_argument("--out-dir", help="gpu: the training's folder (curve.csv, train.csv, config.json, checkpoint)")
    p.add_argument("--cuda-graph", action="store_true",
                   help="gpu: train with the update recorded as CUDA graphs (learner.cuda_graph=true, which the "
                        "paper preset sets anyway)")
    p.add_argument("--baseline-seconds", type=float,
                   help="gpu: also train this long with the update launched eagerly (cuda_graph false; in "
                        "<out-dir>/baseline), for the ratio on one machine; with --side-by-side: the N trainings "
                        "side by side without CUDA MPS this long first; default 0: none")
    p.add_argument("--side-by-side", type=int, metavar="N",
                   help="gpu: instead of the learner benchmarks, one paper-preset training alone (all cores), then "
                        "N side by side (cores / N threads each; each `egosearch train --max-wall-s` in "
                        "<out-dir>/side_by_side/<i>), under CUDA MPS where the command can start it; --out defaults "
                        "to results/paper/gpu_check/side_by_side.json (aggregate env steps/s, the paper `all`'s "
                        "projected hours), N >= 2")
    p.add_argument("--stacked", type=int, metavar="N",
                   help="gpu, with --side-by-side: last, one training of N seeds with their updates stacked as one "
                        "model (`egosearch train --stack-seeds`, all cores), into the same record (its aggregate env "
                        "steps/s and projected hours under \"stacked\"), N >= 2")
    add_record_outputs(p, "print one JSON object", "the result as JSON with the command, date, commit, CPU and the "
                       "machine's load", "learner.json", "which the docs' Speed page reads")


def add_record_outputs(p, json_help: str, what: str, name: str, reader: str) -> None:
    """--json, --out (a record of one machine's measurement; {machine} becomes its folder) and --force."""
    p.add_argument("--json", action="store_true", help=json_help)
    p.add_argument("--out", help=f"also write {what} (e.g. results/cpu/bench/{name}, {reader}; {{machine}} in it "
                                 f"becomes this machine's folder name: results/cpu/bench/hosts/{{machine}}/{name})")
    add_force(p)


def add_estimate(sub) -> None:
    about = ("how long `snakemake --cores N all` takes from a fresh clone on this machine: the DAG's schedule "
             "simulated from the stored run's job times, trainings scaled by a minute's calibration")
    p = sub.add_parser("estimate", help=about, description=about)
    p.add_argument("what", choices=("all", "check"),
                   help="all: the target `snakemake all` builds; check: a finished run (--log) against the "
                        "simulation of its own jobs")
    p.add_argument("--cores", type=int, default=2, help="the cores snakemake gets (--cores N, 1 to 1024; default 2)")
    add_preset(p, choices=("cpu", "paper"),
                   help="the preset whose stored run gives the job times (default cpu; check: the preset the "
                        "log's jobs ran at, which --preset must then be)")
    p.add_argument("--rate", type=float, help="this machine's learner benchmark in env steps per CPU-second (what "
                                              "`egosearch bench learner` prints as env_steps_per_core_s_cpu_profile): "
                                              "skips the calibration")
    p.add_argument("--from-bench", action="store_true",
                   help="take the rate recorded in --bench instead of calibrating (the README's figure)")
    p.add_argument("--bench", help="the learner benchmark record whose machine's ratio of a real training to the "
                                   "benchmark is used (default results/<preset>/bench/learner.json)")
    p.add_argument("--log", help="check: the run's Snakemake log (.snakemake/log/<date>.snakemake.log)")
    p.add_argument("--record", help="check: the provenance record whose job times predict the run (default "
                                    "results/<preset>/provenance.json; before a run rewrites it, keep a copy)")
    p.add_argument("--target", help="check: the target the run built (default all): its DAG gives the jobs' "
                                    "dependencies")
    add_record_outputs(p, "also print the figures as one JSON object", "the figures as JSON, with the command, "
                       "date, commit and machine", "estimate_all.json", "which the README reads")


def add_video(sub) -> None:
    p = sub.add_parser("video", help="a video of one full-body search: first-person depth + third-person view")
    p.add_argument("--character", default="humanoid_phase", help="humanoid_phase, humanoid_matching or fetch "
                                                                 "(default humanoid_phase)")
    p.add_argument("--scenarios", required=True, help="a scenario CSV written by `egosearch scenarios`")
    p.add_argument("--scenario-id", type=int, default=0, help="the scenario_id of the row to search (default 0)")
    p.add_argument("--first-success", metavar="FULLBODY_CSV",
                   help="film the first scenario (by scenario_id) that succeeded in this full-body CSV of the same "
                        "settings with no penetrating pose, in at least --min-steps steps (instead of --scenario-id, "
                        "which is filmed when none did)")
    p.add_argument("--min-steps", type=int, default=0,
                   help="--first-success: the fewest steps of a filmed episode, >= 0 (default 0)")
    p.add_argument("--policy", default="actor", help="actor (with --weights), oracle or random")
    p.add_argument("--weights", help="actor.pt of the search policy (for --policy actor only)")
    p.add_argument("--M", type=int, default=5, help="steps executed per plan, 1 to T (default 5)")
    p.add_argument("--T", type=int, default=20, help="planning horizon, >= 1 (default 20)")
    p.add_argument("--seed", type=int, default=0,
                   help="scenario k's episode is seeded with this + k, as `egosearch fullbody` seeds it (>= 0; "
                        "default 0)")
    p.add_argument("--out", required=True, help="the video: a .mp4 or .gif file")
    p.add_argument("--still", required=True, help="a .png of the moment the target is found")
    p.add_argument("--threads", type=int, default=1, help=THREADS)
    add_force(p)


def add_pictures(sub) -> None:
    p = sub.add_parser("pictures", help="top-down map, placement examples, first/third-person frame")
    p.add_argument("--layout", default="kitchen_living", help=f"home: {LAYOUTS}")
    p.add_argument("--out-dir", default="paper_figs/world", help="folder of the PNGs (default: paper_figs/world)")
    p.add_argument("--seed", type=int, default=0, help="seed of the placement examples, >= 0 (default 0)")
    add_force(p)


def add_report(sub) -> None:
    """One sub-command per report, each with its own options and ``--help``."""
    p = sub.add_parser("report", help="tables, figures, comparisons and provenance from result CSVs")
    reports = p.add_subparsers(dest="what", required=True, metavar="REPORT")
    preset = dict(default="cpu", help="preset: smoke, cpu or paper (default: cpu)")
    prefix = "output path without extension, or a folder (writes {})"

    r = reports.add_parser("table1", help="Table 1 (success per height and placement) from evaluation CSVs")
    r.add_argument("files", nargs="+", help="evaluation CSVs of one variant: .../{variant}/seed{seed}/{layout}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md, .csv and .tex"))
    r.add_argument("--variant", help="the variant of the files (default: read from their paths)")
    r.add_argument("--bounds", nargs="*", metavar="CSV", help="evaluation CSV paths of the searchers Table 1 sets "
                                                             f"beside the policy ({', '.join(searchers.bounds())}: "
                                                             ".../eval/SEARCHER/...): rows that bound the policy")
    r.add_argument("--learning-adds", metavar="CSV", help="the policy against its own start on the same scenarios "
                                                         "(compare/{variant}_vs_its_start.csv, rule learning_adds): "
                                                         "what its learning adds, said in the notes")
    add_force(r)

    r = reports.add_parser("table2", help="Table 2 (learner settings) from a learner preset")
    add_preset(r, **preset)
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md and .tex"))
    add_force(r)

    r = reports.add_parser("fig6", help="Figure 6 (success vs env steps) from training curves")
    r.add_argument("files", nargs="+", help="curve.csv files: .../train/{variant}/seed{seed}/curve.csv")
    levels = ", ".join(s.name for s in searchers.SEARCHERS.values() if s.fig6_level)
    r.add_argument("--levels", nargs="*", help=f"evaluation CSVs of searchers that do not train ({levels}: "
                   ".../eval/SEARCHER/seedN/...): a horizontal line each")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))
    add_force(r)

    r = reports.add_parser("fig7", help="Figure 7 (SPL and attempts per method) from full-body CSVs")
    r.add_argument("files", nargs="+", help="full-body CSVs: .../{setting}/seed{seed}.csv")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))
    r.add_argument("--planner", default="actor", choices=("actor", "oracle"),
                   help="which planner drove the full-body runs (oracle figures say so in a title)")
    add_force(r)

    r = reports.add_parser("budget", help="the budget study: success at one cell vs env steps and core-hours")
    r.add_argument("--run", action="append", required=True, metavar="SETTING=CURVE_CSV:EVAL_CSV",
                   help="one training run of a setting: its curve.csv and its per-episode CSV at the cell "
                        "(repeat per seed and setting)")
    r.add_argument("--chosen", help="the setting the preset uses (drawn filled): one of the --run settings")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".png, .pdf and .csv"))
    add_force(r)

    r = reports.add_parser("compare", help="a candidate variant vs the reference: difference, 95%% CI, p per cell "
                                           "and per shortest-path bin")
    r.add_argument("--reference", nargs="+", required=True, help="the reference variant's evaluation CSVs")
    r.add_argument("--candidate", nargs="+", required=True, help="the candidate variant's evaluation CSVs")
    r.add_argument("--aggregate", help="also write the aggregate over seeds and cells (interquartile mean, "
                   "probability of improvement) to this CSV")
    r.add_argument("--spread", nargs="+", help="every stored seed's evaluation CSVs of the reference variant: a "
                   "screen, read with the seed-spread test on their spread (docs/statistics.md)")
    r.add_argument("--out", help="write the comparison to this CSV (and the split by shortest path ℓ, every cell "
                                 "pooled, to <out stem>_by_length.csv) as well as printing them")
    add_force(r, "; also compares a candidate file with the same content as a reference file (refused without it: "
                 "a copy)")

    r = reports.add_parser("pathlength", help="success by shortest path ℓ and by detour, with two-level intervals")
    r.add_argument("files", nargs="+", help="evaluation CSVs of one variant: .../{variant}/seed{seed}/{home}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--scenarios", nargs="+", required=True, help="the scenario sets they ran: .../scenarios/{home}/"
                                                                 "{placement}/h{height}.csv")
    r.add_argument("--bounds", nargs="*", help="the reference searchers' evaluation CSVs on the same scenarios "
                                               f"({', '.join(searchers.bounds())}: .../eval/SEARCHER/...): a line "
                                               "each")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".md, .png and .pdf"))
    r.add_argument("--out-csv", help="the numbers (default: <out-prefix>.csv)")
    add_force(r)

    r = reports.add_parser("generalise", help="trained-on x evaluated-on: normalised scores per group of homes")
    r.add_argument("files", nargs="+", help="evaluation CSVs of the policies: .../{variant}/seed{seed}/{group}/"
                                            "{placement}/h{height}.csv")
    r.add_argument("--bounds", nargs="+", required=True, help="the random searcher's and the oracle's evaluation "
                                                              "CSVs on the same groups")
    r.add_argument("--generated", help="the variant trained in generated homes (its gap to its training split); "
                                       "one of the files' variants")
    r.add_argument("--reference", help="the variant trained in the paper homes: the generated-homes variant's "
                                       "score there is read against it (one of the files' variants; needs --generated)")
    r.add_argument("--trained-on", nargs="*", default=[], metavar="VARIANT=HOMES",
                   help="what each of the files' variants trained in, for the labels")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".csv, .md and .png"))
    add_force(r)

    r = reports.add_parser("fresh", help="the reference on its stored scenario sets against fresh sets of the same "
                                         "cells: is a gain tuned to the stored sets?")
    r.add_argument("--stored", nargs="+", required=True, help="evaluation CSVs on the stored sets: .../{variant}/"
                                                              "seed{seed}/{home}/{placement}/h{height}.csv")
    r.add_argument("--fresh", nargs="+", required=True, help="the same actors' evaluation CSVs on the fresh sets")
    r.add_argument("--variant", default="head_on", help="the variant, for the caption (default: head_on)")
    r.add_argument("--fresh-seed", type=int, help="the fresh sets' scenario seed (>= 0), for the caption")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".csv and .md") + "; no dot in its name")
    add_force(r, "; also reads a --fresh file with the same content as a --stored one (refused without it: a copy)")

    traces = "trace files of `egosearch evaluate --traces`: .../{variant}/seed{seed}/{layout}/{placement}/h{height}.npz"

    r = reports.add_parser("behaviour", help="how the policies search, from per-step traces, and the paper's "
                                             "behaviour sentences (Section 6.3, Figure 6) read against them")
    r.add_argument("files", nargs="+", help=traces)
    r.add_argument("--pairs", nargs="+", default=["head_on:head_off"],
                   metavar="HEAD_ON:HEAD_OFF",
                   help="the pairs the claims are read on, side by side, the first leading: the variant (or "
                        "searcher) that moves its head and the one that does not, each among the files' "
                        "(default: head_on:head_off)")
    r.add_argument("--out-prefix", required=True,
                   help=prefix.format("_episodes.csv, .csv, .md, _claims.csv and _claims.md"))
    add_force(r)

    r = reports.add_parser("searches", help="top-down pictures of chosen searches and a gaze heatmap per cell, "
                                            "from per-step traces")
    r.add_argument("files", nargs="+", help=traces)
    r.add_argument("--seed", type=int, default=0, help="the seed whose files give the pictured searches: one of "
                                                        "the files' seeds (default 0)")
    r.add_argument("--out-dir", required=True, help="folder of the PNGs")
    add_force(r)

    r = reports.add_parser("provenance", help="commit, machine, date and job wall times of a results folder")
    add_preset(r, **preset)
    r.add_argument("--results", default="results/cpu", help="the results folder (default: results/cpu)")
    r.add_argument("--out", required=True, help="the provenance JSON to write")
    r.add_argument("--note", help="free text kept in the record (e.g. how the run was resumed)")
    add_force(r)

    r = reports.add_parser("failures", help="how each traced searcher fails per cell: stuck, never saw the target, "
                                          "saw and lost it, timed out near it (egosearch.report.failures)")
    r.add_argument("files", nargs="+", help="per-step trace files (.npz) of one or more searchers")
    r.add_argument("--out-prefix", required=True, help="writes PREFIX.csv, PREFIX_stuck.csv and PREFIX.md")
    r.add_argument("--stuck-read", nargs="*", default=[], help="the searchers whose stuck episodes PREFIX.md reads: "
                   "what they are pressed against, seen before or not, what they did (egosearch.report.stuck_contacts)")
    add_force(r)

    r = reports.add_parser("memory-window", help="how much memory the task asks for: the tuned searcher held to its "
                                                "last K steps against the students (egosearch.report.memory_window)")
    r.add_argument("--searchers", nargs="+", required=True, metavar="CSV",
                   help="evaluation CSVs of the memory-window searchers (frontier_tuned_window{K}, "
                        "frontier_tuned_head_off_window{K}) and of the whole-episode ones, on Table 1's sets: "
                        ".../eval/{searcher}/seed0/{home}/{placement}/h{height}.csv")
    r.add_argument("--students", nargs="+", required=True, metavar="CSV",
                   help="the students' evaluation CSVs on the same sets, every seed: one head-moving variant and "
                        "one head-fixed variant")
    r.add_argument("--out-prefix", required=True, help=prefix.format(".csv, .md, .png and .pdf"))
    add_force(r)

    r = reports.add_parser("null-screen", help="the reference's seeds screened against each other, before and after "
                                             "the seed spread counts (a consistency check, the spread held out); "
                                             "its summary with the test's simulated level (docs/statistics.md)")
    r.add_argument("files", nargs="+", help="every spread seed's evaluation CSVs of one variant")
    r.add_argument("--out", required=True, help="the null screen's CSV")
    r.add_argument("--summary", required=True, help="the seed spread, false-positive rates and power, as JSON")
    r.add_argument("--simulations", type=int, help="simulated screens per setting of the false-positive rate "
                   "(default: the stored record's, egosearch.report.calibration.SIMULATIONS)")
    add_force(r)

    r = reports.add_parser("reread-screens", help="every stored screen read again with the seed-spread test, beside "
                                                "its stored verdict (docs/ablations/reread.md)")
    add_preset(r, **preset)
    r.add_argument("--out", required=True, help="the re-read's CSV")
    add_force(r)

    r = reports.add_parser("regenerate", help="every table and figure from the stored CSVs of a preset (seconds)")
    add_preset(r, **preset)
    r.add_argument("--variant", help="the variant of Table 1 (default: the workflow config's reference_variant)")

    r = reports.add_parser("verify", help="check every stored result file against the sha256 in its provenance")
    add_preset(r, **preset)

    r = reports.add_parser("readme", help="rewrite the generated blocks of the README and the docs pages from the "
                                          "stored results")
    add_preset(r, **preset)
    r.add_argument("--readme", help="the one page whose marked blocks are rewritten (default: README.md and every "
                                    "page under docs/ of the current folder)")
    r.add_argument("--check", action="store_true", help="only check that the blocks are up to date (exit 2 if not)")
