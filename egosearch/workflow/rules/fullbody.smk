rule fullbody:
    """Algorithm 1 (or a baseline of paper 6.4) with a full-body character."""
    input:
        actor=ancient(f"{RESULTS}/train/{REF}/seed{{seed}}/actor.pt"),
        scenarios=ancient(fullbody_scenarios),
    output:
        "results/{profile}/fullbody/{setting}/seed{seed}.csv",
    log:
        "results/{profile}/logs/fullbody/{setting}/seed{seed}.log",
    benchmark:
        "results/{profile}/benchmarks/fullbody/{setting}/seed{seed}.tsv"
    params:
        limit=FULLBODY["scenarios"],
        T=FULLBODY["T"],
    threads: 1
    resources:
        mem_mb=2000,
        runtime=60,
    conda:
        CONDA_ENV
    shell:
        "egosearch fullbody --setting {wildcards.setting} --weights {input.actor} --scenarios {input.scenarios} "
        "--limit {params.limit} --T {params.T} --seed {wildcards.seed} --out {output} > {log} 2>&1"


rule fullbody_oracle:
    """The same settings with the privileged oracle as planner (not in the paper): separates what
    the replanner and the motion generator do from how good the learned search policy is."""
    input:
        scenarios=ancient(fullbody_scenarios),
    output:
        "results/{profile}/fullbody_oracle/{setting}/seed{seed}.csv",
    log:
        "results/{profile}/logs/fullbody_oracle/{setting}/seed{seed}.log",
    benchmark:
        "results/{profile}/benchmarks/fullbody_oracle/{setting}/seed{seed}.tsv"
    params:
        limit=FULLBODY["scenarios"],
        T=FULLBODY["T"],
    threads: 1
    resources:
        mem_mb=2000,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch fullbody --policy oracle --setting {wildcards.setting} --scenarios {input.scenarios} "
        "--limit {params.limit} --T {params.T} --seed {wildcards.seed} --out {output} > {log} 2>&1"
