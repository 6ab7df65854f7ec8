"""A policy over a scenario set -> one row per episode."""

from __future__ import annotations

import os

import gymnasium

import egosearch.envs  # noqa: F401  (registers the ids, the decision envs too)
from egosearch.core.csvio import write_csv_atomic
from egosearch.runs.metrics import episode_spl, spl
from egosearch.sim.body import EVAL_HEIGHTS
from egosearch.sim.scenarios import Scenario, generate_scenarios

EPISODE_COLUMNS = ("scenario_id", "success", "steps", "path_length", "shortest_path", "spl",
                   "collisions", "episode_return")


def make_env(env_id: str, scenario: Scenario, **kwargs) -> gymnasium.Env:
    """An env for the scenario's home, at its camera height and placement scheme."""
    return gymnasium.make(env_id, layout=scenario.layout, placement=scenario.placement,
                          height=scenario.height, **kwargs)


def run_episode(env: gymnasium.Env, policy, scenario: Scenario, seed: int = 0, recorder=None) -> dict:
    """One deterministic episode of ``policy`` on ``scenario``; ``recorder`` (an
    :class:`egosearch.runs.trace.TraceRecorder`) is shown the state after the reset and after every step."""
    obs, info = env.reset(seed=seed, options={"scenario": scenario})
    policy.reset(seed=seed)
    if recorder is not None:
        recorder.start(env, scenario, info, learns=getattr(policy, "learns", "steps"))
    total = 0.0
    done = False
    while not done:
        action = policy.act(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        if recorder is not None:
            recorder.step(env, action, info)
        total += float(reward)
        done = terminated or truncated
    success = bool(info["success"])
    return {
        "scenario_id": scenario.scenario_id,
        "success": int(success),
        "steps": info["steps"],
        "path_length": round(info["path_length"], 4),
        "shortest_path": scenario.shortest_path,
        "spl": round(episode_spl(success, scenario.shortest_path, info["path_length"]), 5),
        "collisions": info["collisions"],
        "episode_return": round(total, 4),
    }


def evaluate(env_id: str, make_policy, scenarios: list[Scenario], seed: int = 0, progress: bool = False,
             desc: str = "evaluate", recorder=None, env_kwargs: dict | None = None) -> list[dict]:
    """Run ``make_policy(env)`` on every scenario; the env is rebuilt only when the home or
    height changes. ``recorder``: see :func:`run_episode`; ``env_kwargs``: the env's observation options
    (:data:`egosearch.envs.OBSERVATION_OPTIONS`, a trained actor's recorded ones)."""
    rows, env, env_key, policy = [], None, None, None
    iterator = scenarios
    if progress:
        from tqdm import tqdm

        iterator = tqdm(scenarios, desc=desc, unit="ep")
    try:
        for sc in iterator:
            key = (sc.layout, sc.placement, sc.height)
            if key != env_key:
                if env is not None:
                    env.close()
                env, env_key = make_env(env_id, sc, **(env_kwargs or {})), key
                policy = make_policy(env)
            rows.append(run_episode(env, policy, sc, seed=seed + sc.scenario_id, recorder=recorder))
    finally:
        if env is not None:
            env.close()
    return rows


def write_episodes(path: str | os.PathLike, rows: list[dict]) -> None:
    write_csv_atomic(path, EPISODE_COLUMNS, rows)


CURVE_SEED = 7
"""The training curve's scenarios are drawn with this seed, and episode i of them is seeded ``CURVE_SEED +
scenario_id``: the same episodes at every evaluation step of every training seed."""
CURVE_LEVEL_COLUMNS = ("home", "height", *EPISODE_COLUMNS)
"""A searcher's episodes on a training curve's scenarios (``egosearch evaluate --curve-of``): Figure 6's levels.
Scenario ids restart in each home and height, so the home and height say which scenario a row is."""


def curve_scenarios(layout: str | list[str], placement: str, n: int, seed: int = CURVE_SEED) -> list[Scenario]:
    """The ``n`` held-out scenarios a training curve is evaluated on: ``layout`` (a home, or a list of homes),
    the three evaluation heights, each (home, height) group drawn with ``seed`` and taken in turn."""
    layouts = [layout] if isinstance(layout, str) else list(layout)
    groups = [(home, h) for home in layouts for h in EVAL_HEIGHTS]
    per_group = [generate_scenarios(home, placement, h, n=-(-n // len(groups)), seed=seed) for home, h in groups]
    return [sc for i in range(max(map(len, per_group))) for group in per_group for sc in group[i:i + 1]][:n]


def curve_episodes(env_id: str, make_policy, scenarios: list[Scenario], progress: bool = False,
                   desc: str = "evaluate", recorder=None, env_kwargs: dict | None = None) -> list[dict]:
    """``make_policy(env)`` on a training curve's scenarios (:func:`curve_scenarios`), each episode seeded as
    the curve's are: rows of :data:`CURVE_LEVEL_COLUMNS`."""
    # by home and height, so that each env is built once (the curve interleaves them)
    grouped = sorted(scenarios, key=lambda sc: (sc.layout, sc.height, sc.scenario_id))
    rows = evaluate(env_id, make_policy, grouped, seed=CURVE_SEED, progress=progress, desc=desc, recorder=recorder,
                    env_kwargs=env_kwargs)
    return [{"home": sc.layout, "height": sc.height, **row} for sc, row in zip(grouped, rows, strict=True)]


def scenario_evaluator(env_id: str, layout: str | list[str], placement: str, n: int, seed: int = CURVE_SEED,
                       env_kwargs: dict | None = None):
    """``evaluate(policy) -> {success_rate, spl, episode_return, episodes}`` on ``n`` fixed held-out
    scenarios of ``layout`` (a home, or a list of homes taken in turn), the three evaluation heights
    in turn. The learner calls it every ``eval_every`` steps: these rows are Figure 6's data.
    ``episode_return`` is always the paper's reward (the env's default r_d), whatever reward a
    variant trains with, so that the curves of variants are on one scale. ``env_kwargs``: the observation
    options the policy trains with (:data:`egosearch.envs.OBSERVATION_OPTIONS`)."""
    scenarios = curve_scenarios(layout, placement, n, seed)
    envs: dict = {}

    def evaluate_policy(policy) -> dict:
        rows = []
        for sc in scenarios:
            key = (sc.layout, sc.height)
            if key not in envs:
                envs[key] = make_env(env_id, sc, **(env_kwargs or {}))
            rows.append(run_episode(envs[key], policy, sc, seed=seed + sc.scenario_id))
        episodes = [{"home": sc.layout, "height": sc.height, "scenario_id": sc.scenario_id, "success": r["success"],
                     "shortest_path": r["shortest_path"], "path_length": r["path_length"]}
                    for sc, r in zip(scenarios, rows, strict=True)]
        return {"episodes": episodes, "success_rate": sum(r["success"] for r in rows) / len(rows),
                "spl": spl([r["success"] for r in rows], [r["shortest_path"] for r in rows],
                           [r["path_length"] for r in rows]),
                "episode_return": sum(r["episode_return"] for r in rows) / len(rows)}

    def close() -> None:
        for env in envs.values():
            env.close()
        envs.clear()

    evaluate_policy.close = close
    return evaluate_policy
