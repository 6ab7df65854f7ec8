# egosearch: the paper's experiments as one DAG.
#   snakemake all                               # everything at the default `cpu` preset (hours: `egosearch estimate all` says how many here)
#   snakemake table1                            # Table 1 only (trains what it needs)
#   snakemake compare --config variant=my_variant
#   snakemake -n results/cpu/train/my_variant/seed0/actor.pt --config set="batch_size=64"   # learner fields, as `egosearch train --set`
# On 2 cores of this machine (profiles/default/config.yaml); `--cores N` chooses others.
# Rules call `egosearch` entry points; the experiment list lives in egosearch/workflow/.
import os
import sys

from snakemake.settings.types import Quietness
from snakemake.utils import min_version, validate

from egosearch.workflow.check import checked_variants, let_jobs_run_long, renamed_preset_key

min_version("9.0")

configfile: "egosearch/workflow/config.yaml"
# `--config profile=NAME`: the old name of `preset`, read with a note until egosearch 0.2
renamed_preset_key(config, note=workflow.is_main_process)
# A bad key or value, or a typo in a variant's name or file (its learner fields included), is one
# line here and exit 1, before the DAG is built; command-line numbers are read as numbers first.
CHECKED_VARIANTS = checked_variants(config, command_line=workflow.config_settings.overwrite_config)
validate(config, "egosearch/workflow/config.schema.json")
# with allow_long, the jobs' `egosearch train` and `demos` allow what the checks above allowed
let_jobs_run_long(config)

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
        rules.learning_adds.input,
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
    # before a real run's first job: its stored inputs as recorded, no other run making its files, then the cost
    # of its plan (rules/common.smk)
    refuse_unwritable_outputs()
    refuse_damaged_inputs()
    claim_the_plans_outputs()
    print_the_plans_cost()


# Once the DAG is built, a dry run's as a real run's: every training takes the config's `set` and none stored was
# trained with another one (rules/common.smk); wrapped first, so that a refused plan prints no cost line.
if workflow.is_main_process:
    check_the_trainings_set_once_built()


# A dry run is where a user plans (`snakemake -n screen --config variant=NAME`): it prints the same cost
# line once its DAG is built, just above Snakemake's job stats (rules/common.smk). The DAG's own quiet child
# (egosearch.workflow.dag, which `estimate all` runs) prints nothing.
if (workflow.is_main_process and workflow.output_settings.dryrun
        and Quietness.ALL not in (workflow.output_settings.quiet or ())):
    print_the_plans_cost_once_built()


# A dry run under --executor slurm (`snakemake -n --workflow-profile profiles/slurm all`) ends with what each of
# its jobs asks sbatch for, per rule, as the slurm plugin renders it (egosearch.workflow.cluster.sbatch_plan):
# printed at exit, once Snakemake has built the DAG and listed its jobs (a dry run calls no onstart).
if (workflow.is_main_process and workflow.output_settings.dryrun and EXECUTOR == "slurm"
        and Quietness.ALL not in (workflow.output_settings.quiet or ())):
    from egosearch.workflow.cluster import print_sbatch_plan_at_exit

    print_sbatch_plan_at_exit(workflow)


# A job that Slurm killed at its time or memory limit: one line each when the run stops, saying which
# limit, what the same command does next (a training resumes from its checkpoint in partial/) and the
# --set-resources that gives it more (egosearch.workflow.cluster.killed_job_lines); then, whatever the executor,
# each failed job's own reason (egosearch.workflow.failures).
onerror:
    if EXECUTOR == "slurm":
        from egosearch.workflow.cluster import killed_job_lines

        for line in killed_job_lines(log, train_checkpoint):
            print(line, file=sys.stderr)
    # each failed job's own one-line reason, last on the console (its log holds the rest); a job that would
    # replace stored files has restored them (its outputs are update(): rules/*.smk)
    from egosearch.workflow.failures import failed_job_lines

    for line in failed_job_lines(log):
        print(line, file=sys.stderr)


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
