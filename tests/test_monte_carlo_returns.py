"""Monte Carlo's returns against the textbook recursion, on an episode longer than its buffer."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import MonteCarlo


@pytest.mark.parametrize("discount", [0.5, 1.0])
def test_a_long_episode_gets_the_returns_of_the_recursion(discount: float) -> None:
    # One episode of 700 steps (the kept steps start with room for 64: they grow as it
    # goes), every state visited once and the step 1, so each Q(s, 0) is exactly the
    # return from its visit.
    steps = 700
    hp = {"discount": discount, "learning_rate": 1.0, "learning_rate_schedule": "constant"}
    learner = MonteCarlo(2, hp, n_states=steps + 1, seed=0)
    rewards = np.random.default_rng(3).normal(size=steps)
    for t in range(steps):
        learner.update_one(t, 0, float(rewards[t]), t + 1, t == steps - 1)
    expected = np.zeros(steps + 1)
    for t in range(steps - 1, -1, -1):
        expected[t] = rewards[t] + discount * expected[t + 1]
    np.testing.assert_allclose(learner.q[:steps, 0], expected[:steps], rtol=1e-9, atol=1e-12)
    assert learner.counts[:steps, 0].tolist() == [1] * steps
