"""A learner's config: the run settings every learner shares, composed with the learner's own settings;
the presets (smoke, cpu, paper); and Table 2, generated from a config.

A training's config is :class:`LearnerConfig`: the :class:`egosearch.rl.run_settings.RunSettings` (env
steps, envs, evaluation, checkpoints, device, ...), the observation options' fields, and the settings class
registered with its learner in :mod:`egosearch.rl.learner_registry` (SAC + CURL's
:mod:`egosearch.rl.sac_curl_settings`, SAC-DrQ's :mod:`egosearch.rl.sac_drq_settings`, ..., with the
training aids it opts into, :mod:`egosearch.rl.training_aids`), composed
into one flat dataclass per learner (``LearnerConfig(algorithm="sac_drq")`` is a ``SacDrqConfig``). A
learner reads its own fields and the shared ones, and has no other: a value for a field its learner does
not have is one ``ValueError`` naming the field, the learner and the fields it has, raised when the config
is built, before any work. Each field carries its own docstring saying where the value comes from — "Table
2" (the paper, Appendix A), "CURL" (the defaults of the reference code of Srinivas et al. 2020,
github.com/MishaLaskin/curl, which Table 2 follows almost line by line) or "ours" (engineering choices of
this project that do not change the algorithm).

Presets (:mod:`egosearch.rl.presets`, data) are named value sets applied on top of the defaults:

- ``paper``: Table 2 exactly (and CURL's defaults for what Table 2 does not list);
- ``cpu``:   the default: a cheaper learner (SAC with a DrQ-v2-style update, not CURL) and
  training-only aids, so that policies search within the 2-core machine's budget (see
  :func:`cpu_preset` for what it changes and the measurements behind it);
- ``smoke``: a training run that finishes in seconds, to exercise the plumbing.

``table2_rows(cfg)`` renders a config as the (parameter, setting) rows of Table 2, in the
paper's order and wording, so the table in the report is generated, not typed;
``departure_rows(cfg)`` lists where it departs from the paper, with each field's docstring.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
from dataclasses import dataclass, fields
from typing import Any

from egosearch.rl.learner_registry import ALGORITHMS, LEARNERS, learner  # the registered learners and their settings
from egosearch.rl.network_settings import ACTIVATIONS, NetworkSettings, PooledSettings, RandomShiftSettings, SacSettings
from egosearch.rl.presets import (
    PRESETS,
    SMOKE_LEARNER_PRESET,
    cpu_preset,
    paper_preset,
    smoke_preset,
    smoke_sized,
)
from egosearch.rl.run_settings import (
    BODY_STEPS,
    CURRICULUM_END_RADIUS,
    CURRICULUM_START_RADIUS,
    DECISIONS,
    DISTANCE_REWARDS,
    RunSettings,
)
from egosearch.rl.training_aids import DEMO_TEACHERS, TRAINING_AIDS
from egosearch.sim.observation_options import OPTIONS

DEFAULT_ALGORITHM: str = RunSettings.algorithm
"""The learner a config that names none gets (``RunSettings.algorithm``'s default: the paper's)."""

_ACTIVATION_LABELS = {"relu": "ReLU", "elu": "ELU", "leaky_relu": "LeakyReLU", "gelu": "GELU",
                      "tanh": "Tanh"}

_BUILDING_BLOCKS = (NetworkSettings, SacSettings, PooledSettings, RandomShiftSettings)
"""The settings classes the learners' own are made of (their fields are documented there)."""

def option_settings() -> tuple[type, ...]:
    """The settings classes of the registered observation options (:mod:`egosearch.sim.observation_options`):
    one bool field each, which every learner's config has beside the run settings."""
    return tuple(entry.settings_class() for entry in OPTIONS.values())


def shared_fields() -> tuple[str, ...]:
    """The fields every learner's config has: the run settings' and the observation options', as declared."""
    return tuple(f.name for klass in (RunSettings, *option_settings()) for f in fields(klass))


