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

#: The modular searcher's high level (egosearch.searchers.modular): one step is one decision of where to
#: explore and how to sweep the head; the frontier searcher walks the body. A change of observation and of
#: what is learned (never the paper's).
MODULAR_ENV_IDS = {
    "EgoSearchModular-v0": {"head": True},
    "EgoSearchNoHeadModular-v0": {"head": False},
}

MODULAR_MAP_CELLS = 12
"""Side of the egocentric map the modular searcher's high level reads (squares)."""
MODULAR_MAP_CELL_SIZE = 0.5
"""Side of its squares (m): the map covers 6 m x 6 m around the body."""
MODULAR_MAP_DIM = 3 * MODULAR_MAP_CELLS * MODULAR_MAP_CELLS
"""Values the map appends to ``mask`` in the ``*Modular-v0`` envs."""


def modular_decision_dim(head: bool) -> int:
    """Values of one decision of the modular searcher: the goal point (forward, left) and, with the head,
    the sweep (yaw amplitude, pitch centre); each in [-1, 1]."""
    return 4 if head else 2


BODY_ENV_IDS = {"EgoSearchModular-v0": "EgoSearch-v0", "EgoSearchNoHeadModular-v0": "EgoSearchNoHead-v0"}
"""The body env of each decision env: where ``egosearch.searchers.modular.ModularPolicy`` acts step by step."""

ALL_ENV_IDS = (*ENV_IDS, *MODULAR_ENV_IDS)
"""Every id a policy may be trained and evaluated in."""

for _env_id, _kwargs in ENV_IDS.items():
    if _env_id not in registry:
        # SearchEnv enforces T_max itself (truncated=True at step 100), so no TimeLimit wrapper.
        register(id=_env_id, entry_point="egosearch.sim.env:SearchEnv", kwargs=dict(_kwargs))
for _env_id, _kwargs in MODULAR_ENV_IDS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point="egosearch.searchers.modular:ModularSearchEnv", kwargs=dict(_kwargs))


def env_space_dims(env_id: str) -> dict[str, int]:
    """``{"action", "mask", "proprio"}`` sizes of a registered id, without building its env."""
    # local: registering the ids must not load pybullet and the sensor (the Snakefile's checks import this)
    from egosearch.sim.env import space_dims

    if env_id in MODULAR_ENV_IDS:
        from egosearch.sim.env import MASK_FEATURE_DIM

        head = MODULAR_ENV_IDS[env_id]["head"]
        return {**space_dims(head), "action": modular_decision_dim(head), "mask": MASK_FEATURE_DIM + MODULAR_MAP_DIM}
    return space_dims(**ENV_IDS[env_id])


def observed_env_id(env_id: str, target_memory: bool, modular_searcher: bool = False) -> str:
    """The id a policy trains and is evaluated in: ``env_id``, or with ``target_memory`` (a learner
    config field that changes the observation) its ``*Memory-v0`` form of the same head, with
    ``modular_searcher`` (one that changes what is learned) its ``*Modular-v0`` form."""
    if modular_searcher and env_id in ENV_IDS:
        return "EgoSearchModular-v0" if ENV_IDS[env_id]["head"] else "EgoSearchNoHeadModular-v0"
    if not target_memory or env_id not in ENV_IDS or ENV_IDS[env_id].get("target_memory"):
        return env_id
    return "EgoSearchMemory-v0" if ENV_IDS[env_id]["head"] else "EgoSearchNoHeadMemory-v0"
