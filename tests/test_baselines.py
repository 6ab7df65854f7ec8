"""Figure 7's baselines (paper 6.4): the noisy searcher and the one-step straight line, by hand."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from egosearch.motion.replan import NoisySearchPolicy, line_plan
from egosearch.sim.body import AgentSpec, AgentState


class Recorder:
    """A policy that answers a fixed action and records what it was asked."""

    def __init__(self, action):
        self.action = np.asarray(action, np.float32)
        self.seen, self.resets = [], []

    def reset(self, seed=None):
        self.resets.append(seed)

    def act(self, obs):
        self.seen.append(obs)
        return self.action


def _obs(visible: bool) -> dict:
    mask = np.zeros(30, np.float32)
    mask[-1] = 1.0 if visible else 0.0
    return {"mask": mask}


def test_noisy_search_is_random_until_seen_then_the_policy():
    inner = Recorder([0.5, -0.5, 0.25, 0.0, 1.0])
    noisy = NoisySearchPolicy(inner, action_dim=5, seed=0)
    noisy.reset(seed=3)
    assert inner.resets == [3]
    expected = np.random.default_rng([3, 7]).uniform(-1.0, 1.0, (2, 5)).astype(np.float32)
    first = noisy.act(_obs(False))
    second = noisy.act(_obs(False))
    np.testing.assert_array_equal(first, expected[0])
    np.testing.assert_array_equal(second, expected[1])
    assert inner.seen == []  # the policy is not even asked while the target is unseen
    np.testing.assert_array_equal(noisy.act(_obs(True)), inner.action)
    assert len(inner.seen) == 1
    # The random stream goes on where it stopped: seeing the target consumed none of it.
    np.testing.assert_array_equal(noisy.act(_obs(False)),
                                  np.random.default_rng([3, 7]).uniform(-1.0, 1.0, (3, 5))[2].astype(np.float32))
    # The same seed, the same episode.
    noisy.reset(seed=3)
    np.testing.assert_array_equal(noisy.act(_obs(False)), expected[0])
    noisy.reset(seed=4)
    assert not np.array_equal(noisy.act(_obs(False)), expected[0])


def _env(x, y, theta, pitch=0.0, head_yaw=0.0, head=True):
    spec = AgentSpec(head=head)
    return SimpleNamespace(spec_agent=spec, state=AgentState(x, y, theta, pitch, head_yaw, 1.2), base_height=1.65)


def test_line_plan_by_hand():
    # Facing +y; the action asks full speed forward, half the side step (0.075 m to the left, i.e. -x),
    # a full right turn (-0.4 rad), pitch +0.1 rad and yaw -0.35 rad.
    env = _env(1.0, 2.0, math.pi / 2, pitch=0.2, head_yaw=0.1)
    plan = line_plan(env, [1.0, 0.5, -1.0, 0.4, -1.0], horizon=3)
    assert len(plan) == 4
    assert (plan[0].x, plan[0].y, plan[0].theta) == (1.0, 2.0, math.pi / 2) and plan[0] is not env.state
    for k, s in enumerate(plan[1:], start=1):
        assert (s.x, s.y) == pytest.approx((1.0 - 0.075 * k, 2.0 + 0.25 * k), abs=1e-12)
        assert s.theta == pytest.approx(math.pi / 2 - 0.4)
        assert (s.pitch, s.head_yaw) == pytest.approx((0.3, -0.25))
        assert s.camera_height == 1.65  # the plan is at the evaluated height, not the noisy one
    assert (env.state.x, env.state.y) == (1.0, 2.0)  # planning moves nothing


def test_line_plan_clips_the_action_and_the_head():
    env = _env(0.0, 0.0, 0.0, pitch=0.45, head_yaw=1.3)
    plan = line_plan(env, [3.0, -2.0, 0.0, 1.0, 1.0], horizon=2)
    # Actions beyond [-1, 1] are clipped: 0.25 m forward (+x), 0.15 m to the right (-y) per step.
    assert (plan[2].x, plan[2].y) == pytest.approx((0.5, -0.3))
    # The head stops at its limits: pitch 0.5 rad up, yaw 1.4 rad.
    assert (plan[1].pitch, plan[1].head_yaw) == (0.5, 1.4)
    # Without a head the camera keeps the body's pitch and yaw.
    flat = line_plan(_env(0.0, 0.0, 0.0, pitch=-0.35, head_yaw=0.0, head=False), [1.0, 0.0, 0.5], horizon=1)
    assert (flat[1].pitch, flat[1].head_yaw, flat[1].theta) == (-0.35, 0.0, pytest.approx(0.2))
