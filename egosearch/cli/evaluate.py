"""``egosearch evaluate``."""

from __future__ import annotations

from egosearch.cli.acting import check_threads, policy_factory, set_acting_threads
from egosearch.cli.checks import check_seed, check_suffix
from egosearch.core.csvio import write_csv_atomic
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.envs import ALL_ENV_IDS, parse_env_options
from egosearch.runs.evaluate import CURVE_LEVEL_COLUMNS, curve_episodes, curve_scenarios, evaluate, write_episodes
from egosearch.runs.metrics import spl
from egosearch.runs.trace import TraceRecorder
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out, "--traces": args.traces})
    check_overwrites(files={"--out": args.out, "--traces": args.traces},
                     inputs={"--scenarios": args.scenarios, "--weights": args.weights}, force=args.force)
    check_suffix("--traces", args.traces, (".npz",), "a trace file")
    if args.curve_of and args.seed is not None:
        raise ValueError(f"--seed={args.seed} with --curve-of: the curve's episodes have their own seeds, and its "
                         "levels must run the same ones; leave --seed out")
    args.seed = 0 if args.seed is None else args.seed
    check_seed("--seed", args.seed)
    if not args.curve_of and args.preset != "cpu":
        raise ValueError(f"--preset={args.preset} is read with --curve-of only (a scenario file needs no preset)")
    curve = curve_set(args.curve_of, args.preset, args.allow_long) if args.curve_of else None
    check_threads(args.threads)
    if args.env_id is not None and args.env_id not in ALL_ENV_IDS:  # '' too: it would read as no --env-id
        raise ValueError(f"--env-id={args.env_id!r}; allowed: {', '.join(ALL_ENV_IDS)}")
    given = parse_env_options(args.env_option)
    set_acting_threads(args.threads)
    make_policy, env_id, env_kwargs = policy_factory(args.policy, args.weights, args.seed, env_id=args.env_id,
                                                     out=args.out, env_kwargs=given)
    recorder = TraceRecorder() if args.traces else None
    desc = f"evaluate {args.policy} on {env_id}"
    if curve is not None:
        rows = curve_episodes(env_id, make_policy, curve, progress=True, desc=desc, recorder=recorder,
                              env_kwargs=env_kwargs)
        write_csv_atomic(args.out, CURVE_LEVEL_COLUMNS, rows)
    else:
        rows = evaluate(env_id, make_policy, read_scenarios(args.scenarios), seed=args.seed, progress=True,
                        desc=desc, recorder=recorder, env_kwargs=env_kwargs)
        write_episodes(args.out, rows)
    if recorder is not None:
        print(f"wrote {recorder.write(args.traces)}: {len(recorder.columns['step'])} steps of {len(rows)} episodes")
    rate = sum(r["success"] for r in rows) / len(rows)
    value = spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                [r["path_length"] for r in rows])
    print(f"{args.policy}: success {rate:.3f}  SPL {value:.3f}  over {len(rows)} episodes -> {args.out}")



def curve_set(variant: str, preset: str, allow_long: bool = False) -> list:
    """The scenarios ``variant``'s training curve is evaluated on at ``preset`` (what ``egosearch train``
    hands the learner): its curve homes, its training placement, ``eval_episodes`` of them."""
    # local: resolving a variant loads the learner registry (torch), which a scenario-file run never needs
    from egosearch.sim.home_pool import curve_homes
    from egosearch.variants import check_learner_config, resolve_variant

    resolved = resolve_variant(variant, preset)
    check_learner_config(resolved.variant, preset, allow_long=allow_long)
    env = resolved.train_env
    return curve_scenarios(curve_homes(env), env["placement"], resolved.config.eval_episodes)
