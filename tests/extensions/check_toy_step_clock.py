"""The toy observation option's own test (tests/test_toy_step_clock.py in the copy)."""

from __future__ import annotations

import numpy as np

from egosearch.envs import env_space_dims, observation_kwargs, parse_env_options
from egosearch.rl.config import load_config
from egosearch.sim.env import SearchEnv


def test_the_clock_is_observed_sized_and_set_by_its_config_field():
    env = SearchEnv("studio", "everywhere", toy_step_clock=True)
    obs, _ = env.reset(seed=0)
    assert obs["proprio"].shape == (5,) and obs["proprio"][4] == 0.0
    for _ in range(3):
        obs, *_ = env.step(np.zeros(5, np.float32))
    assert obs["proprio"][4] == np.float32(0.03)
    assert env_space_dims("EgoSearch-v0", {"toy_step_clock": True})["proprio"] == 5
    assert parse_env_options(["toy_step_clock=true"]) == {"toy_step_clock": True}
    cfg = load_config("cpu", {"toy_step_clock": True})
    # the field adds its option to whatever options the preset itself turns on (the cpu preset's contact signal)
    preset_options = observation_kwargs(load_config("cpu", {}).to_dict())
    assert "toy_step_clock" not in preset_options
    assert observation_kwargs(cfg.to_dict()) == preset_options | {"toy_step_clock": True}
    assert not load_config("cpu", {}).toy_step_clock
