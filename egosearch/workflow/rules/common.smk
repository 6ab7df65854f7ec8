# Inputs are ancient(): stored results are trusted whatever their file times (a fresh clone gives
# every file the checkout time). A job still reruns when a job upstream of it runs, but Snakemake
# does not rerun a job with stored outputs for a MISSING input (a variant added to the config):
# the Snakefile names such rules and the `-R` that redoes them.
# Names and paths shared by every rule. Every output path is a function of
# (preset, variant, seed, layout, placement, height): Snakemake knows them all in advance.
from pathlib import Path

from snakemake.exceptions import WorkflowError

from egosearch.core.gpu_share import resolve_trainings_per_gpu, train_threads
from egosearch.workflow.cluster import (is_cluster, partitions_asked, profile_mix_problem, resource_problem,
                                       slurm_run_problem, snakemake_args, snakemake_executor)
from egosearch.report.workflow_jobs import BOUND_SEEDS, bound_eval_files, workflow_heights
from egosearch.searchers import searcher_registry as searchers
from egosearch.workflow.check import claims_pairs, set_arguments, variant_head, workflow_set

# The executor of this run (--executor, or a profile's executor:, as profiles/slurm names slurm): Snakemake
# parses the Snakefile before it hands the run its executor, so workflow.local_exec cannot tell
# (egosearch.workflow.cluster). Under a cluster executor each job is a cluster job of its own.
EXECUTOR = snakemake_executor()
LOCAL_RUN = not is_cluster(EXECUTOR)
_args = snakemake_args()
_mix = _args is not None and workflow.is_main_process and profile_mix_problem(
    getattr(_args, "profile", None), getattr(_args, "workflow_profile", None))
if _mix:
    import sys

    print(f"egosearch: error: {_mix}", file=sys.stderr)
    sys.exit(1)
if EXECUTOR == "slurm" and workflow.is_main_process:
    # every job's memory and time a number > 0, sbatch, squeue and sinfo on PATH (a real run), and every
    # slurm_partition the run names on the cluster: one line here, before the first job, not an sbatch error per
    # job once the run has started
    _default_args = getattr(workflow.resource_settings.default_resources, "args", None) or []
    _overrides = workflow.resource_settings.overwrite_resources or {}
    _problem = resource_problem(_default_args, _overrides) or slurm_run_problem(
        workflow.output_settings.dryrun, partitions_asked(_default_args, _overrides))
    if _problem:
        import sys

        print(f"egosearch: error: {_problem}", file=sys.stderr)
        sys.exit(1)

# Optional (`--use-conda`): the software every rule runs with.
CONDA_ENV = "../envs/egosearch.yaml"

PRESET = config["preset"]
PROF = config["presets"][PRESET]
LAYOUT = config["layout"]  # the full-body runs', the budget cell's and the pictures' home
HOMES = config["homes"]  # Table 1's homes
SEEDS = PROF["seeds"]
HEIGHTS = workflow_heights(config)
PLACEMENTS = config["placements"]
FULLBODY = PROF["fullbody"]
REF = config["reference_variant"]
RESULTS = f"results/{PRESET}"
# `--config set="FIELD=VALUE,..."`: learner fields on top of every variant's, handed to the trainings (and
# demonstrations) this run makes as `--set` arguments (checked in the Snakefile with the config)
SET_OVERRIDES = workflow_set(config)
SET_ARGS = set_arguments(SET_OVERRIDES)
FIGS = f"paper_figs/{PRESET}"
BASELINES = ["one_step_short", "one_step_long", "noisy_search"]

# The variants `all` trains (checked in the Snakefile with the compare candidate, if any).
VARIANTS = {name: CHECKED_VARIANTS[name] for name in dict.fromkeys(config["variants"] + [REF])}

wildcard_constraints:
    preset="smoke|cpu|paper",
    variant="[A-Za-z0-9_\\-]+",
    seed="[0-9]+",
    height="[0-9.]+",
    placement="no_low_cabinets|everywhere",
    layout="kitchen_living|bedroom_bath|studio|home[0-9]+|generated_heldout|generated_train",
    setting="(ours-M[0-9]+|one_step_short|one_step_long|noisy_search)-(humanoid_phase|humanoid_matching|fetch)",


def refuse_unwritable_outputs():
    """Before a real run's first job: every folder its jobs write in (outputs, logs, benchmarks) can be written
    (egosearch.workflow.check.unwritable_outputs_line), else one line and exit 1."""
    from egosearch.workflow.check import unwritable_outputs_line

    line = unwritable_outputs_line(f for job in workflow.dag.needrun_jobs()
                                   for f in [*job.output, *job.log, *([job.benchmark] if job.benchmark else [])])
    if line:
        print(line, file=sys.stderr)
        sys.exit(1)


