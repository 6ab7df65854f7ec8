rule scenarios:
    """The fixed scenario set of one Table 1 cell (paper 6.1)."""
    output:
        update("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/scenarios/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/scenarios/{layout}/{placement}/h{height}.tsv"
    wildcard_constraints:
        layout="kitchen_living|bedroom_bath|studio|home[0-9]+",
    params:
        n=PROF["scenarios_per_cell"],
        seed=config["scenario_seed"],
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    conda:
        CONDA_ENV
    shell:
        "egosearch scenarios --force --layout {wildcards.layout} --placement {wildcards.placement} "
        "--height {wildcards.height} --n {params.n} --seed {params.seed} --out {output} > {log} 2>&1"
