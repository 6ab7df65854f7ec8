"""Every gymnasium id egosearch provides, and the env's options resolved in one place.

``import egosearch.envs`` registers them all; so does ``import egosearch`` when gymnasium is loaded, which
is how ``gymnasium.make("egosearch:EgoSearch-v0")`` finds them with no other import. Registering loads
neither the physics nor the sensor.

What a policy observes and what it learns are options (:class:`EnvOptions`): the head, the target memory,
the floor map (keyword options of the body env, :mod:`egosearch.sim.body_envs`) and the modular searcher's
decisions (its own env, :mod:`egosearch.searchers.decision_envs`). A learner config names two of them
(``target_memory``, ``modular_searcher``) and a variant its env id; :func:`observed_env_id` turns the three
into the id a run trains and is evaluated in, and :func:`env_options` any id, a stored run's included,
back into its options."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass

from egosearch.searchers.decision_envs import MODULAR_ENV_IDS, MODULAR_MAP_DIM, decision_env_id, modular_decision_dim
from egosearch.sim.body_envs import ENV_IDS, body_env_id, body_options
from egosearch.sim.observation_options import OPTIONS

ALL_ENV_IDS = (*ENV_IDS, *MODULAR_ENV_IDS)
"""Every id a policy may be trained and evaluated in."""
OBSERVATION_OPTIONS = OPTIONS.keys()
"""The body env's keyword options that change what a policy observes with no id of their own (no new id per
combination of options; a live view of :mod:`egosearch.sim.observation_options`' registry): a learner config
field of the same name sets each, the run's config records it in its actor file, and ``egosearch evaluate``
builds the actor's env with the recorded ones (:func:`observation_kwargs`; ``--env-option`` overrides them,
and an actor that does not fit is refused)."""


def observation_kwargs(config: Mapping | None) -> dict[str, bool]:
    """The observation options a learner config (its ``to_dict()``, or the one an actor file records) turns
    on, as the env's keyword arguments; those off are left out, so a config without them builds the env it
    always did."""
    return {name: True for name in OBSERVATION_OPTIONS if (config or {}).get(name)}


def parse_env_options(pairs: list[str] | None) -> dict[str, bool]:
    """``--env-option key=value`` pairs -> the env's keyword arguments; one clear line for a key not in
    :data:`OBSERVATION_OPTIONS` or a value other than true/false."""
    out: dict[str, bool] = {}
    given: dict[str, str] = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        if not sep or key not in OBSERVATION_OPTIONS:
            raise ValueError(f"--env-option {pair!r}: KEY=true|false with KEY one of {', '.join(OBSERVATION_OPTIONS)}")
        if value.lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"--env-option {pair!r}: the value is true or false, not {value!r}")
        if key in given:
            # argparse's append would let the last one win without a word
            raise ValueError(f"--env-option {key} is given twice ({given[key]}, {pair}); give each option once")
        given[key] = pair
        out[key] = value.lower() in ("true", "1")
    return out


@dataclass(frozen=True)
class EnvOptions:
    """What an env id stands for."""

    head: bool = True
    """The camera's two joints (paper 4); False: the camera fixed to the body."""
    target_memory: bool = False
    """The last-seen target memory in the observation (a change of observation)."""
    floor_map: bool = False
    """The egocentric floor map in the observation (a change of observation; comes with the memory)."""
    modular: bool = False
    """One step is one decision of where to explore and how to sweep the head, the frontier searcher
    walking the body (a change of what is learned)."""

    @property
    def env_id(self) -> str:
        """The registered id with exactly these options."""
        if self.modular:
            if self.target_memory or self.floor_map:
                raise ValueError("the modular searcher's decision env has no target memory or floor map option")
            return decision_env_id(self.head)
        return body_env_id(self.head, self.target_memory, self.floor_map)


def env_options(env_id: str) -> EnvOptions:
    """The options of a registered id; one clear line for any other."""
    if env_id in MODULAR_ENV_IDS:
        return EnvOptions(head=MODULAR_ENV_IDS[env_id]["head"], modular=True)
    if env_id in ENV_IDS:
        return EnvOptions(**body_options(env_id))
    raise ValueError(f"env id {env_id!r} is not one of egosearch's; allowed: {', '.join(ALL_ENV_IDS)}")


def observed_env_id(env_id: str, target_memory: bool, modular_searcher: bool = False) -> str:
    """The id a policy trains and is evaluated in: a variant's ``env_id`` with the two learner config fields
    that change it, ``target_memory`` (added to a body env's observation) and ``modular_searcher`` (the
    decision env of the same head). A decision env stays as it is, and so does an env of the user's own
    (registered by them: a test's fake env), which the two fields cannot change."""
    if env_id not in ALL_ENV_IDS:
        if target_memory or modular_searcher:
            raise ValueError(f"env id {env_id!r} is not one of egosearch's ({', '.join(ALL_ENV_IDS)}): the config's "
                             "target_memory and modular_searcher choose among those only; leave them off")
        return env_id
    options = env_options(env_id)
    if options.modular:
        return env_id
    if modular_searcher:
        return EnvOptions(head=options.head, modular=True).env_id
    return EnvOptions(**{**asdict(options), "target_memory": options.target_memory or bool(target_memory)}).env_id


def env_space_dims(env_id: str, env_kwargs: Mapping | None = None) -> dict[str, int]:
    """``{"action", "mask", "proprio"}`` sizes of a registered id with these observation options
    (:data:`OBSERVATION_OPTIONS`), without building its env."""
    # local: registering the ids must not load pybullet and the sensor (the Snakefile's checks import this)
    from egosearch.sim.env import MASK_FEATURE_DIM, space_dims

    options = env_options(env_id)
    observed = {k: bool(v) for k, v in (env_kwargs or {}).items() if k in OBSERVATION_OPTIONS}
    if options.modular:
        if any(observed.values()):
            unread = ", ".join(k for k, v in observed.items() if v)
            raise ValueError(f"{env_id} is a decision env: it does not read {unread}")
        return {**space_dims(options.head), "action": modular_decision_dim(options.head),
                "mask": MASK_FEATURE_DIM + MODULAR_MAP_DIM}
    return space_dims(options.head, options.target_memory, options.floor_map, **observed)