def refuse_damaged_inputs():
    """Before a real run's first job: the stored files its jobs read must be the ones their provenance recorded
    (egosearch.workflow.check.damaged_inputs_line), else one line and exit 1, before anything is written."""
    from egosearch.workflow.check import damaged_inputs_line

    line = damaged_inputs_line(f for job in workflow.dag.needrun_jobs() for f in job.input)
    if line:
        print(line, file=sys.stderr)
        sys.exit(1)


def claim_the_plans_outputs():
    """Before a real run's first job: no other run in this clone is making a file this one makes, else one line
    naming it and exit 1; the run's record is removed when it ends (egosearch.workflow.run_lock: the suite's own,
    as a run that ends removes Snakemake's lock folder, the locks of runs still going included)."""
    import atexit

    from egosearch.workflow.run_lock import claim, release

    line = claim((f for job in workflow.dag.needrun_jobs() for f in job.output), sys.argv)
    if line:
        print(line, file=sys.stderr)
        sys.exit(1)
    atexit.register(release)


def print_the_plans_cost():
    """The cost of what this invocation runs (egosearch.cost.estimate.print_costs): the jobs of its DAG that
    need to run, counted as Snakemake's job stats count them, trainings and evaluations of the reference
    included; nothing when nothing is to be done. No target given: Snakemake builds the first rule, `all`."""
    from egosearch.cost.estimate import print_costs
    from egosearch.workflow.dag import plan_jobs, whole_dag

    print_costs(workflow.dag_settings.targets or {"all"}, config, PRESET, SEEDS, REF, cores_given(),
                trainings_per_gpu=TRAININGS_PER_GPU, plan=plan_jobs(workflow.dag, PRESET),
                whole=whole_dag(workflow.dag))


def check_the_trainings_set_once_built():
    """Once the DAG is built, in a dry run as in a real one and before any job: every training of the plan takes
    the workflow config's `set`, and none stored in its folder was trained with another set (none, without a
    `set`) (egosearch.workflow.check.trainings_set_line), else one line and exit 1. Snakemake has no hook
    between building the DAG and printing a dry run's plan, so its DAG-building step is wrapped (as the cost
    line's is, print_the_plans_cost_once_built)."""
    from egosearch.workflow.check import trainings_set_line

    build_dag = getattr(workflow, "_build_dag", None)
    if build_dag is None:
        return

    def build_then_check():
        build_dag()
        trainings = [(job.wildcards.variant, Path(str(job.output[0])).parent)
                     for job in workflow.dag.jobs if job.rule.name == "train"]
        line = trainings_set_line(trainings, SET_OVERRIDES, lambda variant: PROF["learner"])
        if line:
            print(f"egosearch: error: {line}", file=sys.stderr)
            sys.exit(1)

    workflow._build_dag = build_then_check


def print_the_plans_cost_once_built():
    """A dry run's cost line: Snakemake calls onstart only before a real run's first job and has no hook for a
    dry run's DAG, so its DAG-building step is wrapped to print the line (print_the_plans_cost) when the DAG
    is there, before Snakemake prints the plan. A Snakemake without that step (pyproject pins 9.x, which has
    it) gets no dry-run cost line rather than a failed dry run."""
    build_dag = getattr(workflow, "_build_dag", None)
    if build_dag is None:
        return

    def build_then_print():
        build_dag()
        print_the_plans_cost()

    workflow._build_dag = build_then_print


def scenario_file(placement, height):
    return f"{RESULTS}/scenarios/{LAYOUT}/{placement}/h{height}.csv"


def table1_scenario_files():
    """The scenario set of every Table 1 cell in every home."""
    return expand(f"{RESULTS}/scenarios/{{home}}/{{placement}}/h{{height}}.csv",
                  home=HOMES, placement=PLACEMENTS, height=HEIGHTS)


def pathlength_files(variants=None):
    """`pathlength`'s outputs per variant: its numbers under results/, its table and figure under paper_figs/."""
    return [path for v in (variants or VARIANTS)
            for path in (f"{RESULTS}/pathlength/{v}.csv", *(f"{FIGS}/pathlength_{v}.{ext}" for ext in ("md", "png", "pdf")))]