def field_order() -> tuple[str, ...]:
    """The order fields are shown in (the departures from the paper in the generated Table 2 pages,
    ``egosearch config show``): the run settings' as declared (Table 2's observation and data first), each
    training aid's right after the run-settings field it names (its ``shown_after``), the observation
    options', then each building block's and each registered learner's own, as declared. A new field has its
    place where it is written; no list to keep."""
    names = []
    for name in (f.name for f in fields(RunSettings)):
        names += [name, *(f.name for aid in TRAINING_AIDS if aid.shown_after == name for f in fields(aid))]
    names += [f.name for klass in settings_classes() for f in fields(klass)]
    return tuple(dict.fromkeys(names))


@dataclass
class LearnerConfig(RunSettings):
    """Hyper-parameters of one training run, whichever learner ``algorithm`` names (paper 4.2 and
    Table 2): the run settings and the learner's own, composed (``LearnerConfig(algorithm=...)`` builds
    that learner's config class, :func:`config_class`). Checkpoints, config.json and actor files store it
    as a plain dict (:meth:`to_dict`), never as a pickled class, so renaming it does not touch stored runs."""

    def __new__(cls, *args: Any, **values: Any) -> LearnerConfig:
        if cls is LearnerConfig:  # the composed class of the learner named (SAC + CURL, the paper's, by default)
            cls = config_class(values.get("algorithm", DEFAULT_ALGORITHM))
        return super().__new__(cls)

    def validate(self) -> LearnerConfig:
        """Raise ``ValueError`` (one line naming the field and its allowed range) if any value
        is out of range; return ``self`` otherwise. The run settings' checks come first, then those of
        each settings class the learner's own are made of."""

        def bad(name: str, allowed: str) -> None:
            raise ValueError(f"LearnerConfig.{name}={getattr(self, name)!r} is out of range; "
                             f"allowed: {allowed}")

        for f in fields(self):
            value = getattr(self, f.name)
            expected = {"int": int, "float": (int, float), "str": str, "bool": bool}[f.type]
            if isinstance(value, bool) and f.type != "bool" or not isinstance(value, expected):
                raise ValueError(f"LearnerConfig.{f.name}={value!r} has the wrong type; "
                                 f"expected {f.type}")
            if f.type == "float" and not math.isfinite(value):
                bad(f.name, "a finite number")
        if self.algorithm != _ALGORITHM_OF.get(type(self), self.algorithm):
            bad("algorithm", f"{_ALGORITHM_OF[type(self)]} (this is {type(self).__name__})")
        RunSettings.own_checks(self, bad)
        for name in OPTIONS:
            if self.modular_searcher and getattr(self, name):
                bad(name, "False with modular_searcher (the frontier searcher walks the body; the decision env does "
                          "not read the option)")
        for klass in reversed(type(self).__mro__):
            if klass not in (RunSettings, LearnerConfig) and "own_checks" in vars(klass):
                vars(klass)["own_checks"](self, bad)
        return self

    def to_dict(self) -> dict[str, Any]:
        """Plain-python dict (JSON / ``torch.load(weights_only=True)`` safe): the run settings and the
        learner's own, flat, as config.json has always stored them."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> LearnerConfig:
        """Inverse of :meth:`to_dict`; a field the learner ``values["algorithm"]`` does not have is a one-line
        ``ValueError``."""
        klass = config_class(values.get("algorithm", DEFAULT_ALGORITHM))
        _refuse_foreign(klass, values)
        return klass(**values).validate()

    @classmethod
    def from_stored(cls, values: dict[str, Any]) -> LearnerConfig:
        """A stored run's recorded config (config.json, done.json, a checkpoint). Runs stored before the
        config was split recorded every learner's fields: those of other learners, which this one never read,
        are left out; a field the run's learner has keeps its recorded value."""
        klass = config_class(values.get("algorithm", DEFAULT_ALGORITHM))
        own = {f.name for f in fields(klass)}
        return klass(**{k: v for k, v in values.items() if k in own}).validate()


_ALGORITHM_OF: dict[type, str] = {}
"""Each composed config class -> the algorithm it is the config of."""


@functools.cache
def _composed(algorithm: str, settings: type | None, options: tuple[type, ...]) -> type[LearnerConfig]:
    # fields come run settings first, then the observation options', then the learner's own settings' (with
    # the training aids it opts into): dataclasses collect them base-most first
    bases = (*(() if settings is None else (settings,)), *options, LearnerConfig)
    name = "".join(part.capitalize() for part in algorithm.split("_")) + "Config"
    klass = dataclasses.make_dataclass(name, [("algorithm", "str", dataclasses.field(default=algorithm))],
                                       bases=bases)
    klass.__module__ = __name__
    klass.__doc__ = (f"The config of the learner {algorithm!r}: the run settings and "
                     f"{settings.__name__ if settings else 'no settings of its own'}.")
    _ALGORITHM_OF[klass] = algorithm
    globals()[name] = klass  # so that pickle finds it (multiprocessing may hand a config to a worker)
    return klass


