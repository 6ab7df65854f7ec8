"""What the Snakefile checks before it builds the DAG: the config against its schema, and every
variant the run names. A problem is one line on stderr and exit status 1, not a Snakemake
traceback (an error raised inside an input function reaches the user as an
``InputFunctionException`` with a traceback, after the DAG banner).

Snakemake reads ``--config key=[a,b]`` list items as strings; where the schema asks for a number,
a string that reads as one is taken as that number, so ``--config 'heights=[1.05]'`` works.
"""

from __future__ import annotations

import json
import os
import re
import sys
from pathlib import Path

from egosearch.core.schema_errors import schema_error
from egosearch.report.workflow_jobs import claims_pairs  # noqa: F401  (the rules import it from here)
from egosearch.searchers import searcher_registry as searchers
from egosearch.variants import (  # noqa: F401  (variant_head: the rules import it from here)
    ABLATIONS_DIR,
    ALLOW_LONG_ENV,
    ALLOW_LONG_WORKFLOW,
    Variant,
    VariantError,
    check_learner_config,
    format_set,
    load_variant,
    parse_set,
    variant_head,
)

SCHEMA_PATH = Path(__file__).resolve().parent / "config.schema.json"


class ConfigError(ValueError):
    """A workflow config that does not validate; the message is one line naming the key."""


def _number(value, kind: str):
    if not isinstance(value, str):
        return value
    try:
        number = float(value)
    except ValueError:
        return value
    if kind == "integer":
        return int(number) if number.is_integer() else value
    return number


def coerce_numbers(value, schema: dict, root: dict | None = None):
    """``value`` with every string that the schema wants as a number read as one (lists and
    objects walked, ``$ref`` into ``$defs`` followed)."""
    root = root or schema
    if "$ref" in schema:
        schema = root["$defs"][schema["$ref"].rsplit("/", 1)[-1]]
    kind = schema.get("type")
    if kind in ("number", "integer"):
        return _number(value, kind)
    if kind == "boolean" and isinstance(value, str) and value.lower() in ("true", "false"):
        return value.lower() == "true"
    if isinstance(value, list) and "items" in schema:
        return [coerce_numbers(v, schema["items"], root) for v in value]
    if isinstance(value, dict):
        out = {}
        for key, v in value.items():
            sub = schema.get("properties", {}).get(key)
            if sub is None:
                sub = next((s for pattern, s in schema.get("patternProperties", {}).items()
                            if re.search(pattern, key)), None)
            out[key] = coerce_numbers(v, sub, root) if sub is not None else v
        return out
    return value


def every_claims_pairs(config: dict) -> list[tuple[str, list[list[str]]]]:
    """(where in the config, pairs) for the top level's ``claims_pairs`` and each preset's own: all are
    checked, whichever preset runs, so that a typo waits for no other preset's run."""
    return [("claims_pairs", config.get("claims_pairs", []))] + [
        (f"presets/{name}/claims_pairs", preset["claims_pairs"])
        for name, preset in config.get("presets", {}).items() if "claims_pairs" in preset]


def check_config(config: dict, schema_path: Path = SCHEMA_PATH) -> None:
    """Coerce numbers in place, then validate; ``ConfigError`` names the key and the value."""
    import jsonschema

    schema = json.loads(Path(schema_path).read_text())
    config.update(coerce_numbers(dict(config), schema))
    try:
        jsonschema.validate(config, schema)
    except jsonschema.ValidationError as err:
        where, what = schema_error(err)
        raise ConfigError(f"config {where}: {what}") from None
    for where, pairs in every_claims_pairs(config):
        for i, pair in enumerate(pairs):
            if pair[0] == pair[1]:
                raise ConfigError(f"config {where}: {pair} is one searcher twice; a pair is [head moving, head "
                                  "fixed]")
            if list(pair) in [list(p) for p in pairs[:i]]:
                # the behaviour pages and the failure table would read its traces twice
                raise ConfigError(f"config {where}: {list(pair)} is given twice; each pair once")
    check_training_seeds(config)
    check_budgets(config)
    for where, pairs in every_claims_pairs(config):
        first = pairs[0] if pairs else []
        if first and all(name in searchers.classical() for name in first):
            # versus_teacher and Figure 6 read the first pair's trainings (their curves, their teachers)
            raise ConfigError(f"config {where}: the first pair {list(first)} is Figure 6's and versus_teacher's, "
                              "which read its trainings: name variants there (e.g. [head_on, head_off]) and the "
                              "classical searchers in a later pair")
    if config.get("fresh_scenario_seed") == config["scenario_seed"]:
        raise ConfigError(f"config fresh_scenario_seed: {config['fresh_scenario_seed']} is the stored sets' "
                          "scenario_seed; the fresh-set check needs sets never stored")


