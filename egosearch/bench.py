"""``egosearch bench env``: sensor frames/s and env steps/s on one core."""

from __future__ import annotations

import contextlib
import os
import platform
import time

import numpy as np


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


def bench_env(layout: str = "kitchen_living", frames: int = 3000, steps: int = 3000, seed: int = 0) -> dict:
    import gymnasium

    import egosearch.envs  # noqa: F401
    from egosearch.scene.layouts import get_scene
    from egosearch.scene.meshes import triangle_count
    from egosearch.sensor import bench_sensor

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
    return {
        "layout": layout,
        "triangles": triangle_count(scene),
        "sensor_frames_per_s": round(sensor["sensor_frames_per_s"], 1),
        "sensor_ms_per_frame": round(sensor["sensor_ms_per_frame"], 3),
        "env_steps_per_s": round(steps / elapsed, 1),
        "env_ms_per_step": round(1000 * elapsed / steps, 3),
        "env_resets_included": done_episodes,
        "pinned_core": core,
        "cpu": platform.processor() or platform.machine(),
    }
