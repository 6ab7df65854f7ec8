"""``egosearch variant new|check``."""

from __future__ import annotations

from egosearch.core.outputs import check_outputs
from egosearch.variants import ABLATIONS_DIR, check_learner_config, load_variant, new_variant


def run(args) -> None:
    if args.what == "new":
        check_outputs(dirs={"the variants folder": ABLATIONS_DIR})
        path = new_variant(args.name, template=args.template)
        print(f"wrote {path}: edit it, then `snakemake --cores 2 compare --config variant={args.name}`")
        return
    for name in args.names:
        variant = load_variant(name)
        for profile in args.profile:
            check_learner_config(variant, profile)
        print(f"{variant.path}: valid at the {', '.join(args.profile)} learner profile(s)")
