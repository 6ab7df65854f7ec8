"""A toy classical searcher (the extension test's, tests/test_extending.py): it turns on the spot, head fixed.
Copied to egosearch/searchers/toy_spin.py in a temporary copy of the repository."""

from __future__ import annotations

import numpy as np


class ToySpin:
    """Every step a full turn to the left and nothing else."""

    def __init__(self, env):
        self.action_dim = env.action_space.shape[0]

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, obs: dict) -> np.ndarray:
        action = np.zeros(self.action_dim, np.float32)
        action[2] = 1.0  # forward, lateral, turn
        return action