def let_jobs_run_long(config: dict) -> None:
    """With the workflow config's ``allow_long``, the jobs' ``egosearch train`` and ``demos`` allow what the
    Snakefile's checks allowed, through the environment (``ALLOW_LONG_ENV``, which they read) rather than a flag:
    their command lines stay as they were, so that no stored job reruns for a changed command."""
    if config.get("allow_long"):
        os.environ[ALLOW_LONG_ENV] = "1"


def check_training_seeds(config: dict) -> None:
    """Every seed a training of the run takes (each preset's ``seeds``, ``spread_seeds`` and budget seeds, and the
    screen's ``screen_seed`` on) at most 2**32 - 1: a training seeds numpy's 32-bit global generator, and a
    larger seed failed in its job, after the DAG had started."""
    from egosearch.core.seeds import MAX_SEED

    given = [("screen_seed", config.get("screen_seed", 0) + config.get("screen_seeds", 1) - 1)]
    for name, preset in config.get("presets", {}).items():
        given += [(f"presets/{name}/{key}", max(preset.get(key) or [0])) for key in ("seeds", "spread_seeds")]
        given.append((f"presets/{name}/budget/seeds", max((preset.get("budget") or {}).get("seeds") or [0])))
    for where, seed in given:
        if seed > MAX_SEED:
            value = (f"{config['screen_seed']} with screen_seeds={config.get('screen_seeds', 1)} trains seeds up to "
                     f"{seed}, which" if where == "screen_seed" else f"{seed}")
            raise ConfigError(f"config {where}: {value} is out of range; allowed: a training seed <= 2**32 - 1 = "
                              f"{MAX_SEED} (numpy's global seed is 32-bit)")


def check_budgets(config: dict) -> None:
    """Each preset's budget study reads each setting once, the preset's own (its ``reference``, else the
    reference variant) apart from the others: a setting that is the reference too drew the same runs twice."""
    for name, preset in config.get("presets", {}).items():
        budget = preset.get("budget") or {}
        reference = budget.get("reference", config.get("reference_variant"))
        if reference in budget.get("variants", []):
            named = "budget/reference" if "reference" in budget else "reference_variant"
            raise ConfigError(f"config presets/{name}/budget/variants: {reference!r} is the study's own setting "
                              f"({named}), read against itself; leave it out of variants (its runs are the "
                              "preset's seeds already)")


def command_line_claims_pairs(config: dict, command_line: dict | None) -> None:
    """``--config claims_pairs=...`` where the run's preset names its own: the preset's are read, and the ones
    typed would be ignored without a word."""
    preset = config.get("preset")
    if command_line and "claims_pairs" in command_line and "claims_pairs" in config["presets"].get(preset, {}):
        raise ConfigError(f"config claims_pairs: the {preset} preset names its own (presets/{preset}/"
                          "claims_pairs in egosearch/workflow/config.yaml), which the run reads instead of the "
                          "top level's; edit that one, or run another preset")


def check_pair_heads(variants: dict[str, Variant], config: dict) -> None:
    """Each claims pair is [head moving, head fixed], as the behaviour claims read it: a pair the other way round
    (or two of one head) would read each claim backwards without a word."""
    for where, pairs in every_claims_pairs(config):
        for pair in pairs:
            heads = [searchers.get(n).head if n in searchers.SEARCHERS else variant_head(variants[n]) for n in pair]
            if heads != [True, False] and None not in heads:
                said = ", ".join(f"{n} (head {'moving' if h else 'fixed'})" for n, h in zip(pair, heads))
                raise ConfigError(f"config {where}: {list(pair)} is {said}; a pair is [head moving, head fixed]")


