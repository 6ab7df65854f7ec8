"""The cost model: how long a run of the workflow, a comparison or one training takes on a machine.
Imports core, rl (the env step units; the learner benchmark, to calibrate), variants, the workflow's DAG and
report's readers of the workflow and its runs; imported by the CLI (``estimate``, ``train``) and the Snakefile.

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
