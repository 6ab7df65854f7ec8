"""Variants as data: one YAML file per variant in ``ablations/``, and the one place where a variant
at a learner preset becomes what a training runs (:func:`resolve_variant`: the learner config and
the env id it observes). The CLI, the benchmarks and the DAG's checks all resolve through it.

Adding a variant is adding a file; nothing else changes. A file is validated against
``egosearch/workflow/variant.schema.json`` and its ``config`` against the learner's config, so a
typo is one clear line before any job starts.
"""

from __future__ import annotations

import difflib
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import jsonschema
import yaml

from egosearch.core.schema_errors import schema_error
from egosearch.envs import EnvOptions, env_options, observed_env_id
from egosearch.rl.config import (  # noqa: F401  (format_set, identity_set: the CLI and the workflow read them here)
    ALGORITHMS,
    LearnerConfig,
    field_types,
    format_set,
    identity_set,
    load_variant_config,
    refuse_foreign_fields,
)
from egosearch.rl.run_settings import ALLOW_LONG_ENV, LONG_RUN_BOUNDS
from egosearch.searchers import searcher_registry as searchers
from egosearch.sim.home_pool import check_home_split

#: ``ablations/`` of the working directory (where Snakemake runs), else of this checkout.
ABLATIONS_DIR = next((p for p in (Path.cwd() / "ablations", Path(__file__).resolve().parent.parent / "ablations")
                      if p.is_dir()), Path("ablations"))
SCHEMA_PATH = Path(__file__).resolve().parent / "workflow" / "variant.schema.json"


class VariantError(ValueError):
    """A variant that does not exist or does not validate; the message is one line."""


@dataclass(frozen=True)
class Variant:
    name: str
    """File stem in ``ablations/``; the ``{variant}`` of every output path."""
    env_id: str
    """``EgoSearch-v0`` (head on) or ``EgoSearchNoHead-v0`` (head off); the ``*Memory-v0`` ids add
    the last-seen target memory to the observation (a change of observation), the ``*Map-v0`` ids a floor
    map too; the ``*Modular-v0`` ids learn only where to explore and how to sweep the head, and the
    frontier searcher walks (``egosearch.searchers.modular``)."""
    train_env: dict
    """Keyword arguments of the training env (layout, placement, objects, training-only aids)."""
    config: dict = field(default_factory=dict)
    """Learner config overrides on top of the preset."""
    description: str = ""
    path: str = ""
    """The file it was read from (for messages)."""


def variant_names(directory: Path = ABLATIONS_DIR) -> list[str]:
    return sorted(p.stem for p in Path(directory).glob("*.yaml"))


def _resolve(name_or_path: str | Path, directory: Path) -> Path:
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") and path.exists():
        return _shown(path)
    if path.suffix in (".yaml", ".yml") or len(path.parts) > 1:
        # a path, not a name: ablations/<path>.yaml is never what was meant
        problem = ": not a .yaml file" if path.is_file() else " is a folder" if path.is_dir() else ": no such file"
        raise VariantError(f"{path}{problem}; a variant is a name (a file in {_shown(Path(directory))}) or the path "
                           "of an existing .yaml file")
    candidate = Path(directory) / f"{name_or_path}.yaml"
    if not candidate.exists():
        names = variant_names(directory)
        # case-blind, as a name typed Head_On means head_on
        lowered = {name.lower(): name for name in names}
        close = difflib.get_close_matches(str(name_or_path).lower(), lowered, n=1)
        hint = f" (did you mean {lowered[close[0]]!r}?)" if close else ""
        raise VariantError(f"variant={str(name_or_path)!r} is unknown{hint}; allowed: "
                           f"{', '.join(names)} (files in {_shown(Path(directory))})")
    return _shown(candidate)


def _shown(path: Path) -> Path:
    """``path`` relative to the working directory when it is under it: messages say ablations/x.yaml."""
    try:
        return path.resolve().relative_to(Path.cwd().resolve())
    except ValueError:
        return path


