# Tables and figures: CSV in, files out; seconds, no torch, no simulator.

rule table1:
    """Success rate per camera height x placement scheme, pooled over seeds (paper Table 1), with
    the random searcher and the privileged oracle on the same scenarios, and in its notes what the
    policy's learning adds (its comparison against its own start, rule learning_adds)."""
    input:
        policy=ancient(eval_files(REF)),
        bounds=ancient(bound_files()),
        learning_adds=ancient(f"{RESULTS}/compare/{REF}_vs_its_start.csv"),
    output:
        update(expand(f"{FIGS}/table1.{{ext}}", ext=["md", "csv", "tex"])),
    log:
        f"{RESULTS}/logs/report/table1.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/table1.tsv"
    params:
        variant=REF,
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report table1 --force {input.policy} --variant {params.variant} --bounds {input.bounds} "
        "--learning-adds {input.learning_adds} --out-prefix {params.prefix} > {log} 2>&1"


rule table2:
    """The learner's hyperparameters of this preset, generated from the config (paper Table 2)."""
    output:
        update(expand(f"{FIGS}/table2.{{ext}}", ext=["md", "tex"])),
    log:
        f"{RESULTS}/logs/report/table2.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/table2.tsv"
    params:
        learner=PROF["learner"],
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report table2 --force --preset {params.learner} --out-prefix {params.prefix} > {log} 2>&1"


rule table2_paper:
    """Table 2 of the paper, regenerated from the `paper` preset of the config."""
    output:
        update(expand("paper_figs/table2.{ext}", ext=["md", "tex"])),
    log:
        f"{RESULTS}/logs/report/table2_paper.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/table2_paper.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report table2 --force --preset paper --out-prefix {params.prefix} > {log} 2>&1"


rule fig6:
    """Success rate vs environment steps, head on vs head off (paper Figure 6); the random and
    classical searchers and each policy's start a horizontal line."""
    input:
        curves=ancient([curve_files(v) for v in VARIANTS]),
        levels=ancient(fig6_level_files()),
    output:
        update(expand(f"{FIGS}/fig6.{{ext}}", ext=["png", "pdf", "csv"])),
    log:
        f"{RESULTS}/logs/report/fig6.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/fig6.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report fig6 --force {input.curves} --levels {input.levels} --out-prefix {params.prefix} > {log} 2>&1"


rule fig7:
    """SPL per method and attempts vs M of the full-body replanner (paper Figure 7)."""
    input:
        ancient(fullbody_files()),
    output:
        update(expand(f"{FIGS}/fig7.{{ext}}", ext=["png", "pdf", "csv"])),
    log:
        f"{RESULTS}/logs/report/fig7.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/fig7.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report fig7 --force {input} --out-prefix {params.prefix} > {log} 2>&1"


rule fig7_oracle:
    """Figure 7 again with the privileged oracle as planner (not in the paper)."""
    input:
        ancient(fullbody_files("oracle")),
    output:
        update(expand(f"{FIGS}/fig7_oracle.{{ext}}", ext=["png", "pdf", "csv"])),
    log:
        f"{RESULTS}/logs/report/fig7_oracle.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/fig7_oracle.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report fig7 --force {input} --out-prefix {params.prefix} --planner oracle > {log} 2>&1"


rule pathlength:
    """Success by shortest path length and by detour for one variant, every Table 1 cell pooled and per
    camera height, beside the reference searchers on the same scenarios."""
    input:
        policy=ancient(lambda wc: eval_files(wc.variant)),
        scenarios=ancient(table1_scenario_files()),
        bounds=ancient(bound_files()),
    output:
        csv=update(f"{RESULTS}/pathlength/{{variant}}.csv"),
        md=update(f"{FIGS}/pathlength_{{variant}}.md"),
        png=update(f"{FIGS}/pathlength_{{variant}}.png"),
        pdf=update(f"{FIGS}/pathlength_{{variant}}.pdf"),
    log:
        f"{RESULTS}/logs/report/pathlength_{{variant}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/pathlength_{{variant}}.tsv"
    params:
        prefix=lambda wc, output: output.md.rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report pathlength --force {input.policy} --scenarios {input.scenarios} --bounds {input.bounds} "
        "--out-prefix {params.prefix} --out-csv {output.csv} > {log} 2>&1"


rule pictures:
    """The world's pictures: top-down map, placements, first/third-person views."""
    output:
        update(expand("paper_figs/world/{layout}_{kind}.png", layout=[LAYOUT], kind=["topdown", "placements", "views"])),
    log:
        f"{RESULTS}/logs/report/pictures.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/pictures.tsv"
    params:
        layout=LAYOUT,
        out_dir=lambda wc, output: str(Path(output[0]).parent),
    conda:
        CONDA_ENV
    shell:
        "egosearch pictures --force --layout {params.layout} --out-dir {params.out_dir} > {log} 2>&1"


