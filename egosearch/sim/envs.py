"""Every gymnasium id egosearch provides, registered in one place (``import egosearch.sim.envs``)."""

from gymnasium.envs.registration import register, registry

#: id -> fixed keyword arguments of :class:`egosearch.sim.env.SearchEnv`.
ENV_IDS = {
    "EgoSearch-v0": {"head": True},
    "EgoSearchNoHead-v0": {"head": False},
    # A change of observation (never the paper's): the last-seen target memory (SearchEnv docs).
    "EgoSearchMemory-v0": {"head": True, "target_memory": True},
    "EgoSearchNoHeadMemory-v0": {"head": False, "target_memory": True},
    # ... and the egocentric floor map built from its depth frames and pose (also a change of observation).
    "EgoSearchMap-v0": {"head": True, "target_memory": True, "floor_map": True},
    "EgoSearchNoHeadMap-v0": {"head": False, "target_memory": True, "floor_map": True},
}

for _env_id, _kwargs in ENV_IDS.items():
    if _env_id not in registry:
        # SearchEnv enforces T_max itself (truncated=True at step 100), so no TimeLimit wrapper.
        register(id=_env_id, entry_point="egosearch.sim.env:SearchEnv", kwargs=dict(_kwargs))


def env_space_dims(env_id: str) -> dict[str, int]:
    """``{"action", "mask", "proprio"}`` sizes of a registered id, without building its env."""
    # local: registering the ids must not load pybullet and the sensor (the Snakefile's checks import this)
    from egosearch.sim.env import space_dims

    return space_dims(**ENV_IDS[env_id])


def observed_env_id(env_id: str, target_memory: bool) -> str:
    """The id a policy trains and is evaluated in: ``env_id``, or with ``target_memory`` (a learner
    config field that changes the observation) its ``*Memory-v0`` form of the same head."""
    if not target_memory or env_id not in ENV_IDS or ENV_IDS[env_id].get("target_memory"):
        return env_id
    return "EgoSearchMemory-v0" if ENV_IDS[env_id]["head"] else "EgoSearchNoHeadMemory-v0"