def config_class(algorithm: str) -> type[LearnerConfig]:
    """The config class of the learner registered as ``algorithm``: the run settings and its own."""
    if algorithm not in ALGORITHMS:
        raise ValueError(f"LearnerConfig.algorithm={algorithm!r} is out of range; allowed: {', '.join(ALGORITHMS)}")
    return _composed(algorithm, learner(algorithm).settings_class(), option_settings())


def own_settings(algorithm: str) -> tuple[str, ...]:
    """The fields of ``algorithm``'s own settings (not the shared ones: the run settings and the observation
    options'), in :func:`field_order`."""
    shared = set(shared_fields())
    return tuple(n for n in field_order() if n in {f.name for f in fields(config_class(algorithm))} - shared)


def settings_classes() -> list[type]:
    """Every settings class: the run settings, the training aids, the observation options', the building blocks
    and each registered learner's own."""
    own = [entry.settings_class() for entry in LEARNERS.values()]
    classes = [RunSettings, *TRAINING_AIDS, *option_settings(), *_BUILDING_BLOCKS, *(k for k in own if k is not None)]
    return list(dict.fromkeys(classes))


def field_defaults() -> dict[str, Any]:
    """Every field of every settings class -> its default (the paper's, Table 2's or CURL's)."""
    return {f.name: f.default for klass in settings_classes() for f in fields(klass)}


def field_types() -> dict[str, str]:
    """Every field of every settings class -> its type's name ("int", "float", "str" or "bool")."""
    return {f.name: f.type for klass in settings_classes() for f in fields(klass)}


def refuse_foreign_fields(algorithm: str, values: dict[str, Any]) -> None:
    """One line (a ``ValueError``) for the first field of ``values`` that the learner ``algorithm`` does not
    have (a variant file's ``config`` is checked so when it is read)."""
    klass = config_class(algorithm)
    _refuse_foreign(klass, _without_aids_left_off(klass, values))


def _without_aids_left_off(klass: type[LearnerConfig], values: dict[str, Any]) -> dict[str, Any]:
    """``values`` less the training aids' fields that ``klass``'s learner does not have and that ``values`` set to
    their defaults (the aid off): a variant that turns the cpu preset's aids off (``head_on_from_scratch``)
    asks, at a preset whose learner has none (smoke's SAC+CURL), for what that learner already is."""
    own = {f.name for f in fields(klass)}
    off = {f.name: f.default for aid in TRAINING_AIDS for f in fields(aid) if f.name not in own}
    return {k: v for k, v in values.items() if k not in off or v != off[k]}


def _refuse_foreign(klass: type[LearnerConfig], values: dict[str, Any]) -> None:
    """One line for the first field of ``values`` that ``klass``'s learner does not have: the field, the
    learner, the learners that have it or the nearest name, and the learner's own fields."""
    own = [f.name for f in fields(klass)]
    for key in values:
        if key in own:
            continue
        algorithm = _ALGORITHM_OF[klass]
        mine = f"{algorithm} ({learner(algorithm).display_name})"
        listed = f"its own fields, beside the run settings: {', '.join(own_settings(algorithm)) or 'none'}"
        others = [name for name in LEARNERS
                  if name != algorithm and key in {f.name for f in fields(config_class(name))}]
        if others:
            raise ValueError(f"algorithm {mine} has no field {key!r} (a setting of {', '.join(others)}); {listed}")
        close = difflib.get_close_matches(str(key), own, n=1)
        hint = f" (did you mean {close[0]}?)" if close else ""
        raise ValueError(f"unknown LearnerConfig field {key!r}{hint} for algorithm {mine}; {listed}")