rule compare:
    """Does a new variant beat the stored reference? Per cell: difference, 95% CI, p-value; and the
    same per shortest-path bin, every cell pooled."""
    input:
        reference=ancient(eval_files(REF)),
        candidate=compare_candidate,
    output:
        cells=update(f"{RESULTS}/compare/{config.get('variant') or 'none'}_vs_{REF}.csv"),
        by_length=update(f"{RESULTS}/compare/{config.get('variant') or 'none'}_vs_{REF}_by_length.csv"),
        stuck=update(f"{RESULTS}/compare/{config.get('variant') or 'none'}_vs_{REF}_stuck.csv"),
    log:
        f"{RESULTS}/logs/report/compare_{config.get('variant') or 'none'}.log",
    conda:
        CONDA_ENV
    shell:
        # writes {output.by_length} and {output.stuck} beside {output.cells} (by_length_path, stuck_path)
        "egosearch report compare --force --reference {input.reference} --candidate {input.candidate} "
        "--out {output.cells} 2>&1 | tee {log}"


rule screen:
    """A lever's first test: the variant trained on screen_seeds seeds against the mean of the reference's
    spread seeds on the same stored sets, per cell and per shortest-path bin. Whatever its seed count it runs
    the seed-spread test (a t-test on the seeds' cell means, the reference's spread seeds and the candidate's
    showing how far one seed's mean strays), so a row is "lower" or "higher" only beyond that spread; the
    aggregate over seeds and cells (interquartile mean, probability of improvement) is written beside it."""
    input:
        reference=ancient(spread_files(REF)),
        candidate=screen_candidate,
    output:
        cells=update(f"{RESULTS}/compare/{screen_name()}.csv"),
        by_length=update(f"{RESULTS}/compare/{screen_name()}_by_length.csv"),
        aggregate=update(f"{RESULTS}/compare/{screen_name()}_aggregate.csv"),
        stuck=update(f"{RESULTS}/compare/{screen_name()}_stuck.csv"),
    log:
        f"{RESULTS}/logs/report/{screen_name()}.log",
    conda:
        CONDA_ENV
    shell:
        "egosearch report compare --force --reference {input.reference} --candidate {input.candidate} "
        "--spread {input.reference} --out {output.cells} --aggregate {output.aggregate} 2>&1 | tee {log}"


rule null_screen:
    """The reference screened against itself (outside `all`: it needs the spread seeds): every spread seed
    as a candidate against each other seed and against the rest, before and after the seed spread counts, the
    spread held out (from the seeds on neither side: a consistency check); the simulated false-positive rate of
    the screen's test in every setting (its calibration), the seed spread per cell and the difference a screen
    of 1, 2, 3 and 6 seeds detects (docs/statistics.md)."""
    input:
        ancient(spread_files(REF)),
    output:
        screens=update(f"{RESULTS}/compare/null_screen_{REF}.csv"),
        summary=update(f"{RESULTS}/compare/seed_spread_{REF}.json"),
    log:
        f"{RESULTS}/logs/report/null_screen_{REF}.log",
    conda:
        CONDA_ENV
    shell:
        "egosearch report null-screen --force {input} --out {output.screens} --summary {output.summary} "
        "2>&1 | tee {log}"


rule screens_reread:
    """Every stored screen read again with the seed-spread test every screen runs now, beside its stored verdict
    (it reads the stored evaluation files the screens read; docs/ablations/reread.md)."""
    input:
        ancient(stored_screens()),
    output:
        update(f"{RESULTS}/compare/screens_reread.csv"),
    log:
        f"{RESULTS}/logs/report/screens_reread.log",
    params:
        preset=PRESET,
    conda:
        CONDA_ENV
    shell:
        "egosearch report reread-screens --force --preset {params.preset} --out {output} 2>&1 | tee {log}"


rule seed_spread:
    """`snakemake --cores 2 seed_spread`: the null screen, its summary, and the stored screens read again."""
    input:
        rules.null_screen.output,
        rules.screens_reread.output,


rule provenance:
    """Commit, preset, machine, date, the wall time of every rule and the sha256 of every stored
    result file, next to the results. Every result of `all` is an input, so that the record is
    checked whenever one of them is rewritten; update() keeps the old record in place (Snakemake
    would delete it first), so that the command leaves it byte for byte as it was when no stored
    file changed (`egosearch report regenerate` rewrites identical files)."""
    input:
        ancient([eval_files(v) for v in VARIANTS]),
        ancient(bound_files()),
        rules.table1.output,
        rules.table2.output,
        rules.fig6.output,
        rules.fig7.output,
        rules.fig7_oracle.output,
        rules.video.output,
        pathlength_files(),
    output:
        update(provenance_file()),
    log:
        f"{RESULTS}/logs/report/provenance.log",
    params:
        preset=PRESET,
        results=lambda wc, output: str(Path(output[0]).parent),
    conda:
        CONDA_ENV
    shell:
        "egosearch report provenance --force --preset {params.preset} --results {params.results} --out {output} "
        "> {log} 2>&1"


rule learning_adds:
    """What learning adds: the preset's pair (head on, head off) against its own start (each seed's
    policy at step 0: the clone after imitation, else the untrained net) on the same stored sets, per
    cell and per shortest-path bin (part of `all`; Table 1's notes say the reference's)."""
    input:
        [f"{RESULTS}/compare/{variant}_vs_its_start.csv" for variant in VARIANTS],


