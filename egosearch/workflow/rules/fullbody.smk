rule fullbody:
    """Algorithm 1 (or a baseline of paper 6.4) with a full-body character."""
    input:
        actor=ancient(f"{RESULTS}/train/{REF}/seed{{seed}}/actor.pt"),
        scenarios=ancient(fullbody_scenarios),
    output:
        update("results/{preset}/fullbody/{setting}/seed{seed}.csv"),
    log:
        "results/{preset}/logs/fullbody/{setting}/seed{seed}.log",
    benchmark:
        "results/{preset}/benchmarks/fullbody/{setting}/seed{seed}.tsv"
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
        "egosearch fullbody --force --setting {wildcards.setting} --weights {input.actor} "
        "--scenarios {input.scenarios} --limit {params.limit} --T {params.T} --seed {wildcards.seed} --out {output} "
        "> {log} 2>&1"


rule fullbody_oracle:
    """The same settings with the privileged oracle as planner (not in the paper): separates what
    the replanner and the motion generator do from how good the learned search policy is."""
    input:
        scenarios=ancient(fullbody_scenarios),
    output:
        update("results/{preset}/fullbody_oracle/{setting}/seed{seed}.csv"),
    log:
        "results/{preset}/logs/fullbody_oracle/{setting}/seed{seed}.log",
    benchmark:
        "results/{preset}/benchmarks/fullbody_oracle/{setting}/seed{seed}.tsv"
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
        "egosearch fullbody --force --policy oracle --setting {wildcards.setting} --scenarios {input.scenarios} "
        "--limit {params.limit} --T {params.T} --seed {wildcards.seed} --out {output} > {log} 2>&1"


rule video:
    """One learned search, filmed: the first scenario (by scenario_id) that the reference policy
    found in Figure 7's `ours` M=5 humanoid runs in at least 20 steps (3 s: a search, not a target
    in view from the start) with no penetrating pose, replayed as a GIF (first-person depth + mask
    beside a third-person view with the target ringed) and a still of the moment it is found."""
    input:
        actor=ancient(f"{RESULTS}/train/{REF}/seed{FULLBODY['seeds'][0]}/actor.pt"),
        scenarios=ancient(scenario_file("everywhere", "1.65")),
        fullbody=ancient(f"{RESULTS}/fullbody/ours-M5-humanoid_phase/seed{FULLBODY['seeds'][0]}.csv"),
    output:
        gif=update(f"{FIGS}/search.gif"),
        still=update(f"{FIGS}/search_still.png"),
    log:
        f"{RESULTS}/logs/report/video.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/video.tsv"
    params:
        seed=FULLBODY["seeds"][0],
    threads: 1
    resources:
        mem_mb=2000,
        runtime=20,
    conda:
        CONDA_ENV
    shell:
        "egosearch video --force --character humanoid_phase --scenarios {input.scenarios} "
        "--first-success {input.fullbody} --min-steps 20 "
        "--weights {input.actor} --M 5 --seed {params.seed} --out {output.gif} --still {output.still} > {log} 2>&1"
