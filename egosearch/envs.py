"""Every gymnasium id egosearch provides, registered in one place (``import egosearch.envs``)."""

from gymnasium.envs.registration import register, registry

#: id -> fixed keyword arguments of :class:`egosearch.env.SearchEnv`.
ENV_IDS = {
    "EgoSearch-v0": {"head": True},
    "EgoSearchNoHead-v0": {"head": False},
}

for _env_id, _kwargs in ENV_IDS.items():
    if _env_id not in registry:
        # SearchEnv enforces T_max itself (truncated=True at step 100), so no TimeLimit wrapper.
        register(id=_env_id, entry_point="egosearch.env:SearchEnv", kwargs=dict(_kwargs))
