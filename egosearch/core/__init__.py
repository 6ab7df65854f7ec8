"""Plumbing every stage shares: checked paths, staged runs, atomic CSVs, the machine, stale locks, registries.
Imports: nothing.
Imported by: cli, cost, motion, report, rl, runs, searchers, sim, variants, workflow, Snakefile.
Packages: torch.
(torch only inside the functions that share a GPU, when they run.)"""
