"""``egosearch config show ALGORITHM``: a learner's whole config in one place, each field with its value,
where the value comes from and the file that declares it. ``egosearch config page``: every learner's, as
docs/config.md (:mod:`egosearch.rl.config_page`)."""

from __future__ import annotations

from egosearch.rl.config import config_sources, load_variant_config
from egosearch.variants import format_set, load_variant, parse_set, resolve_variant


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
    set_overrides = parse_set(args.set)
    overrides, name, variant = {}, "", None
    if args.variant:
        variant = load_variant(args.variant)  # checks it against the learner fields (one line for a bad one)
        overrides, name = {k: v for k, v in variant.config.items() if k != "algorithm"}, variant.name
        if variant.config.get("algorithm", args.algorithm) != args.algorithm:
            raise ValueError(f"--variant {args.variant} trains algorithm {variant.config['algorithm']}, not "
                             f"{args.algorithm}: show that one")
        trained = load_variant_config(args.preset).algorithm  # at smoke, the cpu preset's learner
        if "algorithm" not in variant.config and trained != args.algorithm:
            # the variant names no learner: it trains the preset's, and this table would pass for its config
            raise ValueError(f"--variant {args.variant} trains algorithm {trained} at the {args.preset} preset "
                             f"(the preset's learner), not {args.algorithm}: show that one (egosearch config show "
                             f"{trained} --preset {args.preset} --variant {args.variant})")
    try:
        rows = config_sources(args.algorithm, args.preset, overrides, name, set_overrides)
    except ValueError as err:
        if not set_overrides:
            raise
        # the value out of range may be the command line's: say so, as egosearch train does
        raise ValueError(f"--set {format_set(set_overrides)}: {err}") from None
    files = sorted({row["declared_in"].rsplit(".", 1)[0] for row in rows})
    print(f"{args.algorithm} at preset {args.preset}{f' with variant {name}' if name else ''}"
          f"{f' and --set {format_set(set_overrides)}' if set_overrides else ''}: {len(rows)} fields, "
          f"declared in {', '.join(f.replace('.', '/') + '.py' for f in files)}")
    for line in environment_lines(variant, args.algorithm, args.preset, set_overrides):
        print(line)
    if args.full:
        print_full(rows)
        return
    widths = {key: max(len(key), *(len(row[key]) for row in rows)) for key in ("field", "value", "source", "paper")}
    head = "  ".join(key.ljust(widths[key]) for key in widths) + "  declared in: what it is (--full: all of it)"
    print(head)
    for row in rows:
        cells = "  ".join(row[key].ljust(widths[key]) for key in widths)
        print(f"{cells}  {row['declared_in'].rsplit('.', 1)[1]}: {row['doc']}")


def environment_lines(variant, algorithm: str, preset: str, set_overrides: dict) -> list[str]:
    """What a training takes from the variant file besides its config: the env id it trains and is evaluated in
    (the variant's ``env_id``, or the form its config's observation options turn it into) and the training env's
    keyword arguments (``train_env``); without a variant, where they come from."""
    if variant is None:
        return ["env_id, train_env: a variant's (ablations/NAME.yaml); give --variant to see them"]
    resolved = resolve_variant(variant, preset, {"algorithm": algorithm}, set_overrides)
    observed = "" if resolved.env_id == variant.env_id else (
        f" (its config's observation makes it {resolved.env_id}: the id it trains and is evaluated in)")
    train_env = ", ".join(f"{key}={value!r}" for key, value in variant.train_env.items())
    return [f"env_id     {variant.env_id}{observed}  source: variant {variant.name}",
            f"train_env  {train_env}  source: variant {variant.name}"]


def print_full(rows: list[dict[str, str]]) -> None:
    """Each field as a block: its value, source, paper value and declaring class, then its whole docstring."""
    import textwrap

    for row in rows:
        print(f"\n{row['field']} = {row['value']}  ({row['source']}; paper: {row['paper']}; declared in "
              f"{row['declared_in']})")
        print(textwrap.fill(row["doc_full"] or "(no docstring)", width=110, initial_indent="    ",
                            subsequent_indent="    ", break_long_words=False, break_on_hyphens=False))
