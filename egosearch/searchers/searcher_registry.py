"""The searchers that are not learned, by name: ``egosearch evaluate --policy NAME`` -> the policy it
makes and the env it acts in, and what the tables, figures and workflow say of it.

:data:`SEARCHERS` holds one :class:`Searcher` per name, in registration order; :func:`names` is every
name ``--policy`` takes besides ``actor`` (a trained actor, with ``--weights``), :func:`bounds` the
rows Table 1 sets beside each policy. A searcher's evaluations sit where a variant's would
(``results/<preset>/eval/<name>/``), so no variant may take one of these names. Adding a searcher is
one module with its policy (``reset(seed=None)`` and ``act(obs)``:
:class:`egosearch.searchers.policies.Policy`) and one :func:`register` line below; the CLI, Table 1,
the path-length report, Figure 6, the workflow's checks and the Snakemake rules read this registry.

``frontier_tuned`` and ``frontier_tuned_head_off`` (:mod:`egosearch.searchers.frontier_tuned`, tuned on
training-side sets only) are bound rows of their own, beside the untuned classical rows, which stay Table 1's
classical reference.

Every stage may read this module, the report layer and the workflow included (tests/test_layout.py
allows it, and only it, of searchers/): it imports nothing of egosearch but the registry helper
(:mod:`egosearch.core.named_registry`, which the learners' registry uses too) and no package outside the standard
library, so reading it never loads the simulator. Factories are named ``"module:attribute"`` and imported on
first use, as :mod:`egosearch.rl.learner_registry` names its learners.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from egosearch.core.named_registry import Registry, resolve

FLOOR, BESIDE, CEILING = "floor", "beside", "ceiling"
"""Where a bound's rows stand in Table 1: the floor before the policy and the ceiling after every other
row, both shown (as "not run") even without files; the others after the policy, shown once run."""
TABLE_ROWS = (FLOOR, BESIDE, CEILING)
ACTOR = "actor"
"""``--policy actor``: a trained actor (``--weights``), the one ``--policy`` that is no registered searcher."""


@dataclass(frozen=True)
class Searcher:
    """One registered searcher.

    ``name``: its ``--policy`` and the folder of its results; ``factory``: a callable (or
    ``"module:attribute"``) that makes its policy for an env, ``factory(env)``, or with ``takes_seed``
    ``factory(env, seed=seed)`` (``--seed``: the random searchers draw from it); ``env_id``: the env it
    acts in unless ``--env-id`` names another; ``head``: the head its name says, moving (True) or fixed
    (False), which ``--env-id`` must agree with (None: it acts with either; ``env_id`` must agree too);
    ``label`` and ``what``: its short name and one sentence in the tables (Table 1's rows and note, the
    path-length table); ``help``: its words in ``egosearch evaluate --help`` (searchers in a row with
    the same words are listed together); ``bound``: a Table 1 row beside each policy (and the
    path-length report's), on the same scenario sets, its rows placed by ``table_row``
    (:data:`FLOOR`, :data:`BESIDE` or :data:`CEILING`); ``classical``: config ``claims_pairs`` may name
    it (traced by the ``trace_bound`` rule); ``floor_of``: the decision env (``*Modular-v0``) whose
    trained high level is read against it (the ``decisions_floor`` rule); ``path_style``: its line in
    the path-length figure, (colour, line style, marker), None for its default line; ``fig6_level``: a
    horizontal line in Figure 6, (label, line style, colour), None for none; ``options``: keyword arguments
    its factory is called with, as ``(name, value)`` pairs (a memory window: ``(("memory_window", 5),)``);
    ``observation_options``: the env's observation options (``egosearch evaluate --env-option``) its policy
    reads, any other given is refused (none of the registered searchers reads one: they act on the env's own
    state)."""

    name: str
    factory: str | Callable[..., Any]
    env_id: str = "EgoSearch-v0"
    head: bool | None = None
    label: str = ""
    what: str = ""
    help: str = ""
    bound: bool = False
    table_row: str = BESIDE
    classical: bool = False
    takes_seed: bool = False
    floor_of: str | None = None
    path_style: tuple | None = None
    fig6_level: tuple | None = None
    options: tuple[tuple[str, Any], ...] = ()
    observation_options: tuple[str, ...] = ()

    def policy_factory(self) -> Callable[..., Any]:
        return resolve(self.factory)

    def maker(self, seed: int = 0) -> Callable[[Any], Any]:
        """``make(env) -> policy`` for ``--seed``: the factory itself when it takes no seed."""
        factory = self.policy_factory()
        kwargs = dict(self.options)
        if self.takes_seed:
            kwargs["seed"] = seed
        return partial(factory, **kwargs) if kwargs else factory

    def make(self, env, seed: int = 0):
        """Its policy for ``env``."""
        return self.maker(seed)(env)


_REGISTRY: Registry[Searcher] = Registry("searcher", reserved={ACTOR: "--policy actor is a trained actor"})
SEARCHERS: dict[str, Searcher] = _REGISTRY.entries
"""Every registered searcher by name, in registration order."""


def register(name: str, factory: str | Callable[..., Any], *, replace: bool = False, **fields) -> Searcher:
    """Register a searcher under ``name`` (see :class:`Searcher` for the fields); a name already taken
    needs ``replace``."""
    searcher = Searcher(name, factory, **fields)
    if searcher.table_row not in TABLE_ROWS:
        raise ValueError(f"searcher {name!r}: table_row={searcher.table_row!r}; allowed: {', '.join(TABLE_ROWS)}")
    return _REGISTRY.add(name, searcher, replace=replace)


def unregister(name: str) -> Searcher:
    """Remove a registered searcher (a test's own, after it); returns it."""
    return _REGISTRY.remove(name)


def get(name: str) -> Searcher:
    """The searcher registered as ``name``."""
    return _REGISTRY.get(name)


def names() -> tuple[str, ...]:
    """Every registered name, in registration order: what ``--policy`` takes without ``--weights``."""
    return _REGISTRY.names()


def bounds() -> tuple[str, ...]:
    """Table 1's bound rows in its order: the floor, the others (registration order), the ceiling."""
    return tuple(s.name for s in sorted((s for s in SEARCHERS.values() if s.bound),
                                        key=lambda s: TABLE_ROWS.index(s.table_row)))


def classical() -> tuple[str, ...]:
    """The searchers config ``claims_pairs`` may name beside the variants (traced by ``trace_bound``)."""
    return tuple(s.name for s in SEARCHERS.values() if s.classical)


def modular_floors() -> dict[str, str]:
    """A modular searcher's floor by the decision env its high level was trained in: the same walk (and head
    sweep) with each decision drawn at random. What a trained high level beats it by is what its learned
    decisions add."""
    return {s.floor_of: s.name for s in SEARCHERS.values() if s.floor_of}


# ---- the searchers ------------------------------------------------------------------------------
# Registration order is the order names() lists them in (error lines, the workflow's wildcards);
# Table 1 orders its bounds by table_row, then this order.

register("random", "egosearch.searchers.policies:random_searcher", takes_seed=True,
         label="random searcher", what="uniform random actions", bound=True, table_row=FLOOR,
         path_style=("#555555", "--", "v"), fig6_level=("random searcher", "--", "#555555"))
register("oracle", "egosearch.searchers.policies:OraclePolicy", help="privileged: knows the target",
         label="privileged oracle", what="knows the target and walks the shortest path to it", bound=True,
         table_row=CEILING, path_style=("#222222", ":", "^"))
register("frontier", "egosearch.searchers.frontier:FrontierPolicy", head=True,
         help="the classical searcher, head moving or fixed", label="frontier searcher (classical)",
         what="maps depth with its own pose, walks to the nearest frontier, scans with its head, then walks to the "
              "target it saw (a reference, not tuned)", bound=True, classical=True,
         path_style=("#8c6d31", "-.", "s"), fig6_level=("classical searcher, head moving", "-.", "#000000"))
register("frontier_head_off", "egosearch.searchers.frontier:FrontierPolicy", env_id="EgoSearchNoHead-v0", head=False,
         help="the classical searcher, head moving or fixed", label="frontier searcher, head fixed",
         what="the same with the camera fixed to the body", bound=True, classical=True,
         path_style=("#bd9e39", ":", "D"),
         fig6_level=("classical searcher, head fixed", (0, (5, 1.5, 1, 1.5, 1, 1.5)), "#777777"))
# The frontier searcher tuned on training-side sets (egosearch.searchers.frontier_tuned), a bound row of its
# own: the untuned rows above stay Table 1's classical reference. It is the cpu preset's teacher
# (demo_teacher) since the stuck-student redo, so Figure 6 draws it as a level too.
register("frontier_tuned", "egosearch.searchers.frontier_tuned:FrontierTunedPolicy", head=True,
         help="the same tuned on training-side sets: a teacher and a bound of its own",
         label="frontier searcher, tuned", bound=True, classical=True, path_style=("#637939", "-.", "P"),
         what="the frontier searcher with its parameters tuned on training-side sets only (generated homes, "
              "other scenario seeds), never on Table 1's",
         fig6_level=("tuned searcher (the cpu preset's teacher), head moving", "-.", "#637939"))
register("frontier_tuned_head_off", "egosearch.searchers.frontier_tuned:FrontierTunedPolicy",
         env_id="EgoSearchNoHead-v0", head=False,
         help="the same tuned on training-side sets: a teacher and a bound of its own",
         label="frontier searcher, tuned, head fixed", what="the same with the camera fixed to the body",
         bound=True, classical=True, path_style=("#8ca252", ":", "X"),
         fig6_level=("tuned searcher (the cpu preset's teacher), head fixed", (0, (5, 1.5, 1, 1.5, 1, 1.5)),
                     "#8ca252"))
# The tuned searcher held to its last K steps (egosearch.searchers.frontier: memory_window): how much memory the
# task asks for, against the student's 5 frames (`snakemake memory_window`, docs/baselines.md). Not Table 1 rows.
MEMORY_WINDOWS = (5, 10, 20, 50)
"""The windows (steps) of the memory-window searchers: ``frontier_tuned_window{K}`` and its head-fixed twin."""
for _k in MEMORY_WINDOWS:
    register(f"frontier_tuned_window{_k}", "egosearch.searchers.frontier_tuned:FrontierTunedPolicy", head=True,
             options=(("memory_window", _k),), help="the tuned searcher held to its last K steps (K = 5, 10, 20, 50)",
             label=f"tuned searcher, last {_k} steps", what=f"the tuned frontier searcher with the map and notes of "
             f"its last {_k} steps only (the target's last-seen place kept)")
    register(f"frontier_tuned_head_off_window{_k}", "egosearch.searchers.frontier_tuned:FrontierTunedPolicy",
             env_id="EgoSearchNoHead-v0", head=False, options=(("memory_window", _k),),
             help="the tuned searcher held to its last K steps (K = 5, 10, 20, 50)",
             label=f"tuned searcher, head fixed, last {_k} steps", what="the same with the camera fixed to the body")


def with_head(name: str, head: bool) -> str:
    """The registered searcher that is ``name``'s policy with the head moving (``head``) or fixed: the one with
    the same factory and options whose ``head`` is ``head`` (``frontier_tuned`` -> ``frontier_tuned_head_off``);
    ValueError, one line, when none is registered."""
    searcher = get(name)
    for other in SEARCHERS.values():
        if other.factory == searcher.factory and other.options == searcher.options and other.head is head:
            return other.name
    raise ValueError(f"no registered searcher is {name!r} with its head {'moving' if head else 'fixed'}")


def classical_with_head(head: bool) -> tuple[str, ...]:
    """The classical searchers (``classical``) of one head, in registration order: what a policy of that head is
    read against (``snakemake versus_teacher``)."""
    return tuple(s.name for s in SEARCHERS.values() if s.classical and s.head is head)


def memory_window_searchers(head: bool) -> dict[int | None, str]:
    """The tuned searcher by memory window (None: the whole episode), head moving or fixed."""
    whole = "frontier_tuned" if head else "frontier_tuned_head_off"
    return {**{k: f"{whole}_window{k}" for k in MEMORY_WINDOWS}, None: whole}


register("modular_random", "egosearch.searchers.modular:random_decisions", head=True, takes_seed=True,
         help="the modular searcher's walk with random decisions", label="modular searcher's walk, random decisions",
         what="the modular searcher's walk with each decision drawn uniformly at random",
         floor_of="EgoSearchModular-v0")
register("modular_random_head_off", "egosearch.searchers.modular:random_decisions", env_id="EgoSearchNoHead-v0",
         head=False, takes_seed=True, help="the modular searcher's walk with random decisions",
         label="modular searcher's walk, random decisions, head fixed",
         what="the same with the camera fixed to the body", floor_of="EgoSearchNoHeadModular-v0")
