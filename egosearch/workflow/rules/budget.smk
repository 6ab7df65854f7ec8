# The budget study (`snakemake --cores 2 budget`, not part of `all`): success at 1.05 m excluding
# low cabinets against env steps and core-hours, for the learner settings of config `budget:`.
# A setting is a variant file (ablations/budget_*.yaml: learner overrides on top of the profile),
# so the train and evaluate rules serve it unchanged; the profile's own setting is the reference
# variant's runs, which `all` makes anyway.
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


rule budget:
    """What each learner setting buys per env step and per core-hour (the evidence for the profile)."""
    input:
        ancient([path for runs in budget_inputs().values() for pair in runs for path in pair]),
    output:
        expand(f"{FIGS}/budget.{{ext}}", ext=["png", "pdf", "csv"]),
    log:
        f"{RESULTS}/logs/report/budget.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/budget.tsv"
    params:
        runs=" ".join(f"--run {v}={curve}:{evals}" for v, runs in budget_inputs().items() for curve, evals in runs),
        chosen=REF,
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report budget {params.runs} --chosen {params.chosen} --out-prefix {params.prefix} > {log} 2>&1"