def cores_given():
    """The cores a run on this machine lays its jobs out on: --cores, else --jobs (Snakemake's alias for it
    on one machine; profiles/default gives 2, so `snakemake all` runs as typed), a dry run's too (Snakemake
    gives a dry run 1 core unless --cores says otherwise, not the cores its real run would have). None under
    a cluster executor, which lays its jobs out itself (its --jobs are jobs submitted at once)."""
    import sys

    argv = sys.argv[1:]
    if not LOCAL_RUN:
        return None
    named = any(a == "--cores" or a.startswith("--cores=") or (a.startswith("-c") and not a.startswith("--"))
                for a in argv)
    if workflow.output_settings.dryrun and not named and workflow.nodes:
        return int(workflow.nodes)
    try:
        return workflow.cores
    except WorkflowError:
        return None


def eval_files(variant, homes=None):
    return expand(f"{RESULTS}/eval/{variant}/seed{{seed}}/{{home}}/{{placement}}/h{{height}}.csv",
                  seed=SEEDS, home=homes or HOMES, placement=PLACEMENTS, height=HEIGHTS)


def train_checkpoint(rule, outputs):
    """The checkpoint a job of ``rule`` resumes from after a kill: a training's, in its work folder beside its
    outputs (rules/train.smk: params.work_dir); None for every other rule, which starts over."""
    from egosearch.core.staging import CHECKPOINT_NAME

    return Path(outputs[0]).parent / "partial" / CHECKPOINT_NAME if rule == "train" and outputs else None


def start_actor(actor_path):
    """The start actor file beside a run's actor.pt."""
    from egosearch.core.staging import START_ACTOR_NAME

    return str(Path(actor_path).with_name(START_ACTOR_NAME))


def start_eval_files(variant):
    """``eval_files`` of the variant's start (its actor_start.pt): the policy before it learned."""
    return [f.replace(f"{RESULTS}/eval/", f"{RESULTS}/eval_start/", 1) for f in eval_files(variant)]


def curve_files(variant):
    return expand(f"{RESULTS}/train/{variant}/seed{{seed}}/curve.csv", seed=SEEDS)


def fullbody_settings():
    out = []
    for mg in FULLBODY["motion_generators"]:
        out += [f"ours-M{m}-{mg}" for m in FULLBODY["ms"]]
        out += [f"{baseline}-{mg}" for baseline in BASELINES]
    return out


def fullbody_files(planner="actor"):
    """Full-body CSVs of every setting: planner ``actor`` (the reference variant's policy, paper
    Figure 7) or ``oracle`` (the privileged planner)."""
    stage = "fullbody" if planner == "actor" else f"fullbody_{planner}"
    return expand(f"{RESULTS}/{stage}/{{setting}}/seed{{seed}}.csv",
                  setting=fullbody_settings(), seed=FULLBODY["seeds"])


def provenance_file():
    return f"{RESULTS}/provenance.json"


# Paper-preset trainings side by side on one GPU (config trainings_per_gpu; egosearch.core.gpu_share): on one
# machine each asks for one of `gpu_slots`, which the run offers that many of (unless the command line's
# --resources names gpu_slots: then that many), and takes a fair share of --cores; under a cluster executor each
# training is a job asking for a whole GPU. Outputs and paths are the same either way.
if PRESET == "paper":
    try:
        TRAININGS_PER_GPU = resolve_trainings_per_gpu(config.get("trainings_per_gpu", "auto"), LOCAL_RUN)
    except ValueError as err:
        import sys

        print(f"egosearch: error: {err}", file=sys.stderr)
        sys.exit(1)
    if LOCAL_RUN and "gpu_slots" in workflow.global_resources:
        SLOTS = int(workflow.global_resources["gpu_slots"].value)
        if SLOTS < 1:
            # each training asks for one slot: with none, the plan lists trainings that could never start
            import sys

            print(f"egosearch: error: --resources gpu_slots={SLOTS}: every paper-preset training asks for one "
                  "gpu_slots (its share of the GPU), so none could start; give gpu_slots=1 or more (the trainings "
                  "side by side on one GPU), or leave it out (config trainings_per_gpu sets it: "
                  f"{TRAININGS_PER_GPU} here)", file=sys.stderr)
            sys.exit(1)
        TRAININGS_PER_GPU = SLOTS
    elif LOCAL_RUN:
        workflow.register_resource("gpu_slots", TRAININGS_PER_GPU)
else:
    TRAININGS_PER_GPU = 1
TRAIN_THREADS = train_threads(PRESET, cores_given() if LOCAL_RUN else None, TRAININGS_PER_GPU)