def load_variant(name_or_path: str | Path, directory: Path = ABLATIONS_DIR) -> Variant:
    """The variant named ``name`` (``ablations/<name>.yaml``) or stored at a path.

    Its ``config`` is checked against ``LearnerConfig`` here (names and types): a typo fails on
    reading, wherever a variant is read, not when a training job builds its config."""
    path = _resolve(name_or_path, directory)
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise VariantError(f"{path}: not valid YAML{where} ({problem})") from None
    except UnicodeDecodeError:
        raise VariantError(f"{path}: not a text file; a variant is a YAML file with name, env_id, train_env") from None
    if data is None:
        raise VariantError(f"{path}: empty file; a variant needs name, env_id, train_env")
    if isinstance(data, dict) and "config" in data and data["config"] is None:
        data["config"] = {}  # a bare `config:` (YAML's null) reads as `config: {}`: no override
    schema = json.loads(SCHEMA_PATH.read_text())
    try:
        jsonschema.validate(data, schema)
    except jsonschema.ValidationError as err:
        where, what = schema_error(err)
        raise VariantError(f"{path}: {where}: {what}") from None
    if data["name"] != path.stem:
        raise VariantError(f"{path}: name={data['name']!r} must equal the file name {path.stem!r}")
    if data["name"] in searchers.SEARCHERS:
        raise VariantError(f"{path}: name={data['name']!r} is a reference searcher's, whose evaluations sit in the "
                           f"same folders: name the variant otherwise (taken: {', '.join(searchers.names())})")
    _check_objects(data["train_env"].get("objects") or [], path)
    _check_homes(data["train_env"], path)
    overrides = learner_overrides(data.get("config") or {}, f"{path}: config")
    _check_env_id_agrees(data["env_id"], overrides, path)
    return Variant(name=data["name"], env_id=data["env_id"], train_env=dict(data["train_env"]),
                   config=overrides, description=data.get("description", ""), path=str(path))


@dataclass(frozen=True)
class ResolvedVariant:
    """A variant at a learner preset: the config and env id a training of it runs with."""
    variant: Variant
    preset: str
    """The learner preset (smoke, cpu or paper) the config starts from."""
    config: LearnerConfig
    """The preset's config with the variant's overrides, the ``--set`` overrides, then the caller's, on top; at
    ``smoke``, the variant's ``cpu`` learner with every size its file pins capped
    (:func:`egosearch.rl.config.load_variant_config`)."""
    env_id: str
    """The id the policy trains and is evaluated in: the variant's ``env_id``, or its ``*Memory-v0``
    form when the config's ``target_memory`` changes the observation."""
    set_overrides: dict = field(default_factory=dict)
    """The command line's overrides (``egosearch train --set FIELD=VALUE``, the workflow config's ``set``),
    checked as a variant file's ``config:`` is (:func:`parse_set`); a training records them in its config.json
    as ``set``, and its resume refuses other ones."""

    @property
    def name(self) -> str:
        return self.variant.name

    @property
    def train_env(self) -> dict:
        return self.variant.train_env


def resolve_variant(variant: str | Path | Variant, preset: str, overrides: dict | None = None,
                    set_overrides: dict | None = None) -> ResolvedVariant:
    """``variant`` (a name, a path or a loaded :class:`Variant`) at the learner ``preset``, with
    ``set_overrides`` (the command line's ``--set``, parsed by :func:`parse_set`) on top of the variant's own
    config fields and ``overrides`` (seed, threads, ...) on top of those. A ``--set`` value out of range (or
    that breaks a rule between fields) is a one-line ``VariantError`` naming ``--set``. At ``smoke`` the variant's
    learner is its ``cpu`` one and every size of the run is capped, whatever the variant pins
    (:func:`egosearch.rl.config.load_variant_config`); a ``--set``, asked on the command line for this run, is
    taken as given, as ``overrides`` are."""
    if not isinstance(variant, Variant):
        variant = load_variant(variant)
    set_overrides = dict(set_overrides or {})
    if set_overrides:
        try:
            load_variant_config(preset, variant.config, overrides)
        except ValueError:
            pass  # the variant's own problem: reported below as it is without --set
        else:
            try:
                load_variant_config(preset, variant.config, {**set_overrides, **(overrides or {})})
            except ValueError as err:
                raise VariantError(f"--set {format_set(set_overrides)}: {err}") from None
    config = load_variant_config(preset, variant.config, {**set_overrides, **(overrides or {})})
    env_id = observed_env_id(variant.env_id, config.target_memory, config.modular_searcher)
    return ResolvedVariant(variant, preset, config, env_id, set_overrides)


