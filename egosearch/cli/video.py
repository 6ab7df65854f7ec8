"""``egosearch video``: one full-body search filmed, first-person depth beside a third-person view."""

from __future__ import annotations

import pandas as pd

from egosearch.cli.acting import check_threads, policy_factory, set_acting_threads
from egosearch.cli.checks import at_least, check_seed, check_suffix, check_text_files
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.motion.replan import FULLBODY_COLUMNS
from egosearch.motion.video import (
    CHARACTERS,
    VIDEO_SUFFIXES,
    NotACleanSuccess,
    clean_successes,
    write_search_video,
)
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out, "--still": args.still})
    check_overwrites(files={"--out": args.out, "--still": args.still},
                     inputs={"--scenarios": args.scenarios, "--weights": args.weights,
                             "--first-success": args.first_success}, force=args.force)
    check_suffix("--out", args.out, VIDEO_SUFFIXES, "the video")
    check_suffix("--still", args.still, (".png",), "the still")
    if args.character not in CHARACTERS:
        raise ValueError(f"--character={args.character!r}; allowed: {', '.join(CHARACTERS)}")
    at_least("--T", args.T, 1, "the planning horizon")
    at_least("--M", args.M, 1, "the number of steps executed per plan")
    if args.M > args.T:
        raise ValueError(f"--M={args.M} > --T={args.T}: Algorithm 1 executes a prefix of each plan; allowed: M <= T")
    at_least("--min-steps", args.min_steps, 0, "the fewest steps of a filmed episode")
    check_seed("--seed", args.seed)
    check_threads(args.threads)
    check_text_files("--first-success", [args.first_success], "full-body CSV")
    set_acting_threads(args.threads)
    scenarios = {sc.scenario_id: sc for sc in read_scenarios(args.scenarios)}
    candidates = []
    if args.first_success:
        candidates = [i for i in clean_successes(read_fullbody_csv(args.first_success), args.min_steps)
                      if i in scenarios]
        if not candidates:
            print(f"note: no episode of {args.first_success} succeeded in >= {args.min_steps} steps with no "
                  f"penetrating pose; filming scenario {args.scenario_id} instead")
    if not candidates and args.scenario_id not in scenarios:
        raise ValueError(f"--scenario-id={args.scenario_id} is not in {args.scenarios}")
    make_policy, env_id, env_kwargs = policy_factory(args.policy, args.weights, args.seed, out=args.out)
    row = None
    # Seeded as `egosearch fullbody` seeds scenario k (--seed + k), the film replays the CSV's episode;
    # should the replay differ, the film takes the next candidate rather than show a penetration.
    for scenario_id in candidates:
        try:
            row = write_search_video(scenarios[scenario_id].layout, args.character, make_policy,
                                     scenarios[scenario_id], args.out, still_path=args.still, M=args.M, T=args.T,
                                     seed=args.seed + scenario_id, env_id=env_id, require_clean=True,
                                     env_kwargs=env_kwargs)
            break
        except NotACleanSuccess as err:
            print(f"note: the replay differs from {args.first_success}: {err}; trying the next scenario")
    if row is None:
        if candidates:
            raise ValueError(f"no episode of {args.first_success} replayed as a success with no penetrating pose")
        scenario = scenarios[args.scenario_id]
        row = write_search_video(scenario.layout, args.character, make_policy, scenario, args.out,
                                 still_path=args.still, M=args.M, T=args.T, seed=args.seed + args.scenario_id,
                                 env_id=env_id, env_kwargs=env_kwargs)
    print(f"{args.character}: scenario {row['scenario_id']}, success {row['success']} in {row['steps']} steps, "
          f"{row['penetrations']} penetrating pose(s) -> {args.out}, {args.still}")


def read_fullbody_csv(path: str) -> pd.DataFrame:
    """``--first-success``'s file, checked for the columns the film's choice reads."""
    try:
        runs = pd.read_csv(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"--first-success={path}: no such full-body CSV") from None
    missing = [c for c in ("scenario_id", "success", "steps", "penetrations") if c not in runs.columns]
    if missing:
        raise ValueError(f"--first-success={path}: not a full-body CSV (missing columns {', '.join(missing)}; one "
                         f"has {', '.join(FULLBODY_COLUMNS)})")
    return runs
