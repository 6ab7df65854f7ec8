# Per-step traces and what they say about how the policies search (`snakemake --cores 2 behaviour
# searches`, outside `all`): each trained policy reruns its Table 1 evaluation of the trace cells
# with `--traces`. The runs are deterministic on one machine, so the episodes CSV beside each trace
# repeats the stored evaluation row for row where both ran on the same CPU (another CPU's floating point
# can change some episodes: docs/results.md, "The same actors on another machine"). Names: common.smk.

# Every Table 1 cell: the behaviour statistics pool them, with the cell and scenario as the unit.
TRACE_CELLS = [(placement, height) for placement in PLACEMENTS for height in HEIGHTS]
# The pictures: the humanoid's camera height of Section 6.3, with targets inside cabinets allowed.
SEARCH_CELLS = [("everywhere", HEIGHTS[-1])]
# The pairs the claims are read on (config claims_pairs): variants with every seed, the classical
# searchers with BOUND_SEEDS. The first pair is Figure 6's (the head moving, and held fixed): the
# pictured searches are its.
CLAIMS_PAIRS = [tuple(pair) for pair in claims_pairs(config)]
TRACE_VARIANTS = list(CLAIMS_PAIRS[0])
TRACE_FILES = [f"{RESULTS}/traces/{v}/seed{s}/{home}/{placement}/h{height}.npz"
               for v in dict.fromkeys(v for pair in CLAIMS_PAIRS for v in pair)
               for s in (BOUND_SEEDS if v in CLASSICAL_SEARCHERS else SEEDS)
               for home in HOMES for placement, height in TRACE_CELLS]
SEARCH_TRACE_FILES = [f"{RESULTS}/traces/{v}/seed{s}/{home}/{placement}/h{height}.npz"
                      for v in TRACE_VARIANTS for s in SEEDS for home in HOMES for placement, height in SEARCH_CELLS]


rule trace:
    """One trained policy on one Table 1 cell, every step of every episode recorded."""
    input:
        actor=ancient("results/{preset}/train/{variant}/seed{seed}/actor.pt"),
        scenarios=ancient("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        trace=update("results/{preset}/traces/{variant}/seed{seed}/{layout}/{placement}/h{height}.npz"),
        episodes=update("results/{preset}/traces/{variant}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/traces/{variant}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/traces/{variant}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy actor --weights {input.actor} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output.episodes} --traces {output.trace} > {log} 2>&1"


# traces/frontier/... and traces/frontier_head_off/... are the classical searchers', not variants.
ruleorder: trace_bound > trace


rule trace_bound:
    """A classical searcher on one Table 1 cell, every step of every episode recorded (the claims read
    on the classical pair)."""
    input:
        scenarios=ancient("results/{preset}/scenarios/{layout}/{placement}/h{height}.csv"),
    output:
        trace=update("results/{preset}/traces/{bound}/seed{seed}/{layout}/{placement}/h{height}.npz"),
        episodes=update("results/{preset}/traces/{bound}/seed{seed}/{layout}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/traces/{bound}/seed{seed}/{layout}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/traces/{bound}/seed{seed}/{layout}/{placement}/h{height}.tsv"
    wildcard_constraints:
        bound="|".join(CLASSICAL_SEARCHERS),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=30,
    conda:
        CONDA_ENV
    shell:
        "egosearch evaluate --force --policy {wildcards.bound} --scenarios {input.scenarios} "
        "--seed {wildcards.seed} --out {output.episodes} --traces {output.trace} > {log} 2>&1"


rule behaviour:
    """Behaviour statistics per searcher and head on minus head off per pair, and the paper's behaviour
    sentences (Section 6.3, Figure 6) with their verdicts, read on each pair side by side."""
    input:
        ancient(TRACE_FILES),
    output:
        update(expand(f"{FIGS}/behaviour{{suffix}}", suffix=["_episodes.csv", ".csv", ".md", "_claims.csv", "_claims.md"])),
    log:
        f"{RESULTS}/logs/report/behaviour.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/behaviour.tsv"
    params:
        prefix=lambda wc, output: output[1].rsplit(".", 1)[0],
        pairs=" ".join(f"{on}:{off}" for on, off in CLAIMS_PAIRS),
    conda:
        CONDA_ENV
    shell:
        "egosearch report behaviour --force {input} --pairs {params.pairs} --out-prefix {params.prefix} > {log} 2>&1"


rule failures:
    """How each traced searcher fails, per Table 1 cell: stuck (failed with 50 or more collisions), never saw
    the target, saw it and lost it, saw it and was stuck, timed out near it (egosearch.report.failures); and
    what Figure 6's pair is stuck against (egosearch.report.stuck_contacts)."""
    input:
        ancient(TRACE_FILES),
    output:
        csv=update(f"{FIGS}/failures.csv"),
        stuck=update(f"{FIGS}/failures_stuck.csv"),
        md=update(f"{FIGS}/failures.md"),
    log:
        f"{RESULTS}/logs/report/failures.log",
    params:
        prefix=lambda wc, output: output.csv.rsplit(".", 1)[0],
        # what Figure 6's pair is stuck against (the stuck episodes' furniture, seen or not, their actions)
        read=" ".join(TRACE_VARIANTS),
    conda:
        CONDA_ENV
    shell:
        "egosearch report failures --force {input} --out-prefix {params.prefix} --stuck-read {params.read} > {log} 2>&1"


rule searches:
    """Chosen searches of seed 0 on the floor plan, and where the camera looks, per trace cell."""
    input:
        ancient(SEARCH_TRACE_FILES),
    output:
        update([f"{FIGS}/searches/{v}_{home}_{placement}_h{height}.png"
                for v in TRACE_VARIANTS for home in HOMES for placement, height in SEARCH_CELLS]),
        update([f"{FIGS}/searches/gaze_{home}_{placement}_h{height}.png" for home in HOMES for placement, height in SEARCH_CELLS]),
    log:
        f"{RESULTS}/logs/report/searches.log",
    params:
        out_dir=lambda wc, output: str(Path(output[0]).parent),
        seed=SEEDS[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report searches --force {input} --seed {params.seed} --out-dir {params.out_dir} > {log} 2>&1"
