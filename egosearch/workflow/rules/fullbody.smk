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
