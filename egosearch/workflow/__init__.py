"""The Snakemake workflow: rules, config and schemas, and the checks the Snakefile runs before the DAG is built.
Imports: core, report, searchers, variants.
Imported by: cli, cost, Snakefile.
Packages: jsonschema, snakemake, snakemake_executor_plugin_slurm, yaml."""
