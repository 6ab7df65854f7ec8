rule train:
    """SAC+CURL on the abstract searcher (paper 4.2). Trains in partial/ (checkpoint and growing
    CSVs, which Snakemake does not delete when it reruns a killed job), resumes there if killed, and
    publishes the outputs only when the run is complete. The workflow config's `set` reaches it as --set
    arguments; a stored training recorded with another set stops the run before any job (rules/common.smk)."""
    output:
        actor=update("results/{preset}/train/{variant}/seed{seed}/actor.pt"),
        curve=update("results/{preset}/train/{variant}/seed{seed}/curve.csv"),
    log:
        "results/{preset}/logs/train/{variant}/seed{seed}.log",
    benchmark:
        "results/{preset}/benchmarks/train/{variant}/seed{seed}.tsv"
    params:
        learner=lambda wc: config["presets"][wc.preset]["learner"],
        out_dir=lambda wc, output: str(Path(output.actor).parent),
        work_dir=lambda wc, output: str(Path(output.actor).parent / "partial"),
    # 1; at the paper preset on one machine, --cores / trainings_per_gpu (common.smk)
    threads: TRAIN_THREADS
    resources:
        **train_resources(PRESET),
    conda:
        CONDA_ENV
    # SET_ARGS: the workflow config's `set` as --set arguments (rules/common.smk), empty without one, so that the
    # command of a run without a set is the one Snakemake recorded for the stored trainings
    shell:
        "egosearch train --force --variant {wildcards.variant} --preset {params.learner} --seed {wildcards.seed} "
        f"--threads {{threads}} --work-dir {{params.work_dir}} --out-dir {{params.out_dir}}{SET_ARGS} > {{log}} 2>&1"


rule demos:
    """The frontier searcher's transitions in the variant's training homes (demonstrations for imitation and
    RL), as many episodes as the variant's demo_episodes: the head-moving searcher for a body with a head, the
    head-fixed one otherwise. The transitions are
    git-ignored (*.replay.npz); the summary beside them records episodes, success and CPU time."""
    output:
        transitions="results/{preset}/demos/{variant}/seed{seed}.replay.npz",
        summary="results/{preset}/demos/{variant}/seed{seed}.json",
    log:
        "results/{preset}/logs/demos/{variant}/seed{seed}.log",
    benchmark:
        "results/{preset}/benchmarks/demos/{variant}/seed{seed}.tsv"
    params:
        learner=lambda wc: config["presets"][wc.preset]["learner"],
    threads: 1
    conda:
        CONDA_ENV
    shell:
        "egosearch demos --force --variant {wildcards.variant} --preset {params.learner} --seed {wildcards.seed} "
        f"--out {{output.transitions}}{SET_ARGS} > {{log}} 2>&1"
