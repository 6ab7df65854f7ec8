"""``egosearch scenarios``."""

from __future__ import annotations

from dataclasses import replace

from egosearch.core.outputs import check_outputs
from egosearch.sim.scenarios import generate_scenarios, write_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out})
    if args.n < 1:
        raise ValueError(f"--n={args.n}: a scenario set needs at least 1 scenario")
    if args.homes:
        first, sep, stop = args.homes.partition(":")
        if not (sep and first.isdigit() and stop.isdigit() and int(first) < int(stop)):
            raise ValueError(f"--homes={args.homes!r}: expected FIRST:STOP, generated home seeds with FIRST < STOP")
        scenarios = []
        for home in range(int(first), int(stop)):  # --n per home, one id sequence over the group
            # the home's seed joins the set's, so that homes do not repeat each other's draws
            for sc in generate_scenarios(f"home{home}", args.placement, args.height, args.n, args.seed + home):
                scenarios.append(replace(sc, scenario_id=len(scenarios)))
    else:
        scenarios = generate_scenarios(args.layout, args.placement, args.height, args.n, args.seed,
                                       progress=True)
    write_scenarios(args.out, scenarios)
    print(f"wrote {len(scenarios)} scenarios to {args.out}")
