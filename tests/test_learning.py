"""Learning actually happens in the real env, at small scale, on an easy setting.

The easy setting: the 4.5 x 4 m ``studio``, no targets in low cabinets, and the progress form of
r_d (Savva et al.), with which a few thousand steps suffice; with the paper's form of r_d the
same budget learns nothing measurable (see the README's results). About four minutes on 2 cores.
"""

import numpy as np
import pytest

from egosearch.evaluate import evaluate
from egosearch.policies import RandomPolicy
from egosearch.rl.config import load_config
from egosearch.rl.train import ActorPolicy, train
from egosearch.scenarios import generate_scenarios

STEPS = 6000


@pytest.mark.slow
def test_sac_curl_beats_the_random_searcher_in_the_studio(tmp_path):
    cfg = load_config("smoke", {"total_env_steps": STEPS, "replay_capacity": STEPS, "init_steps": 500,
                                "eval_every": STEPS, "eval_episodes": 2, "checkpoint_every": STEPS,
                                "log_every": 1000, "num_threads": 1, "seed": 0})
    train("EgoSearch-v0", cfg, tmp_path, env_kwargs={"layout": "studio", "placement": "no_low_cabinets",
                                                     "distance_reward": "progress"},
          variant="easy", progress=False)
    scenarios = generate_scenarios("studio", "no_low_cabinets", 1.05, n=40, seed=5)
    actor = ActorPolicy(tmp_path / "actor.pt")
    learned = np.mean([r["success"] for r in evaluate("EgoSearch-v0", lambda env: actor, scenarios)])
    floor = np.mean([r["success"] for r in evaluate("EgoSearch-v0", lambda env: RandomPolicy(5, seed=0), scenarios)])
    assert learned >= floor + 0.1, (learned, floor)
