"""The body env's gymnasium ids (``import egosearch.sim.envs`` registers them; ``import egosearch.envs``
registers every id, the modular searcher's too, and resolves the env options).

One env, :class:`egosearch.sim.env.SearchEnv`; its observation is chosen by keyword options, not by id:
``gymnasium.make("EgoSearch-v0", head=False, target_memory=True)``. The ids below name the combinations
the stored runs recorded, so that every stored run keeps loading under the id it trained in."""

from gymnasium.envs.registration import register, registry

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

for _env_id, _kwargs in ENV_IDS.items():
    if _env_id not in registry:
        # SearchEnv enforces T_max itself (truncated=True at step 100), so no TimeLimit wrapper.
        register(id=_env_id, entry_point="egosearch.sim.env:SearchEnv", kwargs=dict(_kwargs))


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
