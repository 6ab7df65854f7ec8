"""Training in many generated homes: each episode's home is drawn from a split of home seeds.

Building a home (its scene, pybullet world, sensor geometry and navigation grid) takes 1-2 s here,
while a training episode costs well under a second of env and learner time, so a new home per
episode would dominate training. :class:`HomePoolEnv` keeps ``pool_size`` built homes per env
worker, draws each episode's home from that pool, and every ``episodes_per_swap`` episodes
replaces one pooled home with a fresh draw from the split: over a run the worker sees many homes
at a fraction of the build cost (``egosearch bench homes`` measures both).

Generated homes whose seed lies in :data:`HELDOUT_HOME_SEEDS` are the generalisation benchmark's
unseen homes: no training may draw them (a split that overlaps them is refused).

A resumed run restores the learner, its replay and RNGs exactly, but rebuilds the pool from its
first homes, so the sequence of training homes after a resume differs from a run never stopped.
"""

from __future__ import annotations

import gymnasium

import egosearch.sim.body_envs  # noqa: F401  (registers the ids this env builds)
from egosearch.scene.layouts import HELDOUT_HOME_SEEDS

GENERATED = "generated"
"""``train_env: layout`` of a variant that trains in generated homes (with ``home_seeds``)."""
PAPER_HOMES = "paper_homes"
"""``train_env: layout`` of a variant that trains in both of the paper's homes (an episode in each at random)."""


def curve_homes(train_env: dict) -> list[str]:
    """The homes a variant's training curve (Figure 6) is read in: both paper homes for a policy trained in
    either or both of them; a policy trained in generated homes is read in its split's first home."""
    # local: egosearch.scene loads trimesh (~2 s); the Snakefile's variant checks import this module
    from egosearch.scene.layouts import LAYOUT_NAMES

    layout = train_env["layout"]
    if layout == GENERATED:
        return [f"home{train_env['home_seeds'][0]}"]
    if layout in (*LAYOUT_NAMES, PAPER_HOMES):
        return list(LAYOUT_NAMES)
    return [layout]


def check_home_split(home_seeds) -> range:
    """``[first, stop)`` -> the split as a range; ValueError (one line) when it is empty or overlaps the
    held-out homes."""
    try:
        first, stop = (int(v) for v in home_seeds)
    except (TypeError, ValueError):
        raise ValueError(f"home_seeds={home_seeds!r}: expected [first, stop), two integers") from None
    if not 0 <= first < stop:
        raise ValueError(f"home_seeds={home_seeds!r}: expected 0 <= first < stop")
    held = HELDOUT_HOME_SEEDS
    if first < held.stop and held.start < stop:
        raise ValueError(f"home_seeds=[{first}, {stop}) overlaps the held-out homes [{held.start}, {held.stop}) "
                         "that no training may draw (egosearch.scene.layouts.HELDOUT_HOME_SEEDS)")
    return range(first, stop)


class HomePoolEnv(gymnasium.Env):
    """``env_id`` in generated homes drawn from ``home_seeds`` (see the module docstring), or, with
    ``home_names``, in those named homes (all built once, never swapped); every other keyword goes to
    each home's env."""

    metadata = {"render_modes": []}

    def __init__(self, env_id: str, home_seeds=None, pool_size: int = 4, episodes_per_swap: int = 25,
                 home_names: tuple[str, ...] | None = None, **env_kwargs):
        if (home_seeds is None) == (home_names is None):
            raise ValueError("HomePoolEnv needs either home_seeds or home_names")
        if pool_size < 1 or episodes_per_swap < 1:
            raise ValueError(f"pool_size={pool_size}, episodes_per_swap={episodes_per_swap}: both must be >= 1")
        self.env_id, self.env_kwargs = env_id, dict(env_kwargs)
        self.env_kwargs.pop("layout", None)
        self.names = tuple(home_names) if home_names is not None else None
        self.split = check_home_split(home_seeds) if home_names is None else range(len(self.names))
        self.pool_size = len(self.split) if home_names is not None else min(int(pool_size), len(self.split))
        self.episodes_per_swap = int(episodes_per_swap)
        self.pool: dict[int, gymnasium.Env] = {}
        for seed in self.split[: self.pool_size]:
            self.pool[seed] = self._build(seed)
        first = next(iter(self.pool.values()))
        self.observation_space, self.action_space = first.observation_space, first.action_space
        self.current = first
        self.episodes = 0
        self.homes_built = self.pool_size

    def _build(self, seed: int) -> gymnasium.Env:
        if seed not in self.split:
            raise ValueError(f"home{seed} is outside this env's split [{self.split.start}, {self.split.stop})")
        layout = self.names[seed] if self.names is not None else f"home{seed}"
        return gymnasium.make(self.env_id, layout=layout, **self.env_kwargs)

    @property
    def home(self) -> str:
        return self.current.unwrapped.layout

    def _swap(self) -> None:
        """Replace one pooled home by a fresh draw from the split (not already pooled)."""
        if len(self.split) <= self.pool_size:
            return
        rng = self.np_random
        out = list(self.pool)[int(rng.integers(len(self.pool)))]
        while True:
            new = self.split[int(rng.integers(len(self.split)))]
            if new not in self.pool:
                break
        self.pool.pop(out).close()
        self.pool[new] = self._build(new)
        self.homes_built += 1

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if self.episodes and self.episodes % self.episodes_per_swap == 0:
            self._swap()
        self.episodes += 1
        homes = list(self.pool)
        self.current = self.pool[homes[int(self.np_random.integers(len(homes)))]]
        # always seeded from this env's generator: a home entering the pool is never seeded at random
        obs, info = self.current.reset(seed=int(self.np_random.integers(2**31)), options=options)
        return obs, {**info, "home": self.home}

    def step(self, action):
        obs, reward, terminated, truncated, info = self.current.step(action)
        return obs, reward, terminated, truncated, {**info, "home": self.home}

    def close(self):
        for env in self.pool.values():
            env.close()
        self.pool.clear()
