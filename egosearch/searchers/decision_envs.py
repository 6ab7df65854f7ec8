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


ID_OPTIONS_UNREAD = {"target_memory": "EgoSearchMemory-v0", "floor_map": "EgoSearchMap-v0"}
"""The body-env options with ids of their own that a decision env does not read, with the body id that does."""


def unread_options() -> dict[str, str]:
    """Body-env options a decision env does not read (its observation is the decision's: the mask's features
    and the searcher's map), with a body id that does: those above and every observation option
    (:mod:`egosearch.sim.observation_options`), which any body id reads."""
    from egosearch.sim.observation_options import option_names

    return {**ID_OPTIONS_UNREAD, **{name: "EgoSearch-v0" for name in option_names()}}


def check_decision_options(env_id: str | None, kwargs: dict) -> None:
    """``kwargs`` of a decision env (``env_id``'s registered ones with the caller's on top; None: the class
    built directly) name no option it does not read, and keep the head its id fixes."""
    from egosearch.sim.body_envs import check_flag

    where = env_id or "the modular searcher's decision env"
    for name, reader in unread_options().items():
        if name in kwargs:
            raise ValueError(f"{name}={kwargs[name]!r}: {where} does not read {name} (its observation is the "
                             f"decision's: the mask's features and the searcher's map); allowed: leave {name} out "
                             f"(a body env reads it, e.g. {reader})")
    if "head" in kwargs:
        check_flag("head", kwargs["head"])
    if env_id is not None and bool(kwargs.get("head", True)) != MODULAR_ENV_IDS[env_id]["head"]:
        fixed = MODULAR_ENV_IDS[env_id]["head"]
        other = decision_env_id(not fixed)
        raise ValueError(f"head={kwargs['head']!r} contradicts {env_id}, which fixes head={fixed} (the camera's two "
                         f"joints {'on' if fixed else 'off'}); allowed: head={fixed}, or leave head out ({other} is "
                         f"the id with head={not fixed})")


for _env_id, _kwargs in MODULAR_ENV_IDS.items():
    if _env_id not in registry:
        # named, not imported: registering must not load the physics (egosearch.searchers.decision_entry)
        register(id=_env_id, entry_point=f"egosearch.searchers.decision_entry:{_env_id.replace('-', '_')}",
                 kwargs=dict(_kwargs))
