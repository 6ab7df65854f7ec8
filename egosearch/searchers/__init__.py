"""The searchers that are not learned: oracle, random, the classical frontier searcher, and their registry.
Imports: core, sim.
Imported by: cli, envs, report, rl, runs, variants, workflow, Snakefile.
Packages: gymnasium, numpy, scipy.
Its registry (``registry``: the one place a searcher is added) is plain data that imports only core's registry
helper, so that the report, the workflow and the variants read it without the simulator."""
