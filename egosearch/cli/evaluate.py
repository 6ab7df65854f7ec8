"""``egosearch evaluate``."""

from __future__ import annotations

from egosearch.cli.acting import check_threads, policy_factory, set_acting_threads
from egosearch.cli.checks import check_seed, check_suffix
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.envs import ALL_ENV_IDS
from egosearch.runs.evaluate import evaluate, write_episodes
from egosearch.runs.metrics import spl
from egosearch.runs.trace import TraceRecorder
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out, "--traces": args.traces})
    check_overwrites(files={"--out": args.out, "--traces": args.traces},
                     inputs={"--scenarios": args.scenarios, "--weights": args.weights}, force=args.force)
    check_suffix("--traces", args.traces, (".npz",), "a trace file")
    check_seed("--seed", args.seed)
    check_threads(args.threads)
    if args.env_id is not None and args.env_id not in ALL_ENV_IDS:  # '' too: it would read as no --env-id
        raise ValueError(f"--env-id={args.env_id!r}; allowed: {', '.join(ALL_ENV_IDS)}")
    set_acting_threads(args.threads)
    make_policy, env_id = policy_factory(args.policy, args.weights, args.seed, env_id=args.env_id,
                                           out=args.out)
    scenarios = read_scenarios(args.scenarios)
    recorder = TraceRecorder() if args.traces else None
    rows = evaluate(env_id, make_policy, scenarios, seed=args.seed, progress=True,
                    desc=f"evaluate {args.policy} on {env_id}", recorder=recorder)
    write_episodes(args.out, rows)
    if recorder is not None:
        print(f"wrote {recorder.write(args.traces)}: {len(recorder.columns['step'])} steps of {len(rows)} episodes")
    rate = sum(r["success"] for r in rows) / len(rows)
    value = spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                [r["path_length"] for r in rows])
    print(f"{args.policy}: success {rate:.3f}  SPL {value:.3f}  over {len(rows)} episodes -> {args.out}")

