"""``egosearch video``: one full-body search filmed, first-person depth beside a third-person view."""

from __future__ import annotations

import pandas as pd

from egosearch.cli.acting import policy_factory, set_acting_threads
from egosearch.core.outputs import check_outputs
from egosearch.motion.video import NotACleanSuccess, clean_successes, write_search_video
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out, "--still": args.still})
    set_acting_threads(args.threads)
    scenarios = {sc.scenario_id: sc for sc in read_scenarios(args.scenarios)}
    candidates = []
    if args.first_success:
        candidates = [i for i in clean_successes(pd.read_csv(args.first_success), args.min_steps) if i in scenarios]
        if not candidates:
            print(f"note: no episode of {args.first_success} succeeded in >= {args.min_steps} steps with no "
                  f"penetrating pose; filming scenario {args.scenario_id} instead")
    if not candidates and args.scenario_id not in scenarios:
        raise ValueError(f"--scenario-id={args.scenario_id} is not in {args.scenarios}")
    make_policy, env_id = policy_factory(args.policy, args.weights, args.seed)
    row = None
    # Seeded as `egosearch fullbody` seeds scenario k (--seed + k), the film replays the CSV's episode;
    # should the replay differ, the film takes the next candidate rather than show a penetration.
    for scenario_id in candidates:
        try:
            row = write_search_video(scenarios[scenario_id].layout, args.character, make_policy,
                                     scenarios[scenario_id], args.out, still_path=args.still, M=args.M, T=args.T,
                                     seed=args.seed + scenario_id, env_id=env_id, require_clean=True)
            break
        except NotACleanSuccess as err:
            print(f"note: the replay differs from {args.first_success}: {err}; trying the next scenario")
    if row is None:
        if candidates:
            raise ValueError(f"no episode of {args.first_success} replayed as a success with no penetrating pose")
        scenario = scenarios[args.scenario_id]
        row = write_search_video(scenario.layout, args.character, make_policy, scenario, args.out,
                                 still_path=args.still, M=args.M, T=args.T, seed=args.seed + args.scenario_id,
                                 env_id=env_id)
    print(f"{args.character}: scenario {row['scenario_id']}, success {row['success']} in {row['steps']} steps, "
          f"{row['penetrations']} penetrating pose(s) -> {args.out}, {args.still}")
