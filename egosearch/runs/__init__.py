"""Running searches: a policy over a scenario CSV gives per-episode CSVs and per-step traces; the paper's metrics.
Imports sim/, searchers/ and core/; imported by motion/ (the replanner evaluates) and the CLI."""
