"""The body env ids' entry points (``gymnasium.make("EgoSearch-v0", ...)`` calls one): each checks its id's
options (:func:`egosearch.sim.body_envs.check_body_options`) before it builds :class:`egosearch.sim.env.SearchEnv`.
A module of their own, named by the registrations as a string, so that registering the ids
(:mod:`egosearch.sim.body_envs`) loads neither the physics nor this module."""

from egosearch.sim.body_envs import BODY_METADATA, ENV_IDS, check_body_options
from egosearch.sim.env import SearchEnv


def _entry_point(env_id: str):
    def make(**kwargs):
        check_body_options(env_id, kwargs)
        return SearchEnv(**kwargs)

    make.__name__ = make.__qualname__ = env_id.replace("-", "_")
    make.__doc__ = f"{env_id}: :class:`egosearch.sim.env.SearchEnv` with {ENV_IDS[env_id]}, its options checked."
    make.metadata = BODY_METADATA
    return make


for _env_id in ENV_IDS:
    globals()[_env_id.replace("-", "_")] = _entry_point(_env_id)
