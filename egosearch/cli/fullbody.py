"""``egosearch fullbody``: Algorithm 1 or a baseline with a full-body character."""

from __future__ import annotations

from egosearch.cli.acting import policy_factory, set_acting_threads
from egosearch.core.outputs import check_outputs
from egosearch.motion.replan import evaluate_fullbody, parse_setting, write_fullbody
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out})
    set_acting_threads(args.threads)
    method, m, mg = parse_setting(args.setting)
    make_policy, env_id = policy_factory(args.policy, args.weights, args.seed)
    scenarios = read_scenarios(args.scenarios)[: args.limit or None]
    rows = evaluate_fullbody(env_id, make_policy, scenarios, method=method, mg_name=mg, M=m, T=args.T,
                             seed=args.seed, progress=True)
    write_fullbody(args.out, rows)
    rate = sum(r["success"] for r in rows) / len(rows)
    print(f"{args.setting} ({args.policy}): success {rate:.3f} over {len(rows)} episodes -> {args.out}")
