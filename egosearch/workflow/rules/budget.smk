# The budget study (`snakemake --cores 2 budget`, not part of `all`): success at 1.05 m excluding
# low cabinets against env steps and core-hours, for the learner settings of config `budget:`
# (their paths: budget_inputs in common.smk).
rule budget:
    """What each learner setting buys per env step and per core-hour (the evidence for the preset)."""
    input:
        ancient([path for runs in budget_inputs().values() for pair in runs for path in pair]),
    output:
        update(expand(f"{FIGS}/budget.{{ext}}", ext=["png", "pdf", "csv"])),
    log:
        f"{RESULTS}/logs/report/budget.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/budget.tsv"
    params:
        runs=" ".join(f"--run {v}={curve}:{evals}" for v, runs in budget_inputs().items() for curve, evals in runs),
        chosen=BUDGET_REF,
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report budget --force {params.runs} --chosen {params.chosen} --out-prefix {params.prefix} "
        "> {log} 2>&1"
