# Inputs are ancient(): stored results are trusted whatever their file times (a fresh clone gives
# every file the checkout time). A job still reruns when a job upstream of it runs, but Snakemake
# does not rerun a job with stored outputs for a MISSING input (a variant added to the config):
# the Snakefile names such rules and the `-R` that redoes them.
# Names and paths shared by every rule. Every output path is a function of
# (profile, variant, seed, layout, placement, height): Snakemake knows them all in advance.
from pathlib import Path

# Optional (`--use-conda`): the software every rule runs with.
CONDA_ENV = "../envs/egosearch.yaml"

PROFILE = config["profile"]
PROF = config["profiles"][PROFILE]
LAYOUT = config["layout"]
SEEDS = PROF["seeds"]
HEIGHTS = [f"{h:g}" for h in config["heights"]]
PLACEMENTS = config["placements"]
FULLBODY = PROF["fullbody"]
REF = config["reference_variant"]
RESULTS = f"results/{PROFILE}"
FIGS = f"paper_figs/{PROFILE}"
BASELINES = ["one_step_short", "one_step_long", "noisy_search"]

# The variants `all` trains (checked in the Snakefile with the compare candidate, if any).
VARIANTS = {name: CHECKED_VARIANTS[name] for name in dict.fromkeys(config["variants"] + [REF])}

wildcard_constraints:
    profile="smoke|cpu|paper",
    variant="[A-Za-z0-9_\\-]+",
    seed="[0-9]+",
    height="[0-9.]+",
    placement="no_low_cabinets|everywhere",
    layout="kitchen_living|bedroom_bath|studio|home[0-9]+",
    setting="(ours-M[0-9]+|one_step_short|one_step_long|noisy_search)-(humanoid_phase|humanoid_matching|fetch)",


def scenario_file(placement, height):
    return f"{RESULTS}/scenarios/{LAYOUT}/{placement}/h{height}.csv"


def eval_files(variant):
    return expand(f"{RESULTS}/eval/{variant}/seed{{seed}}/{LAYOUT}/{{placement}}/h{{height}}.csv",
                  seed=SEEDS, placement=PLACEMENTS, height=HEIGHTS)


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


def train_resources(profile):
    """Portable resources: the same DAG runs locally, under slurm or cluster-generic."""
    if profile == "paper":
        return dict(mem_mb=8000, runtime=72 * 60, gpu=1)
    if profile == "cpu":
        return dict(mem_mb=3000, runtime=90, gpu=0)
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


# The floor and the ceiling of Table 1 on the very scenario sets the policies are evaluated on.
# Their CSVs sit beside the variants' (eval/random, eval/oracle): a variant may not take those names.
BOUNDS = ["random", "oracle"]
# One seed: the oracle is deterministic, and the random searcher's spread over 100 scenarios per
# cell is far wider than its spread over seeds.
BOUND_SEEDS = [0]


def bound_files(bounds=BOUNDS, placements=None):
    return expand(f"{RESULTS}/eval/{{bound}}/seed{{seed}}/{LAYOUT}/{{placement}}/h{{height}}.csv",
                  bound=bounds, seed=BOUND_SEEDS, placement=placements or PLACEMENTS, height=HEIGHTS)


def fig6_random_files():
    """The random searcher on the Table 1 cells of the placement scheme the reference trains and
    is evaluated in during training (Figure 6's curves): its level in that figure."""
    placement = VARIANTS[REF].train_env["placement"]
    return bound_files(["random"], [placement]) if placement in PLACEMENTS else []


# The budget study: a setting is a variant file (ablations/budget_*.yaml: learner overrides on top
# of the profile), so the train and evaluate rules serve it unchanged; the profile's own setting
# is the reference variant's runs, which `all` makes anyway.
BUDGET = PROF.get("budget", {"variants": [], "seeds": [0]})
BUDGET_CELL = ("no_low_cabinets", "1.05")


def budget_runs(variant, seeds):
    placement, height = BUDGET_CELL
    return [(f"{RESULTS}/train/{variant}/seed{seed}/curve.csv",
             f"{RESULTS}/eval/{variant}/seed{seed}/{LAYOUT}/{placement}/h{height}.csv") for seed in seeds]


def budget_inputs():
    runs = {v: budget_runs(v, BUDGET["seeds"]) for v in BUDGET["variants"]}
    runs[REF] = budget_runs(REF, SEEDS)
    return runs


