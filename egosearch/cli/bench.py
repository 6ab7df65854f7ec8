"""``egosearch bench env|homes|learner|gpu``: speed benchmarks, recorded with the machine and its load."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import torch

from egosearch.cli.checks import at_least
from egosearch.core.gpu_share import SIDE_BY_SIDE, side_by_side_record
from egosearch.core.machine import with_machine
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.rl.bench_learner import bench_learner, bench_stacked, gpu_check
from egosearch.scene.layouts import get_scene
from egosearch.sim import bench_env as bench
from egosearch.variants import resolve_variant

GPU_CHECK_VARIANT = "head_on"
"""The variant whose paper-preset training ``bench gpu`` times (seed 0)."""

DEFAULTS = {"layout": "kitchen_living", "frames": 3000, "steps": 3000, "seconds": 150.0, "baseline_seconds": 0.0,
            "seeds": 3}
"""Each benchmark's option defaults (the parser leaves them None, so that an option given to a
benchmark that does not read it is told apart from one left alone)."""
READ_BY = {"layout": "env", "frames": "env", "steps": "env", "seconds": "gpu", "out_dir": "gpu",
           "cuda_graph": "gpu", "baseline_seconds": "gpu", "side_by_side": "gpu", "stacked": "gpu",
           "seeds": "stacked", "memory_levers": "learner"}
"""The benchmark that reads each of the options that only one of them reads."""


def run(args) -> None:
    if args.what == "gpu" and args.side_by_side is not None and not args.out:
        args.out = str(SIDE_BY_SIDE)  # the record the docs and the run's line about sharing read
    args.out = with_machine(args.out)
    check_outputs(files={"--out": args.out}, dirs={"--out-dir": args.out_dir})
    check_overwrites(files={"--out": args.out}, dirs={"--out-dir": args.out_dir}, force=args.force)
    for name, what in READ_BY.items():
        # `is not`: 0 equals False, so `--seconds 0` would pass for an option not given
        given = getattr(args, name) is not None and getattr(args, name) is not False
        if given and args.what != what:
            # an option the benchmark never reads would leave a record that seems to say it was used
            raise ValueError(f"--{name.replace('_', '-')} is read by `bench {what}` only, not by `bench {args.what}`")
    for name, value in DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    if args.what == "gpu":
        check_gpu_options(args)
    if args.what == "stacked":
        at_least("--seeds", args.seeds, 2, "the seeds stacked")
    if args.what == "env":
        at_least("--frames", args.frames, 1, "the number of sensor frames to time")
        at_least("--steps", args.steps, 1, "the number of env steps to time")
        try:
            get_scene(args.layout)
        except ValueError as err:
            raise ValueError(f"--layout: {err}") from None

    def measure() -> dict:
        if args.what == "env":
            return bench.bench_env(args.layout, frames=args.frames, steps=args.steps)
        if args.what == "homes":
            return bench.bench_homes()
        if args.what == "stacked":
            return bench_stacked(args.seeds)
        if args.what == "gpu" and args.side_by_side:
            return measure_side_by_side(args)
        if args.what == "gpu":
            overrides = {"cuda_graph": True} if args.cuda_graph else {}
            resolved = resolve_variant(GPU_CHECK_VARIANT, "paper", {**overrides, "seed": 0})
            return gpu_check(args.seconds, args.out_dir, resolved, overrides=overrides,
                             baseline_seconds=args.baseline_seconds)
        return bench_learner(memory_levers=args.memory_levers)

    options = f" --layout {args.layout} --frames {args.frames} --steps {args.steps}" if args.what == "env" else ""
    if args.what == "stacked":
        options = f" --seeds {args.seeds}"
    if args.what == "learner" and args.memory_levers:
        options = " --memory-levers"
    if args.what == "gpu":
        options = (f" --side-by-side {args.side_by_side}" if args.side_by_side else "") + (
            f" --stacked {args.stacked}" if args.stacked else "") + (
            f" --seconds {args.seconds:g}" + (" --cuda-graph" if args.cuda_graph else "") + (
                f" --baseline-seconds {args.baseline_seconds:g}" if args.baseline_seconds else ""))
    record = bench.recorded(f"egosearch bench {args.what}{options}", measure)
    if args.what == "gpu" and args.side_by_side:
        # flat: the measurement's fields beside the machine's, date and commit
        result = {k: v for k, v in record["result"].items() if k != "runs"}
        record = side_by_side_record(record)
    else:
        result = record["result"]
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out} (other processes used {record['other_load_cores']} cores meanwhile)",
              file=sys.stderr)
    if args.json:
        print(json.dumps(result))
    else:
        for key, value in result.items():
            print(f"{key:>28}: {value}")


def check_gpu_options(args) -> None:
    if not args.out_dir:
        raise ValueError("bench gpu needs --out-dir (the paper-preset training's folder)")
    if args.side_by_side is not None:
        at_least("--side-by-side", args.side_by_side, 2, "the trainings side by side on one GPU")
        if args.cuda_graph:
            raise ValueError("--cuda-graph is not read with --side-by-side: its trainings run the paper preset as "
                             "the DAG does (cuda_graph on)")
    if args.stacked is not None:
        at_least("--stacked", args.stacked, 2, "the seeds stacked in one training")
        if args.side_by_side is None:
            raise ValueError("--stacked is measured beside the trainings side by side: give --side-by-side N too "
                             "(the record it writes into is theirs)")
    if not args.seconds > 0:
        raise ValueError(f"--seconds must be a positive number, got {args.seconds}")
    if not args.baseline_seconds >= 0:
        raise ValueError(f"--baseline-seconds must be a number >= 0, got {args.baseline_seconds}")
    if not torch.cuda.is_available():
        # on the CPU it would time the paper preset there, record cuda_graph True, and could replace
        # the stored GPU record with the numbers of a machine that has none
        built = f"built with CUDA {torch.version.cuda}" if torch.version.cuda else "a CPU-only build"
        raise ValueError(f"bench gpu needs a CUDA GPU, and torch {torch.__version__} ({built}) sees none on this "
                         "machine; `bench learner` times the learners on the CPU")


def measure_side_by_side(args) -> dict:
    """``--side-by-side N``: :func:`egosearch.cli.side_by_side.run_side_by_side` for the paper ``all``'s
    trainings (their env steps, the projection's numerator)."""
    from egosearch.cli.side_by_side import run_side_by_side
    from egosearch.report.workflow_jobs import variants_of_all, workflow_config

    config = workflow_config()
    seeds = config["presets"]["paper"]["seeds"]
    variants = variants_of_all(config)
    steps = sum(resolve_variant(v, "paper").config.total_env_steps for v in variants) * len(seeds)
    return run_side_by_side(args.side_by_side, args.seconds, args.out_dir, variant=GPU_CHECK_VARIANT,
                            all_env_steps=steps, all_trainings=len(variants) * len(seeds),
                            baseline_seconds=args.baseline_seconds, stacked=getattr(args, "stacked", None) or 0,
                            say=lambda line: print(line, file=sys.stderr, flush=True))
