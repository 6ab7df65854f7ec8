# egosearch: the paper's experiments as one DAG.
#   snakemake --cores 2 all                     # everything at the default `cpu` profile (hours: `egosearch estimate all` says how many here)
#   snakemake --cores 2 table1                  # Table 1 only (trains what it needs)
#   snakemake --cores 2 compare --config variant=my_variant
# Rules call `egosearch` entry points; the experiment list lives in egosearch/workflow/.
import sys

from snakemake.utils import min_version, validate

from egosearch.workflow.check import checked_variants

min_version("9.0")

configfile: "egosearch/workflow/config.yaml"
# A bad key or value, or a typo in a variant's name or file (its learner fields included), is one
# line here and exit 1, before the DAG is built; command-line numbers are read as numbers first.
CHECKED_VARIANTS = checked_variants(config)
validate(config, "egosearch/workflow/config.schema.json")

include: "egosearch/workflow/rules/common.smk"
include: "egosearch/workflow/rules/scenarios.smk"
include: "egosearch/workflow/rules/train.smk"
include: "egosearch/workflow/rules/evaluate.smk"
include: "egosearch/workflow/rules/fullbody.smk"
include: "egosearch/workflow/rules/report.smk"
include: "egosearch/workflow/rules/budget.smk"
include: "egosearch/workflow/rules/generalise.smk"
include: "egosearch/workflow/rules/traces.smk"
include: "egosearch/workflow/rules/fresh.smk"


rule all:
    input:
        # Every variant on every Table 1 cell: `compare --config variant=head_off` then needs no run.
        [eval_files(v) for v in VARIANTS],
        rules.table1.output,
        rules.table2.output,
        rules.table2_paper.output,
        rules.fig6.output,
        rules.fig7.output,
        rules.fig7_oracle.output,
        rules.pictures.output,
        rules.video.output,
        pathlength_files(),
        provenance_file(),


onstart:
    # The cost of `all` before its first job: the whole DAG from scratch, simulated on these cores
    # (egosearch estimate all; on this machine once it has been calibrated).
    if "all" in workflow.dag_settings.targets and PROFILE != "smoke":
        from egosearch.cli.estimate import print_before_a_run

        print_before_a_run(PROFILE, workflow.cores)
    for target in ("compare", "screen"):
        if target in workflow.dag_settings.targets and config.get("variant"):
            from egosearch.cli.estimate import print_variant_cost

            seeds = SEEDS if target == "compare" else [config["screen_seed"]]
            print_variant_cost(PROFILE, target, config["variant"], seeds, REF, workflow.cores)


# A run killed by SIGKILL leaves its lock: rerunning the same command removes it when no other
# snakemake runs here, then --rerun-incomplete (profiles/default) reruns the killed jobs.
if workflow.is_main_process:
    from egosearch.core.stale_lock import clear_stale_locks

    if clear_stale_locks():
        print("Removed the lock of a snakemake run that was killed (no snakemake process runs here).")

    from egosearch.workflow.check import reports_missing_inputs

    # input functions (compare's) are resolved only when the DAG is built: their paths are unknown here
    for line in reports_missing_inputs(
            (r.name, [str(f) for f in r.output], [str(f) for f in r.input if isinstance(f, str)])
            for r in workflow.rules if not r.has_wildcards()):
        print(line, file=sys.stderr)
