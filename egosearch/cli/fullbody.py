"""``egosearch fullbody``: Algorithm 1 or a baseline with a full-body character."""

from __future__ import annotations

from egosearch.cli.acting import check_threads, policy_factory, set_acting_threads
from egosearch.cli.checks import at_least, check_seed
from egosearch.core.outputs import check_outputs, check_overwrites
from egosearch.motion.replan import DEFAULT_M, evaluate_fullbody, get_method, parse_setting, write_fullbody
from egosearch.sim.scenarios import read_scenarios


def run(args) -> None:
    check_outputs(files={"--out": args.out})
    check_overwrites(files={"--out": args.out}, inputs={"--scenarios": args.scenarios, "--weights": args.weights},
                     force=args.force)
    method, m, mg = parse_setting(args.setting)
    check_plan_options(args.setting, method, m, args.T)
    # -1 would slice off the last scenario and run the rest as if it were the file
    at_least("--limit", args.limit, 0, "the number of scenarios to use (0: all)")
    check_seed("--seed", args.seed)
    check_threads(args.threads)
    set_acting_threads(args.threads)
    make_policy, env_id, env_kwargs = policy_factory(args.policy, args.weights, args.seed, out=args.out)
    scenarios = read_scenarios(args.scenarios)[: args.limit or None]
    rows = evaluate_fullbody(env_id, make_policy, scenarios, method=method, mg_name=mg, M=m, T=args.T,
                             seed=args.seed, progress=True, env_kwargs=env_kwargs)
    write_fullbody(args.out, rows)
    rate = sum(r["success"] for r in rows) / len(rows)
    print(f"{args.setting} ({args.policy}): success {rate:.3f} over {len(rows)} episodes -> {args.out}")


def check_plan_options(setting: str, method: str, m: int | None, T: int) -> None:
    """The setting's M and ``--T`` make a plan; the replanner checks them only in the first episode."""
    if m is not None and m < 1:
        raise ValueError(f"--setting={setting}: M={m}; M is the number of steps executed per plan, >= 1")
    at_least("--T", T, 1, "the planning horizon")
    executed = m if m is not None else get_method(method).default_M or DEFAULT_M
    if get_method(method).kind == "replan" and executed > T:
        raise ValueError(f"--setting={setting} with --T={T}: {method} executes M={executed} steps of each plan, "
                         f"more than the plan's T={T}; allowed: M <= T")
