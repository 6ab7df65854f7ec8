"""The Snakemake workflow: rules, config and schemas, and the checks the Snakefile runs before the DAG is built.
Imports variants and core/; imported by the Snakefile and the CLI only."""