def parse_set(items: list[str] | tuple[str, ...] | str | None, where: str = "--set") -> dict:
    """``FIELD=VALUE`` items (``egosearch train --set``, repeatable; the workflow config's ``set``, a
    comma-separated string or a list) -> {field: value}, each value read as YAML reads a variant file's
    (``64``, ``1e-4``, ``true``; a str field keeps the text as given) and checked as a variant file's
    ``config:`` is (:func:`learner_overrides`: a known field, its type, did-you-mean). A bad item is one
    ``VariantError`` line starting with ``where``. Ranges are checked where the config is built
    (:func:`resolve_variant`)."""
    if items is None:
        return {}
    if isinstance(items, str):
        items = [part for part in items.split(",") if part.strip()]
    kinds, values = field_types(), {}
    for item in items:
        key, eq, text = str(item).partition("=")
        key = key.strip()
        if not eq or not key:
            raise VariantError(f"{where} {str(item)!r}: give FIELD=VALUE, e.g. batch_size=64")
        if key in values:
            raise VariantError(f"{where}: {key} is given twice ({key}={values[key]!r} and {str(item).strip()}); "
                               "give it once")
        if key == "algorithm":
            raise VariantError(f"{where}: algorithm is the variant's learner (its file's config: algorithm); a set "
                               "changes the fields of that learner: make a variant to train another one")
        if kinds.get(key) == "str":
            values[key] = text.strip()
            continue
        if not text.strip():
            # YAML reads nothing as null, and "batch_size=None is not an int" hid that no value was given
            raise VariantError(f"{where} {str(item).strip()!r}: no value after '='; give FIELD=VALUE, e.g. "
                               f"{key}=<a value>")
        try:
            values[key] = yaml.safe_load(text) if text.strip() else None
        except yaml.YAMLError:
            values[key] = text
    return learner_overrides(values, where)


def variant_head(variant: str | Path | Variant) -> bool:
    """Whether the variant's body moves its head (its env id's ``head``)."""
    if not isinstance(variant, Variant):
        variant = load_variant(variant)
    return env_options(variant.env_id).head


ALLOW_LONG_CLI, ALLOW_LONG_WORKFLOW = "--allow-long", "--config allow_long=true"
"""What allows a run past :data:`egosearch.rl.run_settings.LONG_RUN_BOUNDS`: the commands' flag, the workflow's."""


def long_runs_allowed(flag: bool = False) -> bool:
    """``--allow-long`` given, or the workflow's jobs under ``--config allow_long=true`` (its environment)."""
    return bool(flag) or os.environ.get(ALLOW_LONG_ENV) == "1"


def check_run_length(config: LearnerConfig, flag: str = ALLOW_LONG_CLI) -> None:
    """One line (``ValueError``) for a config past a bound of ``LONG_RUN_BOUNDS``, naming ``flag``, which allows
    more."""
    for name, (bound, what) in LONG_RUN_BOUNDS.items():
        value = getattr(config, name, None)
        if isinstance(value, int) and value > bound:
            raise ValueError(f"LearnerConfig.{name}={value} is out of range; allowed: <= {bound:,} {what}, the "
                             f"documented bound; {flag} allows more")


def check_learner_config(variant: Variant, learner_preset: str, allow_long: bool = False,
                         flag: str = ALLOW_LONG_CLI, set_overrides: dict | None = None) -> None:
    """The variant's overrides (and the command line's ``set_overrides``) on top of ``learner_preset`` give a
    valid learner config (ranges and cross-field rules such as ``crop_size <= image_size``) within the
    documented bounds of a run's length unless ``allow_long`` (:func:`check_run_length`, naming ``flag``), else
    one-line ``VariantError``."""
    try:
        resolved = resolve_variant(variant, learner_preset, None, set_overrides)
        if not long_runs_allowed(allow_long):
            check_run_length(resolved.config, flag)
    except ValueError as err:
        raise VariantError(f"{variant.path or variant.name}: config (on the {learner_preset} learner preset): "
                           f"{err}") from None


