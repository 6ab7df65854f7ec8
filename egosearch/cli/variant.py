"""``egosearch variant new|check``."""

from __future__ import annotations

from egosearch.core.outputs import check_outputs
from egosearch.rl.config import PROFILES
from egosearch.variants import ABLATIONS_DIR, VariantError, check_learner_config, load_variant, new_variant


def run(args) -> None:
    if args.what == "new":
        check_outputs(dirs={"the variants folder": ABLATIONS_DIR})
        try:
            load_variant(args.template, ABLATIONS_DIR)
        except VariantError as err:
            raise ValueError(f"--from: {err}") from None
        path = new_variant(args.name, template=args.template, directory=ABLATIONS_DIR)
        # the order docs/ablations.md gives: one seed first, every seed for a variant that passes
        print(f"wrote {path}: edit it, check it (`egosearch variant check {args.name}`), then screen it on one seed: "
              f"`snakemake --cores 2 screen --config variant={args.name}`; a variant that passes its screen gets "
              f"`snakemake --cores 2 compare --config variant={args.name}` (every seed; docs/ablations.md)")
        return
    for profile in args.profile:
        # else the profile's error reads as a fault of the first variant file
        if profile not in PROFILES:
            raise ValueError(f"--profile={profile!r}; allowed: {', '.join(PROFILES)}")
        if args.profile.count(profile) > 1:
            raise ValueError(f"--profile: {profile} is given twice; each profile is checked once")
    for name in args.names:
        variant = load_variant(name)
        for profile in args.profile:
            check_learner_config(variant, profile, allow_long=args.allow_long)
        print(f"{variant.path}: valid at the {', '.join(args.profile)} learner profile(s)")
