"""Running searches: a policy over a scenario CSV gives per-episode CSVs and per-step traces; the paper's metrics.
Imports sim/, searchers/ and core/; imported by rl/ (its curve evaluations), motion/ and the CLI."""
