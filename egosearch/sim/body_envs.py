"""The body env's gymnasium ids (``import egosearch.sim.body_envs`` registers them; ``import egosearch.envs``
registers every id, the modular searcher's too, and resolves the env options).

One env, :class:`egosearch.sim.env.SearchEnv`; its observation is chosen by keyword options:
``gymnasium.make("EgoSearchNoHead-v0", target_memory=True)``. The ids below name the combinations the
stored runs recorded, so that every stored run keeps loading under the id it trained in. An option that
contradicts its id (``head=True`` on a NoHead id, ``target_memory=False`` on a Memory id) or a combination
no id names (``floor_map`` without ``target_memory``) is refused with a ``ValueError`` naming the option and
what is allowed (:func:`check_body_options`), before the env is built."""

from gymnasium.envs.registration import register, registry

BODY_METADATA = {"render_modes": ["rgb_array"], "render_fps": 1.0 / 0.15}
"""SearchEnv's gymnasium metadata (its ``metadata``; the entry points carry it too, for ``gymnasium.make``)."""

BODY_OPTIONS = ("head", "target_memory", "floor_map")
"""The body env's keyword options that change what it observes (and so what an actor must fit):
``head`` (the camera's two joints, in the action too), ``target_memory`` (the last-seen target memory) and
``floor_map`` (the egocentric floor map). Only ``head`` is the paper's choice; the others are changes of
observation (SearchEnv's docs)."""

#: id -> its fixed options (a subset of BODY_OPTIONS; the rest at SearchEnv's defaults).
ENV_IDS = {
    "EgoSearch-v0": {"head": True},
    "EgoSearchNoHead-v0": {"head": False},
    # ids of option combinations stored runs trained in (the same env with those options)
    "EgoSearchMemory-v0": {"head": True, "target_memory": True},
    "EgoSearchNoHeadMemory-v0": {"head": False, "target_memory": True},
    "EgoSearchMap-v0": {"head": True, "target_memory": True, "floor_map": True},
    "EgoSearchNoHeadMap-v0": {"head": False, "target_memory": True, "floor_map": True},
}

OPTION_WORDS = {"head": "the camera's two joints", "target_memory": "the last-seen target memory",
                "floor_map": "the egocentric floor map"}


def check_flag(name: str, value) -> None:
    """An on/off option is a bool (numpy's too): ``head="no"`` would otherwise read as on."""
    if type(value).__name__ not in ("bool", "bool_"):
        raise ValueError(f"{name}={value!r} is a {type(value).__name__}; allowed: True or False")


def check_body_options(env_id: str, kwargs: dict) -> None:
    """``kwargs`` (the id's registered ones with the caller's on top, as ``gymnasium.make`` merges them) do
    not contradict ``env_id``: an option the id fixes keeps its value, and the options together are a
    combination an id names (a floor map comes with the target memory)."""
    fixed = ENV_IDS[env_id]
    for name in BODY_OPTIONS:
        if name in kwargs:
            check_flag(name, kwargs[name])
    options = {"head": True, "target_memory": False, "floor_map": False, **fixed,
               **{k: bool(v) for k, v in kwargs.items() if k in BODY_OPTIONS}}
    for name, value in fixed.items():
        if options[name] != value:
            wanted = {**options, "target_memory": options["target_memory"] or options["floor_map"]}
            other = next((i for i, o in ENV_IDS.items() if body_options(i) == wanted), None)
            instead = f" ({other} is the id with {name}={options[name]})" if other else ""
            raise ValueError(f"{name}={options[name]!r} contradicts {env_id}, which fixes {name}={value} "
                             f"({OPTION_WORDS[name]} {'on' if value else 'off'}); allowed: {name}={value}, or leave "
                             f"{name} out{instead}")
    if options["floor_map"] and not options["target_memory"]:
        maps = [i for i, o in ENV_IDS.items() if o.get("floor_map")]
        raise ValueError(f"floor_map=True in {env_id} needs target_memory=True (the floor map comes with the "
                         f"target memory: {' and '.join(maps)}); allowed: floor_map with target_memory=True, or "
                         "floor_map=False")


for _env_id, _kwargs in ENV_IDS.items():
    if _env_id not in registry:
        # SearchEnv enforces T_max itself (truncated=True at step 100), so no TimeLimit wrapper. The entry
        # point is named, not imported: registering must not load the physics (egosearch.sim.env_entry).
        register(id=_env_id, entry_point=f"egosearch.sim.env_entry:{_env_id.replace('-', '_')}",
                 kwargs=dict(_kwargs))


def body_options(env_id: str) -> dict[str, bool]:
    """Every option of :data:`BODY_OPTIONS` for a body env id (those it does not fix at their default, off)."""
    if env_id not in ENV_IDS:
        raise ValueError(f"env id {env_id!r} is not a body env; allowed: {', '.join(ENV_IDS)}")
    return {"head": True, "target_memory": False, "floor_map": False, **ENV_IDS[env_id]}


def body_env_id(head: bool = True, target_memory: bool = False, floor_map: bool = False) -> str:
    """The registered id whose fixed options are exactly these (a floor map comes with the target memory)."""
    wanted = {"head": bool(head), "target_memory": bool(target_memory or floor_map), "floor_map": bool(floor_map)}
    for env_id in ENV_IDS:
        if body_options(env_id) == wanted:
            return env_id
    raise AssertionError(f"no id for {wanted}")  # ENV_IDS covers every combination body_env_id can ask for
