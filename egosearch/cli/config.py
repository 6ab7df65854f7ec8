"""``egosearch config show ALGORITHM``: a learner's whole config in one place, each field with its value,
where the value comes from and the file that declares it. ``egosearch config page``: every learner's, as
docs/config.md (:mod:`egosearch.rl.config_page`)."""

from __future__ import annotations

from egosearch.rl.config import LearnerConfig, config_sources
from egosearch.rl.profiles import PROFILES


def run(args) -> None:
    if args.action == "page":
        from pathlib import Path

        from egosearch.cli.checks import check_suffix
        from egosearch.core.outputs import check_outputs
        from egosearch.rl.config_page import config_page

        check_suffix("--out", args.out, (".md",), "a Markdown page")
        check_outputs(files={"--out": args.out})
        Path(args.out).write_text(config_page(), encoding="utf-8")
        print(f"wrote {args.out}")
        return
    overrides, name = {}, ""
    if args.variant:
        # local: reading a variant file checks it against the learner fields (one line for a bad one)
        from egosearch.variants import load_variant

        variant = load_variant(args.variant)
        overrides, name = {k: v for k, v in variant.config.items() if k != "algorithm"}, variant.name
        if variant.config.get("algorithm", args.algorithm) != args.algorithm:
            raise ValueError(f"--variant {args.variant} trains algorithm {variant.config['algorithm']}, not "
                             f"{args.algorithm}: show that one")
        trained = PROFILES[args.profile]().get("algorithm", LearnerConfig.algorithm)
        if "algorithm" not in variant.config and trained != args.algorithm:
            # the variant names no learner: it trains the profile's, and this table would pass for its config
            raise ValueError(f"--variant {args.variant} trains algorithm {trained} at the {args.profile} profile "
                             f"(the profile's learner), not {args.algorithm}: show that one (egosearch config show "
                             f"{trained} --profile {args.profile} --variant {args.variant})")
    rows = config_sources(args.algorithm, args.profile, overrides, name)
    files = sorted({row["declared_in"].rsplit(".", 1)[0] for row in rows})
    print(f"{args.algorithm} at profile {args.profile}{f' with variant {name}' if name else ''}: {len(rows)} fields, "
          f"declared in {', '.join(f.replace('.', '/') + '.py' for f in files)}")
    widths = {key: max(len(key), *(len(row[key]) for row in rows)) for key in ("field", "value", "source", "paper")}
    head = "  ".join(key.ljust(widths[key]) for key in widths) + "  declared in: what it is"
    print(head)
    for row in rows:
        cells = "  ".join(row[key].ljust(widths[key]) for key in widths)
        print(f"{cells}  {row['declared_in'].rsplit('.', 1)[1]}: {row['doc']}")
