# The generalisation benchmark (`snakemake --cores 2 generalise`, outside `all`): trained-on x
# evaluated-on. Each group of homes is one scenario file per placement (the evaluate and bound rules
# serve it unchanged: an evaluation rebuilds its env whenever the home changes). Names: common.smk.
rule group_scenarios:
    """One scenario set over a group of generated homes: `scenarios_per_home` in each."""
    output:
        update("results/{preset}/scenarios/{group}/{placement}/h{height}.csv"),
    log:
        "results/{preset}/logs/scenarios/{group}/{placement}/h{height}.log",
    benchmark:
        "results/{preset}/benchmarks/scenarios/{group}/{placement}/h{height}.tsv"
    wildcard_constraints:
        group="|".join(GEN_GROUPS),
    params:
        homes=lambda wc: "{}:{}".format(*GEN_GROUPS[wc.group]),
        n=PROF["scenarios_per_home"],
        seed=config["scenario_seed"],
    threads: 1
    resources:
        mem_mb=1500,
        runtime=20,
    conda:
        CONDA_ENV
    shell:
        "egosearch scenarios --force --homes {params.homes} --placement {wildcards.placement} "
        "--height {wildcards.height} --n {params.n} --seed {params.seed} --out {output} > {log} 2>&1"


ruleorder: group_scenarios > scenarios


rule generalise:
    """Success, SPL and the normalised score (policy - random) / (oracle - random), per variant and
    group of homes, with two-level intervals; the generated-homes variant's gap to its own split."""
    input:
        policies=ancient([generalise_files(v, SEEDS) for v in GEN_VARIANTS]),
        bounds=ancient([generalise_files(b, BOUND_SEEDS) for b in ("random", "oracle")]),
    output:
        update(expand(f"{FIGS}/generalise.{{ext}}", ext=["csv", "md", "png"])),
    log:
        f"{RESULTS}/logs/report/generalise.log",
    benchmark:
        f"{RESULTS}/benchmarks/report/generalise.tsv"
    params:
        prefix=lambda wc, output: output[0].rsplit(".", 1)[0],
        generated=GEN["generated_variant"],
        reference=GEN.get("reference", REF),
        trained_on=" ".join(f"{name}={v.train_env['layout']}" if v.train_env["layout"] != "generated" else
                            "{}=home{}-home{}".format(name, v.train_env["home_seeds"][0], v.train_env["home_seeds"][1] - 1)
                            for name, v in GEN_VARIANTS.items()),
    conda:
        CONDA_ENV
    shell:
        "egosearch report generalise --force {input.policies} --bounds {input.bounds} --generated {params.generated} "
        "--reference {params.reference} --trained-on {params.trained_on} --out-prefix {params.prefix} > {log} 2>&1"
