rule evaluate:
    """One trained policy on one Table 1 cell: a row per episode."""
    input:
        actor=ancient("results/{profile}/train/{variant}/seed{seed}/actor.pt"),
        scenarios=ancient("results/{profile}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        "results/{profile}/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv",
    log:
        "results/{profile}/logs/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{profile}/benchmarks/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy actor --weights {input.actor} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output} > {log} 2>&1"


# eval/random/... and eval/oracle/... are the bounds' (BOUNDS in egosearch.report.tables), not variants.
ruleorder: bound > evaluate


rule bound:
    """A reference searcher on one Table 1 cell: the random searcher, the classical frontier searcher
    (head moving or held fixed) or the privileged oracle (it knows the target)."""
    input:
        scenarios=ancient("results/{profile}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        "results/{profile}/eval/{bound}/seed{seed}/{layout}/{placement}/h{height}.csv",
    log:
        "results/{profile}/logs/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{profile}/benchmarks/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    wildcard_constraints:
        bound="random|oracle|frontier|frontier_head_off",
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy {wildcards.bound} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output} > {log} 2>&1"