def load_config(preset: str = "paper", overrides: dict[str, Any] | None = None) -> LearnerConfig:
    """The config of ``preset`` with ``overrides`` on top, validated.

    A preset is for every learner: the learner takes the preset's values of the fields it has (the
    demonstration fields and ``critic_privileged_state`` only where its settings include those training aids,
    :mod:`egosearch.rl.training_aids`), so a learner pins nothing it does not use.
    An override of a field the learner does not have (but a training aid's set to its default, off), an
    unknown preset or field name and an out-of-range value are one-line ``ValueError``s.
    """
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; allowed: {', '.join(PRESETS)}")
    base, overrides = PRESETS[preset](), dict(overrides or {})
    klass = config_class(overrides.get("algorithm", base.get("algorithm", DEFAULT_ALGORITHM)))
    overrides = _without_aids_left_off(klass, overrides)
    _refuse_foreign(klass, overrides)
    own = {f.name for f in fields(klass)}
    return klass(**{**{k: v for k, v in base.items() if k in own}, **overrides}).validate()


def load_variant_config(preset: str, variant_fields: dict[str, Any] | None = None,
                        overrides: dict[str, Any] | None = None) -> LearnerConfig:
    """The config a training of a variant runs at ``preset``: the preset's, with the variant's fields
    (``variant_fields``, its file's ``config``) on top, then the caller's ``overrides`` (seed, threads).

    At ``smoke`` a variant keeps the learner and levers it has at the ``cpu`` preset (SAC-DrQ for ``head_on``,
    SAC + CURL where it pins ``sac_curl``), every size of the run capped at the smoke preset's whatever the
    variant pins (:func:`egosearch.rl.presets.smoke_sized`): so that a ``cpu`` lever runs at smoke, minutes long.
    The training, the cost line and the reading of a run's preset all take a variant's config from here."""
    variant_fields, overrides = dict(variant_fields or {}), dict(overrides or {})
    if preset != "smoke":
        return load_config(preset, {**variant_fields, **overrides})
    sized = smoke_sized(load_config(SMOKE_LEARNER_PRESET, variant_fields).to_dict())
    return load_config(preset, {**sized, **overrides})


# ---- Table 2 --------------------------------------------------------------------------------

def _num(x: float) -> str:
    """Decimal notation as printed in Table 2 (0.0001, not 1e-04)."""
    text = f"{x:.10f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


def _steps(n: int) -> str:
    return f"{_num(n / 1e6)}M"


def table2_rows(cfg: LearnerConfig) -> list[tuple[str, str]]:
    """``cfg`` as the (parameter, setting) rows of the paper's Table 2, same order and wording.

    With the ``paper`` preset this reproduces Table 2 exactly (e.g. ("Batch-size", "32"),
    ("Replay buffer", "100000"), ("Number of training steps", "0.75M")). A row whose setting the learner
    does not have (PPO has no temperature) reads "none".
    """
    act = _ACTIVATION_LABELS

    def num(name: str) -> str:
        return _num(getattr(cfg, name)) if hasattr(cfg, name) else "none"

    def plain(name: str) -> str:
        return str(getattr(cfg, name)) if hasattr(cfg, name) else "none"

    return [
        ("Image Size", f"{cfg.image_size}x{cfg.image_size}"),
        ("Augmentation", f"Random Crop ({cfg.crop_size}x{cfg.crop_size})" if hasattr(cfg, "crop_size") else
         f"Random Shift (±{getattr(cfg, 'aug_pad', 0)} px at {cfg.image_size // cfg.obs_downsample}x"
         f"{cfg.image_size // cfg.obs_downsample})"),
        ("Image History Buffer Size", str(cfg.frame_history)),
        ("Head History Buffer Size", str(cfg.head_history)),
        ("Replay buffer", str(cfg.replay_capacity)),
        ("Discount rate γ", _num(cfg.gamma)),
        ("Number of training steps", _steps(cfg.total_env_steps)),
        ("Batch-size", str(cfg.batch_size)),
        ("Alpha (SAC) : initial temperature", num("init_temperature")),
        ("Alpha (SAC) : learning rate", num("alpha_lr")),
        ("Alpha (SAC) : optimizer β1", num("alpha_beta1")),
        ("Alpha (SAC) : optimizer β2", num("alpha_beta2")),
        ("Actor : learning rate", _num(cfg.actor_lr)),
        ("Actor : optimizer β1", _num(cfg.actor_beta1)),
        ("Actor : optimizer β2", _num(cfg.actor_beta2)),
        ("Actor : Number of layers", str(cfg.actor_num_layers)),
        ("Actor : Hidden dim", str(cfg.actor_hidden_dim)),
        ("Actor : Activation function", act[cfg.actor_activation]),
        ("Critic : learning rate", _num(cfg.critic_lr)),
        ("Critic : τ (polyak averaging)", num("critic_tau")),
        ("Critic : optimizer β1", _num(cfg.critic_beta1)),
        ("Critic : optimizer β2", _num(cfg.critic_beta2)),
        ("Critic : Number of layers", str(cfg.critic_num_layers)),
        ("Critic : Hidden dim", str(cfg.critic_hidden_dim)),
        ("Critic : Activation function", act[cfg.critic_activation]),
        ("Encoder (CNN) : learning rate", num("encoder_lr")),
        ("Encoder (CNN) : τ (polyak averaging)", num("encoder_tau") if hasattr(cfg, "encoder_tau") else
         f"none ({learner(cfg.algorithm).display_name} has no target encoder)"),
        ("Encoder (CNN) : Number of layers", plain("encoder_num_layers")),
        ("Encoder (CNN) : Number of filters", plain("encoder_num_filters")),
        ("Encoder (CNN) : Latent dimension", plain("encoder_latent_dim")),
        ("Encoder (CNN) : Activation function", act[cfg.encoder_activation]),
    ]