def workflow_variants(config: dict, compare: bool | str = False,
                      directory: Path = ABLATIONS_DIR) -> dict[str, Variant]:
    """Every variant the run may train, read and checked against the run's learner preset:
    ``variants``, ``reference_variant``, the preset's ``budget`` variants and reference, the variants of
    every ``claims_pairs`` (the top level's and each preset's) and, when set (or when
    ``compare`` names a target that compares, "compare" or "screen"), ``variant``."""
    target = compare if isinstance(compare, str) else "compare"
    budget_config = config["presets"][config["preset"]].get("budget", {})
    budget = budget_config.get("variants", []) + ([budget_config["reference"]] if "reference" in budget_config else [])
    generalise = config.get("generalise") or {"variants": []}
    claims = [(where, name) for where, pairs in every_claims_pairs(config) for pair in pairs for name in pair
              if name not in searchers.classical()]  # the classical searchers: traced by trace_bound
    # the config key that names each variant first: an unknown name's line says which key to fix
    named_by: dict[str, str] = {}
    for key, name in ([("variants", n) for n in config["variants"]]
                      + [("reference_variant", config["reference_variant"])]
                      + [(f"presets/{config['preset']}/budget", n) for n in budget]
                      + [("generalise/variants", n) for n in generalise["variants"]] + claims
                      + ([("variant", config["variant"])] if config.get("variant") else [])):
        named_by.setdefault(name, key)
    names = list(named_by)
    if compare and not config.get("variant"):
        raise VariantError(f"{target} needs a variant: snakemake --cores 2 {target} --config variant=NAME")
    if compare and config["variant"] == config["reference_variant"]:
        raise VariantError(f"variant={config['variant']!r} is the reference variant itself: {target} needs another "
                           "variant (or another reference_variant)")
    learner = config["presets"][config["preset"]]["learner"]
    variants = {}
    for name in names:
        variants[name] = _named_variant(name, named_by[name], directory)
        check_learner_config(variants[name], learner, allow_long=config.get("allow_long", False),
                             flag=ALLOW_LONG_WORKFLOW)
    check_pair_heads(variants, config)
    generated = generalise.get("generated_variant")
    if generated is not None and (generated not in generalise["variants"]
                                  or variants[generated].train_env["layout"] != "generated"):
        raise ConfigError(f"config generalise/generated_variant: {generated!r} must be one of generalise/variants "
                          "and train in generated homes (train_env: layout: generated)")
    reference = generalise.get("reference")
    if reference is not None and reference not in generalise["variants"]:
        raise ConfigError(f"config generalise/reference: {reference!r} must be one of generalise/variants")
    return variants


def _named_variant(name: str, key: str, directory: Path) -> Variant:
    """The variant file ``name`` that the config's ``key`` names; a name with no file is refused naming
    the key (a reference searcher's name too: its evaluations are no variant's)."""
    if not (Path(directory) / f"{name}.yaml").is_file():
        if name in searchers.SEARCHERS:
            raise VariantError(f"config {key}: {name!r} is a reference searcher, not a variant (a file in "
                               f"{Path(directory).name}/, e.g. head_on)")
        try:
            load_variant(name, directory)
        except VariantError as err:
            raise VariantError(f"config {key}: {err}") from None
    return load_variant(name, directory)


OLD_PRESET_KEY = "profile"
"""The old name of the workflow config's ``preset`` (``--config profile=NAME``), read for one release (until
egosearch 0.2); Snakemake's ``--profile`` is a folder of its options (``profiles/``), a different thing."""


def renamed_preset_key(config: dict, note: bool = True) -> None:
    """Read ``--config profile=NAME`` as ``preset=NAME`` (in place), with a one-line note when ``note``."""
    if OLD_PRESET_KEY not in config:
        return
    config["preset"] = config.pop(OLD_PRESET_KEY)
    if note:
        print("egosearch: note: --config profile=NAME is the old name of --config preset=NAME (the learner preset: "
              "smoke, cpu or paper; not Snakemake's --profile); it is read until egosearch 0.2", file=sys.stderr)


def checked_variants(config: dict, argv: list[str] | None = None,
                     directory: Path = ABLATIONS_DIR, command_line: dict | None = None) -> dict[str, Variant]:
    """For the Snakefile: check the config and the variants, or print one line and exit 1.
    ``compare`` or ``screen`` among the command's targets makes ``variant`` required; ``command_line``: the
    ``--config`` entries as typed."""
    argv = sys.argv[1:] if argv is None else argv
    try:
        check_config(config)
        command_line_claims_pairs(config, command_line)
        comparing = next((t for t in ("compare", "screen") if t in argv), False)
        workflow_set(config)
        return workflow_variants(config, compare=comparing, directory=directory)
    except (ConfigError, VariantError) as err:
        print(f"egosearch: error: {err}", file=sys.stderr)
        sys.exit(1)


def workflow_set(config: dict) -> dict:
    """The workflow config's ``set`` (``--config set="FIELD=VALUE,..."``) as {field: value}, each field and
    value checked as ``egosearch train --set`` checks them (a one-line ``VariantError`` naming ``config set``);
    the ranges, which depend on the variant, are checked against each training of the DAG
    (:func:`trainings_set_line`)."""
    return parse_set(config.get("set"), where="config set")


def set_arguments(set_overrides: dict) -> str:
    """The ``--set FIELD=VALUE`` arguments that hand ``set_overrides`` to ``egosearch train`` / ``egosearch demos``
    (shell-quoted; empty without a set)."""
    import shlex

    return "".join(f" --set {shlex.quote(f'{key}={value}')}" for key, value in set_overrides.items())