def train_resources(preset):
    """Portable resources: the same DAG runs locally, under slurm or cluster-generic."""
    if preset == "paper":
        # a few times the training's length on the one GPU measured (docs/gpu.md), for slower GPUs; on one
        # machine a share of its GPU (gpu_slots, above), under a cluster executor a whole one
        return dict(mem_mb=8000, runtime=12 * 60, **(dict(gpu_slots=1) if LOCAL_RUN else dict(gpu=1)))
    if preset == "cpu":
        # a per-step training with its teacher's episodes takes about an hour alone on the reference CPU, and
        # hosts differ up to 3x: the stored run's longest took 191 min (a 50 px variant with the target memory),
        # its preset's own trainings up to 108 min; the largest held 4.8 GB (the map-image lever, whose replay
        # keeps a 4 x 32 x 32 map a step, resumed from its checkpoint; from the start 3.3 GB; the others up to
        # 2.5 GB), plus the job's own snakemake (tests/test_cluster.py reads them)
        return dict(mem_mb=5500, runtime=6 * 60, gpu=0)
    return dict(mem_mb=1500, runtime=10, gpu=0)


def fullbody_scenarios(wildcards):
    # Each character searches at its own camera height: the humanoid at 1.65 m, Fetch at 1.05 m.
    height = "1.05" if wildcards.setting.endswith("-fetch") else "1.65"
    return scenario_file("everywhere", height)


def compare_candidate(wildcards):
    # The Snakefile has checked the variant; without one (compare run through the API, not the
    # command line), this is the one error left for DAG time.
    if not config.get("variant"):
        raise ValueError("compare needs a variant: snakemake compare --config variant=NAME")
    return eval_files(config["variant"])


SCREEN_SEEDS = list(range(config["screen_seed"], config["screen_seed"] + config["screen_seeds"]))
# The reference's seeds that measure the seed spread (the preset's spread_seeds; its seeds when it names none).
SPREAD_SEEDS = PROF.get("spread_seeds", SEEDS)


def screen_files(variant):
    """The screened seeds' evaluation files (config screen_seed, screen_seeds) of every Table 1 cell."""
    return expand(f"{RESULTS}/eval/{variant}/seed{{seed}}/{{home}}/{{placement}}/h{{height}}.csv",
                  seed=SCREEN_SEEDS, home=HOMES, placement=PLACEMENTS, height=HEIGHTS)


def spread_files(variant):
    """Every spread seed's evaluation files of every Table 1 cell: the seed spread a screen counts."""
    return expand(f"{RESULTS}/eval/{variant}/seed{{seed}}/{{home}}/{{placement}}/h{{height}}.csv",
                  seed=SPREAD_SEEDS, home=HOMES, placement=PLACEMENTS, height=HEIGHTS)


def stored_screens():
    """The stored screens (screen_NAME_seedN_vs_...csv, screen_NAME_seedsA-B_vs_...csv; their ℓ, aggregate and
    stuck files left out), which `screens_reread` reads again."""
    return sorted(str(p) for p in Path(RESULTS, "compare").glob("screen_*_seed*_vs_*.csv")
                  if not p.stem.endswith(("_by_length", "_aggregate", "_stuck")))


def screen_name():
    """screen_NAME_seed0_vs_REF (one seed), screen_NAME_seeds0-2_vs_REF (three)."""
    seeds = f"seed{SCREEN_SEEDS[0]}" if len(SCREEN_SEEDS) == 1 else f"seeds{SCREEN_SEEDS[0]}-{SCREEN_SEEDS[-1]}"
    return f"screen_{config.get('variant') or 'none'}_{seeds}_vs_{REF}"


def screen_candidate(wildcards):
    if not config.get("variant"):
        raise ValueError("screen needs a variant: snakemake screen --config variant=NAME")
    return screen_files(config["variant"])


# The floor, the classical searcher and the ceiling of Table 1, on the very scenario sets the policies
# are evaluated on.
# Their CSVs sit beside the variants' (eval/random, eval/frontier, ...): a variant may not take those names.
# BOUNDS (the registered bounds, egosearch.searchers.searcher_registry: random, frontier, frontier_head_off,
# oracle). One seed (BOUND_SEEDS): the oracle is deterministic, and the random searcher's spread over 100
# scenarios per cell is far wider than its spread over seeds. bound_eval_files is the order `egosearch
# report regenerate` reads them in too.
# REFERENCE_SEARCHERS is every registered searcher (evaluated by the bound rule), CLASSICAL_SEARCHERS
# those claims_pairs may name (traced by trace_bound), MODULAR_FLOORS a modular searcher's floor by the
# decision env its high level trained in (read by decisions_floor).
BOUNDS = searchers.bounds()
REFERENCE_SEARCHERS = searchers.names()
CLASSICAL_SEARCHERS = searchers.classical()
MODULAR_FLOORS = searchers.modular_floors()
# `versus_teacher`'s comparisons: Figure 6's pair, each against the classical searchers of its own head (the one it
# learned from, read from its config, among them), as (variant, searcher) pairs.
VERSUS_TEACHER = [(variant, searcher) for variant in claims_pairs(config)[0]
                  for searcher in searchers.classical_with_head(variant_head(variant))]


