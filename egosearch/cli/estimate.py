"""``egosearch estimate all``: how long ``snakemake --cores N all`` takes from a fresh clone, on this
machine; ``egosearch estimate check``: the schedule simulation held to a finished run. This module
checks the command's options and inputs and prints the answer; the cost model it asks is
:mod:`egosearch.cost` (the estimate, the schedule simulation, the calibration, the run-log reader).
"""

from __future__ import annotations

import difflib
import json
import math
import os
import sys
from pathlib import Path

from egosearch.cli.checks import read_json_object
from egosearch.core.machine import measured_on, with_machine
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.core.preset_word import recorded_preset
from egosearch.cost.calibration import BUSY_CORES, calibrate, this_machine
from egosearch.cost.estimate import estimate_all
from egosearch.cost.rates import steps_of_bench, steps_of_preset
from egosearch.cost.run_log import RunLog, read_run_log
from egosearch.cost.schedule import machine_key
from egosearch.cost.schedule_check import run_preset, schedule_check
from egosearch.workflow.dag import rule_names

CHECK_ONLY = {"log": "--log", "record": "--record", "target": "--target"}
"""Options that ``estimate check`` reads and ``estimate all`` does not (and the reverse below)."""
ALL_ONLY = {"rate": "--rate", "from_bench": "--from-bench", "bench": "--bench"}

MAX_CORES = 1024
"""Most cores an estimate is made for: snakemake's ``--cores`` on one machine (the DAG has a few hundred
jobs; a larger figure is a typo, and the estimate would be the DAG's longest chain without a word)."""
RECORD_FILE = ("a provenance record is the JSON file `egosearch report provenance` writes "
               "(results/<preset>/provenance.json)")
BENCH_FILE = "a learner benchmark record is the JSON file `egosearch bench learner --out` writes"


