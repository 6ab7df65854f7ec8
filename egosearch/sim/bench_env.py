"""``egosearch bench env``: sensor frames/s and env steps/s on one core; ``egosearch bench homes``: what
building a generated home costs against a training episode, per episode and with the pool.

``--out`` stores a benchmark's result with what it was measured on (:func:`recorded`): the docs' speed
figures are generated from such files (``results/<preset>/bench/*.json``), never typed.
"""

from __future__ import annotations

import contextlib
import os
import platform
import time
from collections.abc import Callable

import numpy as np

import egosearch.sim.body_envs  # noqa: F401  (registers the ids)
from egosearch.core.machine import cpu_seconds_all, measured_on, own_cpu_seconds
from egosearch.scene.layouts import get_scene
from egosearch.scene.meshes import triangle_count
from egosearch.sim.scenarios import MAX_STEPS
from egosearch.sim.sensor import bench_sensor


@contextlib.contextmanager
def one_core():
    """Pin this process to a single core for the measurement, as the targets are per core."""
    if not hasattr(os, "sched_getaffinity"):
        yield None
        return
    before = os.sched_getaffinity(0)
    core = min(before)
    os.sched_setaffinity(0, {core})
    try:
        yield core
    finally:
        os.sched_setaffinity(0, before)


REWARDS_TIMED = ("progress", "geodesic")
"""The training r_d forms ``bench env`` times side by side: the cpu preset's and the geodesic lever's."""
REWARD_ROUNDS = 6
OPTIONS_TIMED = ("map_image", "strided_history")
"""The memory levers' observation options ``bench env`` times beside the env without them, in the same run."""


def _interleaved_ms(envs: dict, actions: np.ndarray, seed: int) -> dict[str, float]:
    """Milliseconds per step of each env on the same actions, in interleaved rounds of one run: the machine's
    load falls on every env alike, so their ratios hold on a busy machine too."""
    spent = dict.fromkeys(envs, 0.0)
    for e in envs.values():
        e.reset(seed=seed)
    for chunk in np.array_split(actions, REWARD_ROUNDS):
        for name, e in envs.items():
            t0 = time.perf_counter()
            for a in chunk:
                _, _, terminated, truncated, _ = e.step(a)
                if terminated or truncated:
                    e.reset()
            spent[name] += time.perf_counter() - t0
    for e in envs.values():
        e.close()
    return {name: 1000 * t / len(actions) for name, t in spent.items()}


def bench_env(layout: str = "kitchen_living", frames: int = 3000, steps: int = 3000, seed: int = 0) -> dict:
    import gymnasium

    scene = get_scene(layout)
    with one_core() as core:
        sensor = bench_sensor(scene, n_frames=frames, seed=seed)
        env = gymnasium.make("EgoSearch-v0", layout=layout)
        env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        actions = rng.uniform(-1, 1, (steps, env.action_space.shape[0])).astype(np.float32)
        done_episodes = 0
        start = time.perf_counter()
        for a in actions:
            _, _, terminated, truncated, _ = env.step(a)
            if terminated or truncated:
                env.reset()
                done_episodes += 1
        elapsed = time.perf_counter() - start
        env.close()
        # The training rewards side by side on the same actions, interleaved rounds, in this one run: a ratio
        # the machine's load cancels from (the geodesic reward reads the navigation grid at every step).
        per_step_ms = _interleaved_ms({name: gymnasium.make("EgoSearch-v0", layout=layout, distance_reward=name)
                                       for name in REWARDS_TIMED}, actions, seed)
        # the memory levers' observations beside the plain one, the same way
        by_option = _interleaved_ms({"none": gymnasium.make("EgoSearchMemory-v0", layout=layout),
                                     **{name: gymnasium.make("EgoSearchMemory-v0", layout=layout, **{name: True})
                                        for name in OPTIONS_TIMED}}, actions, seed)
    return {
        "layout": layout,
        "triangles": triangle_count(scene),
        "sensor_frames_per_s": round(sensor["sensor_frames_per_s"], 1),
        "sensor_ms_per_frame": round(sensor["sensor_ms_per_frame"], 3),
        "env_steps_per_s": round(steps / elapsed, 1),
        "env_ms_per_step": round(1000 * elapsed / steps, 3),
        "env_resets_included": done_episodes,
        "env_ms_per_step_by_reward": {name: round(v, 3) for name, v in per_step_ms.items()},
        "geodesic_over_progress": round(per_step_ms["geodesic"] / per_step_ms["progress"], 3),
        "env_ms_per_step_by_option": {name: round(v, 3) for name, v in by_option.items()},
        "option_over_none": {name: round(by_option[name] / by_option["none"], 3) for name in OPTIONS_TIMED},
        "pinned_core": core,
        "cpu": platform.processor() or platform.machine(),
    }