def recorded_set(run_dir: Path) -> dict | None:
    """The ``set`` a stored training in ``run_dir`` recorded (its config.json, else its done.json): {} for one
    stored before trainings recorded it; None where no training is stored."""
    for name in ("config.json", "done.json"):
        try:
            return dict(json.loads((Path(run_dir) / name).read_text(encoding="utf-8")).get("set") or {})
        except (OSError, ValueError, AttributeError):
            continue
    return None


def trainings_set_line(trainings, set_overrides: dict, learner_of) -> str | None:
    """One line, or None. ``trainings``: the DAG's training jobs as (variant, run folder). Each must take
    ``set_overrides`` (their ranges, and only fields its learner has, at ``learner_of(variant)``, the run's
    learner preset); and a training stored in its folder, whether the plan reuses it or Snakemake would redo
    it, must have recorded the same set: results under one variant's name take one config."""
    from egosearch.variants import identity_set, resolve_variant

    mine = identity_set(set_overrides)
    checked: set[str] = set()
    for variant, run_dir in trainings:
        if set_overrides and variant not in checked:
            checked.add(variant)
            try:
                resolve_variant(variant, learner_of(variant), set_overrides=set_overrides)
            except VariantError as err:
                return f"config set={format_set(set_overrides)}: variant {variant}: {str(err).split(': ', 1)[-1]}"
        recorded = recorded_set(run_dir)
        if recorded is not None and identity_set(recorded) != mine:
            return (f"config set={format_set(mine) or 'none'}: the plan reads the stored training {run_dir}, trained "
                    f"with set {format_set(identity_set(recorded)) or 'none'}; a set applies to the trainings a run "
                    "makes and a variant's results take one config: keep the overrides as a variant of their own "
                    "(`egosearch variant new NAME`, its config: holding them), or target trainings not stored yet")
    return None


def reports_missing_inputs(rules, exists=lambda p: Path(p).exists()) -> list[str]:
    """One line for each rule whose outputs are all stored but some of whose inputs are not.

    ``rules``: (name, outputs, inputs) of the rules without wildcards. Snakemake (>= 7.7) does not
    rerun a job whose outputs exist for a missing input, even one a rule can make (it takes it for
    a deleted intermediate), so a variant or budget setting added to the config would otherwise
    be skipped without a word; ``-R NAME`` makes the missing inputs and redoes the report."""
    lines = []
    for name, outputs, inputs in rules:
        missing = [p for p in inputs if not exists(p)]
        if outputs and missing and all(exists(p) for p in outputs):
            lines.append(f"{name}: its outputs are stored but {len(missing)} of its inputs are not "
                         f"(e.g. {missing[0]}); Snakemake will not make them for it: "
                         f"add `-R {name}` to make them and redo {name}")
    return lines


def damaged_inputs_line(input_paths) -> str | None:
    """One line when a stored file the plan reads differs from the sha256 its provenance recorded (a truncated
    evaluation, say), naming it and how to restore it; None when every such file matches. Files no record lists
    (new results, a smoke run's) pass: only what was stored is vouched for."""
    from egosearch.report.provenance import stored_problems

    existing = sorted({str(p) for p in input_paths if Path(p).is_file()})
    problems, _ = stored_problems(existing, require_record=False)
    if not problems:
        return None
    path, problem = problems[0]
    more = f" ({len(problems) - 1} more stored input(s) differ too; `egosearch report verify` lists them)" \
        if len(problems) > 1 else ""
    return (f"refusing to start: {problem}{more}; restore it with `git checkout -- {path}`, or rerun the job that "
            "writes it and then the `provenance` rule")


def unwritable_outputs_line(output_paths) -> str | None:
    """One line when a folder the plan writes in cannot be written (a read-only results/, mounted so or
    chmod'ed for another user), naming it and the first file it would hold; None when every one can. Each
    output's nearest existing folder is tried with a file made and removed there: what the job would do
    (``os.access`` says yes on a read-only mount for root, and Snakemake failed with a traceback once the
    run had started)."""
    import tempfile

    tried: dict[Path, str | None] = {}
    for path in dict.fromkeys(str(p) for p in output_paths):  # outputs first, as the rule lists them
        folder = Path(path).parent
        while not folder.exists() and folder != folder.parent:
            folder = folder.parent
        if folder not in tried:
            try:
                with tempfile.TemporaryFile(dir=folder):
                    pass
                tried[folder] = None
            except OSError as err:
                tried[folder] = err.strerror or type(err).__name__
        if tried[folder]:
            return (f"refusing to start: {folder} cannot be written ({tried[folder]}), and this run writes {path} "
                    "there; make it writable, or run from a checkout that is")
    return None