rule learning_adds_compare:
    """One variant (all its seeds) against its start (the same seeds at step 0)."""
    input:
        reference=ancient(lambda wc: start_eval_files(wc.variant)),
        candidate=ancient(lambda wc: eval_files(wc.variant)),
    output:
        cells=update(f"{RESULTS}/compare/{{variant}}_vs_its_start.csv"),
        by_length=update(f"{RESULTS}/compare/{{variant}}_vs_its_start_by_length.csv"),
    log:
        f"{RESULTS}/logs/report/learning_adds_{{variant}}.log",
    conda:
        CONDA_ENV
    shell:
        "egosearch report compare --force --reference {input.reference} --candidate {input.candidate} "
        "--out {output.cells} > {log} 2>&1"


rule decisions_floor:
    """What a modular searcher's learned decisions add: each modular pair of the claims pairs (at the cpu
    preset the stored head_on_modular and head_off_modular) against the same walk with random decisions,
    per cell and per shortest-path bin. Nothing to do where no claims pair is a modular searcher."""
    input:
        [f"{RESULTS}/compare/{variant}_vs_{floor}.csv" for variant, floor in DECISIONS_FLOORS],


rule teacher_compare:
    """A variant (every seed) against a classical searcher (its one seed) on the same stored sets: per cell, per
    shortest-path bin and the stuck share. `versus_teacher` asks for Figure 6's pair against the classical
    searchers of its head, the teacher each learned from (its config's demo_teacher) among them."""
    input:
        reference=ancient(lambda wc: bound_files([wc.teacher])),
        candidate=ancient(lambda wc: eval_files(wc.variant)),
    output:
        cells=update(f"{RESULTS}/compare/{{variant}}_vs_{{teacher}}.csv"),
        by_length=update(f"{RESULTS}/compare/{{variant}}_vs_{{teacher}}_by_length.csv"),
        stuck=update(f"{RESULTS}/compare/{{variant}}_vs_{{teacher}}_stuck.csv"),
    log:
        f"{RESULTS}/logs/report/teacher_compare_{{variant}}_vs_{{teacher}}.log",
    wildcard_constraints:
        teacher="|".join(CLASSICAL_SEARCHERS),
    conda:
        CONDA_ENV
    shell:
        "egosearch report compare --force --reference {input.reference} --candidate {input.candidate} "
        "--out {output.cells} > {log} 2>&1"


rule versus_teacher:
    """`snakemake --cores 2 versus_teacher`: Figure 6's pair (the first of claims_pairs) against every classical
    searcher of its head (searchers registered as classical): the untuned frontier searcher, Table 1's classical
    row, and the tuned one, the teacher the cpu preset's pair learned from (VERSUS_TEACHER, common.smk)."""
    input:
        [f"{RESULTS}/compare/{variant}_vs_{searcher}.csv" for variant, searcher in VERSUS_TEACHER],


rule teacher_tuning:
    """`snakemake --cores 1 teacher_tuning`: the tuned teacher's tuning run again (egosearch.runs.teacher_tuning)."""
    input:
        f"{RESULTS}/teacher_tuning/record.json",


rule decisions_floor_compare:
    """One variant of the pair against its floor (all its seeds against the floor's one)."""
    input:
        reference=ancient(lambda wc: bound_files([wc.floor])),
        candidate=ancient(lambda wc: eval_files(wc.variant)),
    output:
        cells=update(f"{RESULTS}/compare/{{variant}}_vs_{{floor}}.csv"),
        by_length=update(f"{RESULTS}/compare/{{variant}}_vs_{{floor}}_by_length.csv"),
    log:
        f"{RESULTS}/logs/report/decisions_floor_{{variant}}_vs_{{floor}}.log",
    wildcard_constraints:
        floor="|".join(MODULAR_FLOORS.values()),
    conda:
        CONDA_ENV
    shell:
        "egosearch report compare --force --reference {input.reference} --candidate {input.candidate} "
        "--out {output.cells} > {log} 2>&1"


rule memory_window:
    """How much memory the search asks for (outside `all`): the tuned frontier searcher held to its last K steps
    (K = 5, 10, 20, 50, and the whole episode; head moving and fixed) on every Table 1 set, beside the students
    that see 5 frames (the first of claims_pairs). About 19,000 episodes for the windows."""
    input:
        searchers=ancient(bound_files(bounds=[name for head in (True, False)
                                              for name in searchers.memory_window_searchers(head).values()])),
        students=ancient(eval_files(claims_pairs(config)[0][0]) + eval_files(claims_pairs(config)[0][1])),
    output:
        update(expand(f"{FIGS}/memory_window.{{ext}}", ext=["csv", "md", "png", "pdf"])),
    log:
        f"{RESULTS}/logs/report/memory_window.log",
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
    conda:
        CONDA_ENV
    shell:
        "egosearch report memory-window --force --searchers {input.searchers} --students {input.students} "
        "--out-prefix {params.prefix} > {log} 2>&1"
