"""Variants as data: one YAML file per variant in ``ablations/``.

Adding a variant is adding a file; nothing else changes. A file is validated against
``egosearch/workflow/variant.schema.json`` and its ``config`` against the learner's config, so a
typo is one clear line before any job starts.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import yaml

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
    """``EgoSearch-v0`` (head on) or ``EgoSearchNoHead-v0`` (head off)."""
    train_env: dict
    """Keyword arguments of the training env (layout, placement, objects)."""
    config: dict = field(default_factory=dict)
    """Learner config overrides on top of the profile."""
    description: str = ""


def variant_names(directory: Path = ABLATIONS_DIR) -> list[str]:
    return sorted(p.stem for p in Path(directory).glob("*.yaml"))


def _resolve(name_or_path: str | Path, directory: Path) -> Path:
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") and path.exists():
        return path
    candidate = Path(directory) / f"{name_or_path}.yaml"
    if not candidate.exists():
        raise VariantError(f"variant={str(name_or_path)!r} is unknown; allowed: "
                           f"{', '.join(variant_names(directory))} (files in {directory})")
    return candidate


def load_variant(name_or_path: str | Path, directory: Path = ABLATIONS_DIR) -> Variant:
    """The variant named ``name`` (``ablations/<name>.yaml``) or stored at a path."""
    import jsonschema

    path = _resolve(name_or_path, directory)
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        raise VariantError(f"{path}: not valid YAML ({str(err).splitlines()[0]})") from None
    schema = json.loads(SCHEMA_PATH.read_text())
    try:
        jsonschema.validate(data, schema)
    except jsonschema.ValidationError as err:
        where = "/".join(str(p) for p in err.absolute_path) or "(top level)"
        raise VariantError(f"{path}: {where}: {err.message}") from None
    if data["name"] != path.stem:
        raise VariantError(f"{path}: name={data['name']!r} must equal the file name {path.stem!r}")
    return Variant(name=data["name"], env_id=data["env_id"], train_env=dict(data["train_env"]),
                   config=dict(data.get("config") or {}), description=data.get("description", ""))