def run(args) -> None:
    args.out = with_machine(args.out)
    if args.cores < 1:
        raise ValueError(f"--cores={args.cores}: the estimate needs at least 1 core")
    if args.cores > MAX_CORES:
        raise ValueError(f"--cores={args.cores}: at most {MAX_CORES}, the cores of one machine snakemake schedules "
                         f"on (this one has {os.cpu_count()})")
    unread = ALL_ONLY if args.what == "check" else CHECK_ONLY
    for name, flag in unread.items():
        # `is not`: 0 equals False, so `--rate 0` would pass for an option not given
        if getattr(args, name) is not None and getattr(args, name) is not False:
            # an option the command never reads would leave a record that seems to say it was used
            raise ValueError(f"{flag} is read by `estimate {'all' if args.what == 'check' else 'check'}` only, not "
                             f"by `estimate {args.what}`")
    if args.what == "check" and not args.log:
        raise ValueError("estimate check needs --log: a finished run's .snakemake/log/<date>.snakemake.log")
    if args.rate is not None and not (args.rate > 0 and math.isfinite(args.rate)):
        raise ValueError(f"--rate={args.rate}: env steps per CPU-second must be a positive, finite number")
    if args.rate is not None and args.from_bench:
        raise ValueError("--rate and --from-bench both name the rate: give one")
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out}, inputs={"--bench": args.bench, "--log": args.log,
                                                        "--record": args.record}, force=args.force)
    if args.what == "check":
        check_target(args.target)
        run_log = read_log(args.log)
        preset = checked_run_preset(args.log, run_log, args.preset)
    else:
        run_log, preset = None, args.preset or "cpu"
    results = Path("results") / preset
    record_path = Path(args.record) if args.record else results / "provenance.json"
    if not args.record and not record_path.is_file() and args.what == "check":
        raise FileNotFoundError(f"{record_path} not found: the jobs of {args.log} ran at the {preset} preset, and "
                                "the check judges them against that preset's recorded job times: give --record, a "
                                f"record of the {preset} preset")
    if not args.record and not record_path.is_file():
        raise FileNotFoundError(f"{record_path} not found: the estimate scales the stored run's job times "
                                "(run it in the project's root, at a preset with a stored run)")
    record = read_record("--record" if args.record else "the stored record", record_path)
    if not record.get("jobs"):
        # every job would be taken at 0 s: "about 0.0 h" (results/paper/ holds its GPU check, not a run)
        raise ValueError(f"{record_path} records no job's time: the {preset} preset has no stored run to "
                         "scale" + ("" if args.record else " (--preset cpu has one)"))
    if args.what == "check":
        if recorded_preset(record) not in (None, preset):
            raise ValueError(f"--record: {record_path} holds the {recorded_preset(record)} preset's job times, but the "
                             f"jobs of {args.log} ran at the {preset} preset: give a record of the {preset} "
                             "preset")
        figures = schedule_check(args.log, record, preset, args.target or "all", args.cores, record_path,
                                 run_log=run_log)
    else:
        figures = _estimate_all_here(args, record, results)
    for line in figures["lines"]:
        print(line)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        # when, where and how: an estimate calibrated on one machine is that machine's (docs/speed.md's table)
        made = {"command": _command(args), **measured_on()}
        Path(args.out).write_text(json.dumps({**made, **figures}, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.out}", file=sys.stderr)
    if args.json:
        print(json.dumps({k: v for k, v in figures.items() if k != "lines"}))


def read_record(option: str, path: Path) -> dict:
    """The provenance record at ``path``: a JSON object whose ``jobs`` is a list of rows, each naming its
    ``rule`` and ``job`` (what the schedule reads)."""
    record = read_json_object(option, path, RECORD_FILE)
    jobs = record.get("jobs", [])
    if not isinstance(jobs, list) or not all(isinstance(row, dict) and "rule" in row and "job" in row
                                             for row in jobs):
        raise ValueError(f"{option}: {path} holds no list of jobs with their rule and job ('jobs'); {RECORD_FILE}")
    return record


def read_bench(option: str, path: Path) -> dict:
    """The learner benchmark record at ``path``: a JSON object whose ``result`` is an object."""
    bench = read_json_object(option, path, BENCH_FILE)
    if not isinstance(bench.get("result", {}), dict) or not isinstance(bench.get("machine", {}), dict):
        raise ValueError(f"{option}: {path} holds no benchmark result ('result' and 'machine' must be objects); "
                         f"{BENCH_FILE}")
    return bench


def read_log(path: str) -> RunLog:
    """``--log``: the finished run's Snakemake log."""
    if Path(path).is_dir():
        raise ValueError(f"--log: {path} is a folder; a Snakemake log is .snakemake/log/<date>.snakemake.log")
    if not Path(path).is_file():
        raise FileNotFoundError(f"--log: {path} not found; a Snakemake log is .snakemake/log/<date>.snakemake.log")
    try:
        return read_run_log(path)
    except ValueError as err:
        raise ValueError(f"--log: {err}") from None


def check_target(target: str | None) -> None:
    """``--target`` is a rule of the workflow: Snakemake otherwise fails with a traceback
    (``MissingRuleException``) once the DAG is built."""
    if target is None:
        return
    rules = rule_names()
    if target not in rules:
        close = difflib.get_close_matches(target, rules, n=1)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise ValueError(f"--target={target!r} is not a rule of the workflow{hint}; the run's target, e.g. all, "
                         "table1 or screen (`snakemake --list-target-rules` lists them)")


def checked_run_preset(log_path: str, run_log: RunLog, asked: str | None) -> str:
    """The preset ``estimate check`` judges the run at: the one its jobs ran at, which ``--preset``, when
    given, must be (a run at another preset judged against this one's job times reads as a slow or fast
    run without a word), else ``--preset``, else cpu."""
    ran = run_preset(run_log)
    if asked and ran and asked != ran:
        raise ValueError(f"--preset={asked}: the jobs of {log_path} ran at the {ran} preset (their paths say so): "
                         f"leave --preset out, or give the log of a {asked} run")
    return ran or asked or "cpu"


def _estimate_all_here(args, record: dict, results: Path) -> dict:
    bench_path = Path(args.bench) if args.bench else results / "bench" / "learner.json"
    if args.bench or bench_path.is_file():
        bench = read_bench("--bench" if args.bench else "the stored learner benchmark", bench_path)
    else:
        bench = {}
    rate, how, where = args.rate, "given", "on this machine"
    if rate is None and args.from_bench:
        rate = bench.get("result", {}).get("env_steps_per_core_s_cpu_profile")
        if not rate:
            raise FileNotFoundError(f"--from-bench: {bench_path} holds no learner benchmark "
                                    "(egosearch bench learner --out writes one)")
        preset = args.preset or "cpu"
        if steps_of_bench(bench) != steps_of_preset(preset):
            raise ValueError(f"--from-bench: {bench_path} timed the cpu preset's {steps_of_bench(bench)}, but the "
                             f"{preset} preset's env steps are {steps_of_preset(preset)} "
                             "(egosearch bench learner --out times today's preset)")
        how = f"recorded in {bench_path}"
        where = f"on {machine_key(bench.get('machine'))}"
    busy = None
    if rate is None:
        print("calibrating: a short cpu-preset training (about a minute, as `egosearch bench learner` times) ...",
              file=sys.stderr, flush=True)
        rate, busy = calibrate()
        how = "measured now"
        where = f"on this machine ({machine_key(this_machine())})"
    figures = estimate_all(record, results, args.cores, args.preset or "cpu", rate=rate, rate_source=how,
                           bench=bench_path, where=where)
    if busy is not None:
        figures["other_load_cores_while_calibrating"] = busy
        if busy > BUSY_CORES:
            figures["lines"].insert(2, f"  the machine was busy while it calibrated: other processes used {busy:.1f} "
                                       "cores meanwhile, so the rate here may be low and the estimate long (calibrate "
                                       "again when it is idle)")
    return figures


def _command(args) -> str:
    """The estimate's command as a user would type it again (what it was calibrated or given)."""
    # check without --preset judges the run at its own preset: the command says what was typed
    preset = args.preset or ("cpu" if args.what == "all" else None)
    words = ["egosearch estimate", args.what, f"--cores {args.cores}"] + ([f"--preset {preset}"] if preset else [])
    words += [f"--rate {args.rate:g}"] if args.rate is not None else []
    words += ["--from-bench"] if args.from_bench else []
    for flag, value in (("--bench", args.bench), ("--log", args.log), ("--record", args.record),
                        ("--target", args.target)):
        words += [f"{flag} {value}"] if value else []
    return " ".join(words + [f"--out {args.out}"])