def learner_overrides(config: dict, where: str) -> dict:
    """``config`` checked field by field against the fields of every learner's config (and, when it names its
    learner, against that learner's: a field it does not have is one line); ``where`` starts each error line
    (a variant file's ``PATH: config``, or ``--set``). PyYAML reads ``1e-4`` (no dot) as a string, so a float
    field also takes a string that reads as a finite number."""
    kinds = field_types()
    if isinstance(config.get("algorithm"), str) and config["algorithm"] in ALGORITHMS:
        try:
            refuse_foreign_fields(config["algorithm"], config)
        except ValueError as err:
            raise VariantError(f"{where}: {err}") from None
    out = {}
    for key, value in config.items():
        if key == "seed":
            # every run sets it (egosearch train --seed, the DAG's seeds), so a variant's would never be read
            raise VariantError(f"{where}: seed is set per run (`egosearch train --seed`, the preset's seeds in "
                               "the workflow config), not by a variant or --set: leave it out")
        if key not in kinds:
            close = difflib.get_close_matches(str(key), kinds, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise VariantError(f"{where}: {key!r} is not a LearnerConfig field{hint}")
        kind = kinds[key]
        if kind == "float" and isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                pass
        expected = {"int": int, "float": (int, float), "str": str, "bool": bool}.get(kind)
        if expected is not None and (isinstance(value, bool) and kind != "bool" or not isinstance(value, expected)):
            raise VariantError(f"{where}: {key}={value!r} is not {'an' if kind == 'int' else 'a'} {kind}")
        if kind == "float" and not math.isfinite(value):
            raise VariantError(f"{where}: {key}={value!r} is not a finite number")
        out[key] = value
    return out


def _check_env_id_agrees(env_id: str, config: dict, path: Path) -> None:
    """The variant's ``config`` does not turn off what its ``env_id`` names: ``observed_env_id`` adds the memory
    or the decisions of a field set true, but never takes away those of the id, so a memory id with
    ``target_memory: false`` trained with the memory while ``config show`` said false."""
    try:
        options = env_options(env_id)
    except ValueError:
        return  # an env of the user's own: the two fields cannot change it (observed_env_id)
    memory = options.target_memory or options.floor_map
    plain = EnvOptions(head=options.head).env_id  # the body env of the same head, with neither
    contradictions = []
    if memory and config.get("target_memory") is False:
        contradictions.append(("target_memory: false", "observes the last-seen target memory",
                               f"target_memory: true or leave it out, or env_id {plain}"))
    if memory and config.get("modular_searcher") is True:
        contradictions.append(("modular_searcher: true", "is a body env (the policy acts at every body step)",
                               f"leave modular_searcher out, or env_id {plain}"))
    if options.modular and config.get("modular_searcher") is False:
        contradictions.append(("modular_searcher: false", "is a modular searcher's decision env",
                               f"modular_searcher: true or leave it out, or env_id {plain}"))
    if options.modular and config.get("target_memory") is True:
        contradictions.append(("target_memory: true", "is a modular searcher's decision env, which has no target "
                               "memory", "target_memory: false or leave it out"))
    if contradictions:
        setting, what, allowed = contradictions[0]
        raise VariantError(f"{path}: config: {setting} contradicts env_id: {env_id}, which {what}; allowed: {allowed}")


def _check_homes(train_env: dict, path: Path) -> None:
    """``layout: generated`` comes with ``home_seeds`` (and only then), a split that spares the held-out homes."""
    generated, seeds = train_env["layout"] == "generated", train_env.get("home_seeds")
    if generated != (seeds is not None):
        raise VariantError(f"{path}: train_env: " + ("layout: generated needs home_seeds: [first, stop)" if generated
                                                    else "home_seeds is only read with layout: generated"))
    if generated:
        try:
            check_home_split(seeds)
        except ValueError as err:
            raise VariantError(f"{path}: train_env: {err}") from None


def _check_objects(names: list[str], path: Path) -> None:
    if not names:
        return
    # local: the object catalogue loads trimesh (~2 s), which the Snakefile's checks need only here
    from egosearch.scene.objects import TARGET_OBJECTS

    unknown = [n for n in names if n not in TARGET_OBJECTS]
    if unknown:
        raise VariantError(f"{path}: train_env/objects: {', '.join(map(repr, unknown))} unknown; "
                           f"allowed: {', '.join(sorted(TARGET_OBJECTS))}")


def new_variant(name: str, template: str = "head_on", directory: Path = ABLATIONS_DIR) -> Path:
    """Write ``<directory>/<name>.yaml``: a copy of ``template`` with ``name:`` set, ready to edit."""
    if not re.fullmatch(r"[A-Za-z0-9_\-]+", name):
        raise VariantError(f"variant name {name!r}: use letters, digits, '_' and '-' only (it names output folders)")
    if name in searchers.SEARCHERS:
        raise VariantError(f"variant name {name!r} is a reference searcher's, whose evaluations sit in the same "
                           f"folders: name the variant otherwise (taken: {', '.join(searchers.names())})")
    path = _shown(Path(directory) / f"{name}.yaml")
    if path.exists():
        raise VariantError(f"{path} exists already; edit it, or choose another name")
    base = load_variant(template, directory)
    data = {"name": name, "description": f"{template} with ... (say what this variant changes)",
            "env_id": base.env_id, "train_env": base.train_env, "config": base.config}
    path.write_text(
        f"# A variant of {template}: edit what differs. env_id: EgoSearch-v0 (head on) or EgoSearchNoHead-v0;\n"
        "# train_env: the training home and placement scheme; config: run settings (egosearch/rl/run_settings.py)\n"
        "# and the learner's own fields (egosearch/rl/*_settings.py) overridden on top of the preset.\n"
        + yaml.safe_dump(data, sort_keys=False, default_flow_style=False))
    try:
        load_variant(path)
    except VariantError:
        # a refused variant leaves no file: later `allowed:` lists would name it
        path.unlink()
        raise
    return path