def bound_files(bounds=BOUNDS, placements=None, homes=None):
    return bound_eval_files(RESULTS, homes or HOMES, placements or PLACEMENTS, HEIGHTS, bounds, BOUND_SEEDS)


def fig6_level_files():
    """The random and classical searchers (head moving and head fixed) on the scenarios the reference's training
    curve is evaluated on, each episode seeded as the curve's: their levels in Figure 6 (rule curve_level)."""
    return [f"{RESULTS}/eval_curve/{s}/{REF}.csv" for s in BOUNDS if searchers.get(s).fig6_level]


# The budget study: a setting is a variant file (ablations/budget_*.yaml: learner overrides on top
# of the preset), so the train and evaluate rules serve it unchanged; the preset's own setting
# is the runs of BUDGET_REF, all seeds.
BUDGET = PROF.get("budget", {"variants": [], "seeds": [0]})
# The setting the others are read against: the reference variant (whose runs `all` makes anyway)
# unless `budget: reference` names one that trains where the budget settings train.
BUDGET_REF = BUDGET.get("reference", REF)
BUDGET_CELL = ("no_low_cabinets", "1.05")


def budget_runs(variant, seeds):
    placement, height = BUDGET_CELL
    return [(f"{RESULTS}/train/{variant}/seed{seed}/curve.csv",
             f"{RESULTS}/eval/{variant}/seed{seed}/{LAYOUT}/{placement}/h{height}.csv") for seed in seeds]


def budget_inputs():
    runs = {v: budget_runs(v, BUDGET["seeds"]) for v in BUDGET["variants"]}
    runs[BUDGET_REF] = budget_runs(BUDGET_REF, SEEDS)
    return runs


# The generalisation benchmark (generalise.smk): each group of homes is one scenario file per
# placement; GEN_GROUPS maps a group to its generated home seeds [first, stop).
from egosearch.scene.layouts import HELDOUT_HOME_SEEDS

GEN = config["generalise"]
GEN_HEIGHT = f"{GEN['height']:g}"
GEN_VARIANTS = {name: CHECKED_VARIANTS[name] for name in GEN["variants"]}
_split = CHECKED_VARIANTS[GEN["generated_variant"]].train_env["home_seeds"]
# group -> generated home seeds [first, stop)
GEN_GROUPS = {
    "generated_heldout": (HELDOUT_HOME_SEEDS.start, HELDOUT_HOME_SEEDS.stop),
    "generated_train": (_split[0], min(_split[1], _split[0] + GEN["train_homes"])),
}


def generalise_files(who, seeds):
    homes = list(GEN_GROUPS) + HOMES
    return expand(f"{RESULTS}/eval/{who}/seed{{seed}}/{{home}}/{{placement}}/h{GEN_HEIGHT}.csv",
                  seed=seeds, home=homes, placement=PLACEMENTS)


# The fresh-set check (rules/fresh.smk): the stored sets' cells drawn again with this seed.
FRESH_SEED = config.get("fresh_scenario_seed", 7)


def fresh_files(kind):
    """The reference's evaluations of every seed and Table 1 cell: on the stored sets, or the fresh."""
    root = f"{RESULTS}/fresh/eval" if kind == "fresh" else f"{RESULTS}/eval"
    return expand(f"{root}/{REF}/seed{{seed}}/{{home}}/{{placement}}/h{{height}}.csv",
                  seed=SEEDS, home=HOMES, placement=PLACEMENTS, height=HEIGHTS)


def decisions_floors():
    """(variant, floor) for each variant of the preset's claims pairs that is a modular searcher (at the cpu
    preset the stored modular pair, head_on_modular and head_off_modular): its floor is the same walk with
    random decisions (MODULAR_FLOORS), on the same stored sets."""
    from egosearch.variants import resolve_variant

    learner = PROF["learner"]
    out = []
    for pair in claims_pairs({**config, "preset": PRESET}):
        for variant in pair:
            if variant not in CHECKED_VARIANTS:  # a classical searcher's pair
                continue
            env_id = resolve_variant(CHECKED_VARIANTS[variant], learner).env_id
            if env_id in MODULAR_FLOORS and (variant, MODULAR_FLOORS[env_id]) not in out:
                out.append((variant, MODULAR_FLOORS[env_id]))
    return out


DECISIONS_FLOORS = decisions_floors()
