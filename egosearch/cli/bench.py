"""``egosearch bench env|homes|learner|gpu``: speed benchmarks, recorded with the machine and its load."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from egosearch.core.outputs import check_outputs
from egosearch.rl.bench import bench_learner, gpu_check
from egosearch.sim import bench
from egosearch.variants import resolve_variant

GPU_CHECK_VARIANT = "head_on"
"""The variant whose paper-profile training ``bench gpu`` times (seed 0)."""


def run(args) -> None:
    check_outputs(files={"--out": args.out}, dirs={"--out-dir": args.out_dir})
    if args.what == "gpu" and not args.out_dir:
        raise ValueError("bench gpu needs --out-dir (the paper-profile training's folder)")
    if args.what == "gpu" and not args.seconds > 0:
        raise ValueError(f"--seconds must be a positive number, got {args.seconds}")
    if not args.baseline_seconds >= 0:
        raise ValueError(f"--baseline-seconds must be a number >= 0, got {args.baseline_seconds}")

    def measure() -> dict:
        if args.what == "env":
            return bench.bench_env(args.layout, frames=args.frames, steps=args.steps)
        if args.what == "homes":
            return bench.bench_homes()
        if args.what == "gpu":
            overrides = {"cuda_graph": True} if args.cuda_graph else {}
            resolved = resolve_variant(GPU_CHECK_VARIANT, "paper", {**overrides, "seed": 0})
            return gpu_check(args.seconds, args.out_dir, resolved, overrides=overrides,
                             baseline_seconds=args.baseline_seconds)
        return bench_learner()

    options = f" --layout {args.layout} --frames {args.frames} --steps {args.steps}" if args.what == "env" else ""
    if args.what == "gpu":
        options = f" --seconds {args.seconds:g}" + (" --cuda-graph" if args.cuda_graph else "") + (
            f" --baseline-seconds {args.baseline_seconds:g}" if args.baseline_seconds else "")
    record = bench.recorded(f"egosearch bench {args.what}{options}", measure)
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
