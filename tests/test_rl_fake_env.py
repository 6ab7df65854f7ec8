"""A tiny stand-in for the search env with the real env's spaces (used by the tests/test_rl_* files).

A bright square ("the target") moves on a 100x100 depth image with the first two action
components; the reward is a live penalty minus the distance of the target from the image
centre, +10 and ``terminated`` once it is within ``SUCCESS_RADIUS`` of the centre;
``truncated`` after ``max_steps``. The depth history is K = 5 frames, oldest first, and at
reset the first frame is repeated K times, exactly like the real env. The mask feature carries
the target's image coordinates (as the real 29-d feature does) plus a visibility flag.
"""

from __future__ import annotations

import gymnasium
import numpy as np
from gymnasium import spaces

FAKE_ENV_ID = "EgoSearchFake-v0"
FAKE_NOHEAD_ENV_ID = "EgoSearchFakeNoHead-v0"
K, SIZE = 5, 100
SUCCESS_RADIUS = 0.2
STEP_SCALE = 0.25


class FakeSearchEnv(gymnasium.Env):
    metadata = {"render_modes": []}

    def __init__(self, head: bool = True, max_steps: int = 30):
        self.head, self.max_steps = head, max_steps
        self.observation_space = spaces.Dict({
            "depth": spaces.Box(0, 255, (K, SIZE, SIZE), np.uint8),
            "mask": spaces.Box(-4.0, 4.0, (30,), np.float32),
            "proprio": spaces.Box(-4.0, 4.0, (4,), np.float32),
        })
        self.action_space = spaces.Box(-1.0, 1.0, (5 if head else 3,), np.float32)
        yy, xx = np.mgrid[0:SIZE, 0:SIZE]
        self._background = ((yy + xx) * (60.0 / (2 * SIZE)) + 40).astype(np.uint8)
        self._frames = np.zeros((K, SIZE, SIZE), np.uint8)
        self.p = np.zeros(2)
        self.steps = 0
        self.last_a = np.zeros(2, np.float32)

    def _frame(self) -> np.ndarray:
        img = self._background.copy()
        cx, cy = ((self.p + 1.0) * 0.5 * (SIZE - 12) + 6).astype(int)
        img[cy - 5:cy + 5, cx - 5:cx + 5] = 250
        return img

    def _obs(self) -> dict:
        x, y = self.p
        mask = np.zeros(30, np.float32)
        mask[:4] = (x, y, np.hypot(x, y), np.arctan2(y, x))
        mask[29] = 1.0
        proprio = np.zeros(4, np.float32)
        if self.head:
            proprio[2:] = self.last_a
        return {"depth": self._frames.copy(), "mask": mask, "proprio": proprio}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        r = self.np_random.uniform(0.5, 1.0)
        a = self.np_random.uniform(-np.pi, np.pi)
        self.p = np.array([r * np.cos(a), r * np.sin(a)])
        self.steps = 0
        self.last_a = np.zeros(2, np.float32)
        self._frames[:] = self._frame()
        return self._obs(), {"success": False}

    def step(self, action):
        a = np.clip(np.asarray(action, np.float64), -1, 1)
        self.p = np.clip(self.p + STEP_SCALE * a[:2], -1, 1)
        self.last_a = a[:2].astype(np.float32)
        self.steps += 1
        self._frames[:-1] = self._frames[1:]
        self._frames[-1] = self._frame()
        dist = float(np.hypot(*self.p))
        success = dist < SUCCESS_RADIUS
        reward = -0.1 - dist + (10.0 if success else 0.0)
        truncated = not success and self.steps >= self.max_steps
        return self._obs(), reward, success, truncated, {"success": success}


def register_fake_envs() -> None:
    if FAKE_ENV_ID not in gymnasium.registry:
        gymnasium.register(FAKE_ENV_ID, entry_point=FakeSearchEnv, kwargs={"head": True})
    if FAKE_NOHEAD_ENV_ID not in gymnasium.registry:
        gymnasium.register(FAKE_NOHEAD_ENV_ID, entry_point=FakeSearchEnv, kwargs={"head": False})


def test_fake_env_contract():
    register_fake_envs()
    env = gymnasium.make(FAKE_ENV_ID)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert all((obs["depth"][i] == obs["depth"][0]).all() for i in range(K))  # first frame x K
    obs2, _, _, _, _ = env.step(env.action_space.sample())
    assert (obs2["depth"][:-1] == obs["depth"][1:]).all()  # oldest first, shifted
    assert gymnasium.make(FAKE_NOHEAD_ENV_ID).action_space.shape == (3,)