HOUSEKEEPING_FIELDS = frozenset({"eval_every", "eval_episodes", "log_every", "checkpoint_every", "seed", "device",
                                  "num_threads", "channels_last", "compile", "cuda_graph",
                                  "keep_checkpoint", "actor_snapshot_every"})
"""Fields that change how a run is watched, saved or placed on the machine, never what it learns."""


RESUMABLE_FIELDS = ("device", "num_threads", "compile", "cuda_graph", "keep_checkpoint")
"""Config fields that may differ between a checkpoint and the run resuming it."""


def identity_set(set_overrides: dict[str, Any]) -> dict[str, Any]:
    """The command line's ``--set`` overrides that make a training another training: all but the fields a resume
    may change (:data:`RESUMABLE_FIELDS`: ``--set num_threads=2`` on resume is the same run)."""
    return {k: v for k, v in set_overrides.items() if k not in RESUMABLE_FIELDS}


def format_set(set_overrides: dict[str, Any]) -> str:
    """``--set`` overrides as the command line gives them: ``batch_size=64,actor_lr=0.0001``."""
    return ",".join(f"{key}={value}" for key, value in set_overrides.items())


def field_docs() -> dict[str, str]:
    """Each config field's docstring (the string literal under it in its settings class's source)."""
    import ast
    import inspect
    import textwrap

    docs = {}
    for klass in settings_classes():
        body = ast.parse(textwrap.dedent(inspect.getsource(klass))).body[0].body
        for node, after in zip(body, body[1:]):
            if (isinstance(node, ast.AnnAssign) and isinstance(after, ast.Expr)
                    and isinstance(after.value, ast.Constant) and isinstance(after.value.value, str)
                    and node.target.id in field_defaults()):
                docs[node.target.id] = " ".join(after.value.value.split())
    return docs


def departure_rows(cfg: LearnerConfig) -> list[tuple[str, str, str, str]]:
    """(field, this config's value, the paper's value, where each comes from) for every field that
    differs from the paper preset, housekeeping fields excepted: what a preset changes, generated.
    The paper's value of a field is its default (the ``paper`` preset sets housekeeping alone)."""
    paper, docs = field_defaults(), field_docs()
    rows = []
    for name in sorted((f.name for f in fields(cfg)), key=field_order().index):
        mine, theirs = getattr(cfg, name), paper[name]
        if name in HOUSEKEEPING_FIELDS or mine == theirs:
            continue
        rows.append((name, str(mine), str(theirs), docs.get(name, "")))
    return rows


def declaring_class(name: str, klass: type) -> type:
    """The settings class whose body declares field ``name`` among ``klass``'s bases (the file to read it in);
    a composed config only restates ``algorithm``'s default, so the search starts below it."""
    for base in klass.__mro__:
        if base not in _ALGORITHM_OF and name in vars(base).get("__annotations__", {}):
            return base
    raise ValueError(f"{name!r} is no field of {klass.__name__}")