def bench_homes(n_homes: int = 6, first_seed: int = 0, episodes: int = 3, seed: int = 0,
                learner_env_steps_per_core_s: float = 150.0, pool_size: int = 4,
                episodes_per_swap: int = 25) -> dict:
    """Seconds to build a generated home's env (scene, world, sensor, navigation grid: the first reset
    included) against the seconds of a training episode, on one core.

    A training episode costs its env steps plus the learner's share; the learner's share is taken
    from the cpu preset's measured rate (``learner_env_steps_per_core_s`` env steps per core-second
    of a whole training, env included, ``egosearch bench learner``). ``build_share_per_episode`` is
    the share of training time a new home per episode would take; ``build_share_pooled`` the share
    with :class:`egosearch.sim.home_pool.HomePoolEnv`'s pool (one build every ``episodes_per_swap``
    episodes, ``pool_size`` at the start, amortised over a 300k-step run of 100-step episodes)."""
    import gymnasium

    builds, steps_s = [], []
    rng = np.random.default_rng(seed)
    with one_core() as core:
        for home in range(first_seed, first_seed + n_homes):
            t0 = time.perf_counter()
            env = gymnasium.make("EgoSearch-v0", layout=f"home{home}")
            env.reset(seed=seed)
            builds.append(time.perf_counter() - t0)
            for _ in range(episodes):
                env.reset()
                t0 = time.perf_counter()
                for _ in range(MAX_STEPS):
                    _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, env.action_space.shape[0]))
                    if terminated or truncated:
                        break
                steps_s.append((time.perf_counter() - t0) / max(1, env.unwrapped.steps))
            env.close()
    build = float(np.mean(builds))
    episode = MAX_STEPS / learner_env_steps_per_core_s
    per_episode = build / (build + episode)
    episodes_per_run = 300_000 / MAX_STEPS
    pooled_builds = pool_size + episodes_per_run / episodes_per_swap
    pooled = pooled_builds * build / (pooled_builds * build + episodes_per_run * episode)
    return {"homes": n_homes, "build_s_mean": round(build, 3), "build_s_max": round(float(np.max(builds)), 3),
            "env_ms_per_step": round(1000 * float(np.mean(steps_s)), 3),
            "training_episode_s": round(episode, 3), "build_share_per_episode": round(per_episode, 3),
            "build_share_pooled": round(pooled, 4), "pool_size": pool_size, "episodes_per_swap": episodes_per_swap,
            "pinned_core": core, "cpu": platform.processor() or platform.machine()}


def recorded(command: str, run: Callable[[], dict]) -> dict:
    """``run()``'s result with what it was measured on: the command, date, commit, CPU and core count,
    and how busy the machine was. A speed figure means little without the load beside it: the load
    average before and after, and ``other_load_cores``, the CPU time other processes used during the
    run per second of it (0 on an idle machine; 1.0 is one core kept busy by something else)."""
    load_before = [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None
    busy0, own0, wall0 = cpu_seconds_all(), own_cpu_seconds(), time.perf_counter()
    result = run()
    wall = time.perf_counter() - wall0
    busy1, own = cpu_seconds_all(), own_cpu_seconds() - own0
    return {
        "command": command,
        **measured_on(),
        "load_average_before": load_before,
        "load_average_after": [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None,
        "other_load_cores": (round(max(0.0, busy1 - busy0 - own) / wall, 2)
                             if busy0 is not None and busy1 is not None and wall > 0 else None),
        "wall_s": round(wall, 1),
        "result": result,
    }
