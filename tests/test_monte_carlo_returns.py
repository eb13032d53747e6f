"""Monte Carlo's batched returns against the textbook recursion, on long interleaved episodes."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import MonteCarlo, Transitions


@pytest.mark.parametrize("discount", [0.5, 1.0])
def test_long_episodes_side_by_side_get_the_returns_of_the_recursion(discount: float) -> None:
    # Env 7 plays one episode longer than the kept rows are wide at first and, with
    # discount 0.5, than one block of the returns' computation; env 2 ends an episode
    # every 5 steps beside it. Every state is visited once and the step is 1, so each
    # Q(s, a) is exactly the return from its visit.
    steps = 700
    hp = {"discount": discount, "learning_rate": 1.0, "learning_rate_schedule": "constant"}
    learner = MonteCarlo(2, hp, n_states=2 * steps, seed=0)
    rng = np.random.default_rng(3)
    rewards = rng.normal(size=(2, steps))
    for t in range(steps):
        states = np.array([t, steps + t])
        ends = np.array([t == steps - 1, t % 5 == 4])
        learner.update(Transitions(states, np.array([0, 1]), rewards[:, t], states,
                                   ends, np.zeros(2, dtype=bool), env=np.array([7, 2])))
    expected = np.zeros((2, steps))
    for t in range(steps - 1, -1, -1):
        later = expected[0, t + 1] if t + 1 < steps else 0.0
        expected[0, t] = rewards[0, t] + discount * later
        later = expected[1, t + 1] if t % 5 != 4 else 0.0
        expected[1, t] = rewards[1, t] + discount * later
    np.testing.assert_allclose(learner.q[:steps, 0], expected[0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(learner.q[steps:, 1], expected[1], rtol=1e-9, atol=1e-12)