ABBREVIATIONS = frozenset({"e.g", "i.e", "eq", "al", "cf", "vs", "fig", "etc", "approx", "resp", "no"})
"""Words whose dot ends no sentence (``e.g.``, ``et al.``, ``eq. 2``)."""


def first_sentence(doc: str) -> str:
    """``doc``'s whole first sentence: up to the first ". " outside brackets whose word is no abbreviation
    (:data:`ABBREVIATIONS`) and whose next word does not start with a digit or a small letter (``eq. 2``,
    ``0.5``); all of ``doc`` when none does."""
    depth = 0
    for i, char in enumerate(doc):
        depth += {"(": 1, "[": 1, ")": -1, "]": -1}.get(char, 0)
        if char != "." or depth > 0 or doc[i + 1:i + 2] != " ":
            continue
        word = doc[:i].rsplit(None, 1)[-1].lstrip("(\"'`").lower() if doc[:i].strip() else ""
        following = doc[i + 2:i + 3]
        if word in ABBREVIATIONS or not following or following.isdigit() or following.islower():
            continue
        return doc[:i + 1]
    return doc.rstrip(".") + "." if doc else ""


def config_sources(algorithm: str, preset: str, variant_overrides: dict[str, Any] | None = None,
                   variant: str = "", set_overrides: dict[str, Any] | None = None) -> list[dict[str, str]]:
    """Every field of ``algorithm``'s config at ``preset`` (with a variant's overrides on top, and the command
    line's ``--set`` overrides on top of those), in :func:`field_order`: its value, where the value comes from
    (the field's default, the preset, the variant, ``--set``), the paper's value, the settings class and module
    that declare it, its docstring's first sentence (``doc``) and its whole docstring (``doc_full``). What
    ``egosearch config show`` prints."""
    overrides = {**(variant_overrides or {}), **(set_overrides or {}), "algorithm": algorithm}
    cfg = load_variant_config(preset, {**(variant_overrides or {}), "algorithm": algorithm}, set_overrides)
    # at smoke a variant has its cpu config, each size capped (load_variant_config): the cpu preset is its base
    base_preset = SMOKE_LEARNER_PRESET if preset == "smoke" else preset
    uncapped = load_config(base_preset, overrides) if preset == "smoke" else cfg
    base, paper, docs = PRESETS[base_preset](), field_defaults(), field_docs()
    rows = []
    for name in sorted((f.name for f in fields(cfg)), key=field_order().index):
        owner = declaring_class(name, type(cfg))
        if getattr(cfg, name) != getattr(uncapped, name):
            source = "smoke cap"
        elif name in (set_overrides or {}):
            source = "--set"
        elif name in (variant_overrides or {}):
            source = f"variant {variant}".strip()
        elif name == "algorithm":
            source = "asked"
        elif name in base:
            source = f"preset {base_preset}"
        else:
            source = "default"
        doc = docs.get(name, "")
        first = first_sentence(doc)
        rows.append({"field": name, "value": repr(getattr(cfg, name)), "source": source,
                     "paper": repr(paper[name]), "declared_in": f"{owner.__module__}.{owner.__name__}", "doc": first,
                     "doc_full": doc})
    return rows


TABLE2_PAPER: tuple[tuple[str, str], ...] = tuple(table2_rows(LearnerConfig()))
"""Table 2 as printed in the paper (the ``paper`` preset rendered by :func:`table2_rows`)."""

__all__ = ["ACTIVATIONS", "ALGORITHMS", "BODY_STEPS", "CURRICULUM_END_RADIUS", "CURRICULUM_START_RADIUS",
           "DECISIONS", "DEMO_TEACHERS", "DISTANCE_REWARDS", "HOUSEKEEPING_FIELDS", "PRESETS",
           "RESUMABLE_FIELDS",
           "TABLE2_PAPER", "LearnerConfig", "config_class", "config_sources", "cpu_preset", "declaring_class",
           "departure_rows", "field_defaults", "field_docs", "field_order", "field_types", "first_sentence",
           "format_set", "identity_set", "load_config", "load_variant_config",
           "own_settings", "paper_preset", "refuse_foreign_fields", "settings_classes", "smoke_preset", "table2_rows"]
