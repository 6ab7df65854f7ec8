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


rule evaluate_start:
    """A trained policy's start (actor_start.pt beside its actor.pt: the clone after imitation, else the
    untrained net) on one Table 1 cell: what its learning starts from, on the stored sets. Runs stored
    before trainings wrote the start have none: the job stops with one line saying so."""
    input:
        actor=ancient("results/{profile}/train/{variant}/seed{seed}/actor.pt"),
        scenarios=ancient("results/{profile}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        "results/{profile}/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv",
    log:
        "results/{profile}/logs/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{profile}/benchmarks/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    params:
        start=lambda wc, input: start_actor(input.actor),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy actor --weights {params.start} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output} > {log} 2>&1"


# eval/random/... and eval/oracle/... are the bounds' (BOUNDS), not variants; so are those of every other
# registered searcher (REFERENCE_SEARCHERS, egosearch.searchers.registry), eval/modular_random/... among them (the
# modular searcher's floor, read by the decisions_floor rule).
ruleorder: bound > evaluate


rule bound:
    """A reference searcher on one Table 1 cell: the random searcher, the classical frontier searcher
    (head moving or held fixed), the privileged oracle (it knows the target) or the modular searcher's
    walk with random decisions (head moving or fixed)."""
    input:
        scenarios=ancient("results/{profile}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        "results/{profile}/eval/{bound}/seed{seed}/{layout}/{placement}/h{height}.csv",
    log:
        "results/{profile}/logs/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{profile}/benchmarks/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    wildcard_constraints:
        bound="|".join(REFERENCE_SEARCHERS),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy {wildcards.bound} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output} > {log} 2>&1"
