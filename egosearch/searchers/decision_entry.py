"""The modular searcher's decision env ids' entry points: each checks its id's options
(:func:`egosearch.searchers.decision_envs.check_decision_options`) before it builds
:class:`egosearch.searchers.modular.ModularSearchEnv`. A module of their own, named by the registrations as a
string, so that registering the ids (:mod:`egosearch.searchers.decision_envs`) loads neither the physics nor
this module."""

from egosearch.searchers.decision_envs import MODULAR_ENV_IDS, check_decision_options
from egosearch.searchers.modular import ModularSearchEnv


def _entry_point(env_id: str):
    def make(**kwargs):
        check_decision_options(env_id, kwargs)
        return ModularSearchEnv(**kwargs)

    make.__name__ = make.__qualname__ = env_id.replace("-", "_")
    make.__doc__ = f"{env_id}: :class:`egosearch.searchers.modular.ModularSearchEnv` with {MODULAR_ENV_IDS[env_id]}."
    make.metadata = {"render_modes": []}
    return make


for _env_id in MODULAR_ENV_IDS:
    globals()[_env_id.replace("-", "_")] = _entry_point(_env_id)
