"""``egosearch variant new|check``."""

from __future__ import annotations

from egosearch.core.outputs import check_outputs
from egosearch.rl.config import PRESETS
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
    for preset in args.preset:
        # else the preset's error reads as a fault of the first variant file
        if preset not in PRESETS:
            raise ValueError(f"--preset={preset!r}; allowed: {', '.join(PRESETS)}")
        if args.preset.count(preset) > 1:
            raise ValueError(f"--preset: {preset} is given twice; each preset is checked once")
    for name in args.names:
        variant = load_variant(name)
        for preset in args.preset:
            check_learner_config(variant, preset, allow_long=args.allow_long)
        print(f"{variant.path}: valid at the {', '.join(args.preset)} learner preset(s)")
