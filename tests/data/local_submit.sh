#!/usr/bin/env bash
# A stand-in for sbatch/qsub: runs the Snakemake jobscript on this machine in the background and
# prints a job id, as a cluster's submit command would.
nohup bash "$1" > "$1.out" 2>&1 &
echo "local-$!"
