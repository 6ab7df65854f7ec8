rule evaluate:
    """One trained policy on one Table 1 cell: a row per episode."""
    input:
        actor=ancient("results/{preset}/train/{variant}/seed{seed}/actor.pt"),
        scenarios=ancient("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        update("results/{preset}/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/eval/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"
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
        actor=ancient("results/{preset}/train/{variant}/seed{seed}/actor.pt"),
        scenarios=ancient("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        update("results/{preset}/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/eval_start/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"
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
# registered searcher (REFERENCE_SEARCHERS, egosearch.searchers.searcher_registry), eval/modular_random/... among them (the
# modular searcher's floor, read by the decisions_floor rule).
ruleorder: bound > evaluate


rule curve_level:
    """A searcher without training (the random and classical searchers) on the held-out scenarios a
    variant's training curve is evaluated on, each episode seeded as the curve's: its level in Figure 6,
    read on the curve's own episodes."""
    output:
        update("results/{preset}/eval_curve/{bound}/{variant}.csv"),
    log:
        "results/{preset}/logs/eval_curve/{bound}/{variant}.log",
    benchmark:
        "results/{preset}/benchmarks/eval_curve/{bound}/{variant}.tsv"
    wildcard_constraints:
        bound="|".join(REFERENCE_SEARCHERS),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=15,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy {wildcards.bound} --curve-of {wildcards.variant} "
        "--preset {wildcards.preset} --out {output} > {log} 2>&1"


rule tune_teacher:
    """The tuned frontier searcher's tuning run again (not part of `all`): every candidate on a training-side
    fit split, the one chosen and the untuned searcher on a held-out split, never a stored set; the record
    says whether the shipped parameters still win and what they do held out. About 13,000 episodes."""
    output:
        update("results/{preset}/teacher_tuning/record.json"),
    log:
        "results/{preset}/logs/teacher_tuning.log",
    benchmark:
        "results/{preset}/benchmarks/teacher_tuning.tsv"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=300,
    params:
        out=lambda wc, output: os.path.dirname(output[0]),
    conda:
        CONDA_ENV
    shell:
        "egosearch tune --force --out {params.out} > {log} 2>&1"


rule bound:
    """A reference searcher on one Table 1 cell: the random searcher, the classical frontier searcher
    (head moving or held fixed), the privileged oracle (it knows the target) or the modular searcher's
    walk with random decisions (head moving or fixed)."""
    input:
        scenarios=ancient("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        update("results/{preset}/eval/{bound}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/bound/{bound}/seed{seed}/{layout}/{placement}/h{height}.tsv"
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
