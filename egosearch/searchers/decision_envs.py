"""The modular searcher's decision envs (:class:`egosearch.searchers.modular.ModularSearchEnv`): their ids,
the size of a decision and of the map its high level reads, registered here without loading the physics
(``import egosearch.envs`` registers every id).

One step of these envs is one decision of where to explore and how to sweep the head; the frontier
searcher walks the body. A change of observation and of what is learned (never the paper's)."""

from gymnasium.envs.registration import register, registry

MODULAR_ENV_IDS = {
    "EgoSearchModular-v0": {"head": True},
    "EgoSearchNoHeadModular-v0": {"head": False},
}
"""id -> its fixed options (``head``)."""

BODY_ENV_IDS = {"EgoSearchModular-v0": "EgoSearch-v0", "EgoSearchNoHeadModular-v0": "EgoSearchNoHead-v0"}
"""The body env of each decision env: where ``egosearch.searchers.modular.ModularPolicy`` acts step by step."""

MODULAR_MAP_CELLS = 12
"""Side of the egocentric map the modular searcher's high level reads (squares)."""
MODULAR_MAP_CELL_SIZE = 0.5
"""Side of its squares (m): the map covers 6 m x 6 m around the body."""
MODULAR_MAP_DIM = 3 * MODULAR_MAP_CELLS * MODULAR_MAP_CELLS
"""Values the map appends to ``mask`` in the decision envs."""


def modular_decision_dim(head: bool) -> int:
    """Values of one decision of the modular searcher: the goal point (forward, left) and, with the head,
    the sweep (yaw amplitude, pitch centre); each in [-1, 1]."""
    return 4 if head else 2


def decision_env_id(head: bool) -> str:
    """The decision env of a head (or of none)."""
    return "EgoSearchModular-v0" if head else "EgoSearchNoHeadModular-v0"


for _env_id, _kwargs in MODULAR_ENV_IDS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point="egosearch.searchers.modular:ModularSearchEnv", kwargs=dict(_kwargs))
