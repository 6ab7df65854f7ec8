# The fresh-set check (`snakemake --cores 2 fresh`, outside `all`): the reference's trained actors
# on scenario sets drawn with `fresh_scenario_seed` in Table 1's homes and cells, read against the
# stored sets. The sets and evaluations live under results/{preset}/fresh/, apart from Table 1's.
# (workflow_check refuses a fresh seed equal to the stored sets' seed). The sets and evaluations are
# the scenarios and evaluate rules' jobs with the fresh seed and paths.


use rule scenarios as fresh_scenarios with:
    output:
        update("results/{preset}/fresh/scenarios/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/fresh/scenarios/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/fresh/scenarios/{layout}/{placement}/h{height}.tsv"
    params:
        n=PROF["scenarios_per_cell"],
        seed=FRESH_SEED,


use rule evaluate as fresh_evaluate with:
    input:
        actor=ancient("results/{preset}/train/{variant}/seed{seed}/actor.pt"),
        scenarios="results/{preset}/fresh/scenarios/{layout}/{placement}/h{height}.csv",
    output:
        update("results/{preset}/fresh/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/fresh/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/fresh/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"


rule fresh:
    """The reference on its stored sets against the fresh sets, per home and cell."""
    input:
        stored=ancient(fresh_files("stored")),
        fresh=fresh_files("fresh"),
    output:
        update(expand(f"{FIGS}/fresh.{{ext}}", ext=["csv", "md"])),
    log:
        f"{RESULTS}/logs/report/fresh.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/fresh.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
        variant=REF,
        seed=FRESH_SEED,
    conda:
        CONDA_ENV
    shell:
        "egosearch report fresh --force --stored {input.stored} --fresh {input.fresh} --variant {params.variant} "
        "--fresh-seed {params.seed} --out-prefix {params.prefix} > {log} 2>&1"
