"""The cost model: how long a run of the workflow, a comparison or one training takes on a machine.
Imports: core, report, rl, variants, workflow.
Imported by: cli, Snakefile.
Packages: none.
rl for the env step units and the learner benchmark (to calibrate), the workflow for the DAG it simulates, the
report for its readers of the workflow's config and stored jobs; the CLI for ``estimate`` and ``train``, the
Snakefile for the cost line before a run.

- :mod:`~egosearch.cost.schedule`: a DAG's jobs laid out on N cores as Snakemake's scheduler starts them,
  at the durations a provenance record gives
- :mod:`~egosearch.cost.rates`: each stored training's env steps per CPU-second, the benchmark's ratio, the
  imitation phase's CPU time
- :mod:`~egosearch.cost.calibration`: this machine's learner rate, measured and cached
- :mod:`~egosearch.cost.estimate`: the estimate of ``snakemake all``, of a comparison's missing jobs and of
  one training, and what ``snakemake`` prints before its first job
- :mod:`~egosearch.cost.run_log`: a finished run read back from its Snakemake log
- :mod:`~egosearch.cost.schedule_check`: the simulation held to that run

This file imports none of them, so a caller loads only the modules it names (the Snakefile's ``onstart``:
:mod:`~egosearch.cost.estimate` and what it reads).
"""
