"""``egosearch scenarios``."""

from __future__ import annotations

from dataclasses import replace

from egosearch.cli.checks import check_seed
from egosearch.cli.parsers import MAX_HOMES, MAX_SCENARIOS
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.scene.layouts import get_scene
from egosearch.sim.body import check_height
from egosearch.sim.scenarios import generate_scenarios, write_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out}, force=args.force)
    if args.n < 1:
        raise ValueError(f"--n={args.n}: a scenario set needs at least 1 scenario")
    # a set the size of a typo runs for years, and its progress bar says so only once it has started
    if args.n > MAX_SCENARIOS:
        raise ValueError(f"--n={args.n}: at most {MAX_SCENARIOS} scenarios in one set (minutes at ~40 scenarios/s; "
                         "a Table 1 cell has 200)")
    check_seed("--seed", args.seed)
    check_height(args.height)
    homes = None
    if args.homes and args.layout:
        # the set would be the generated homes', and its rows read as the layout's
        raise ValueError(f"--layout={args.layout} and --homes={args.homes} both name the homes: give one")
    args.layout = args.layout or "kitchen_living"
    if args.homes:
        first, sep, stop = args.homes.partition(":")
        if not (sep and first.isdigit() and stop.isdigit() and int(first) < int(stop)):
            raise ValueError(f"--homes={args.homes!r}: expected FIRST:STOP, generated home seeds with FIRST < STOP")
        homes = range(int(first), int(stop))
        if len(homes) > MAX_HOMES:
            raise ValueError(f"--homes={args.homes}: {len(homes)} homes; at most {MAX_HOMES} in one set")
        if args.n * len(homes) > MAX_SCENARIOS:
            raise ValueError(f"--n={args.n} per home x --homes={args.homes} ({len(homes)} homes) is "
                             f"{args.n * len(homes)} scenarios; at most {MAX_SCENARIOS} in one set")
    else:
        try:
            get_scene(args.layout)
        except ValueError as err:
            raise ValueError(f"--layout: {err}") from None
    scenarios = []
    if homes is not None:
        for home in homes:  # --n per home, one id sequence over the group
            # the home's seed joins the set's, so that homes do not repeat each other's draws
            for sc in generate_scenarios(f"home{home}", args.placement, args.height, args.n, args.seed + home):
                scenarios.append(replace(sc, scenario_id=len(scenarios)))
    else:
        scenarios = generate_scenarios(args.layout, args.placement, args.height, args.n, args.seed,
                                       progress=True)
    write_scenarios(args.out, scenarios)
    print(f"wrote {len(scenarios)} scenarios to {args.out}")
