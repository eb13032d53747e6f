"""The optimum: backward induction, policy iteration, and the figures known by hand."""

from __future__ import annotations

import itertools
from collections import deque

import gymnasium as gym
import numpy as np
import pytest

from tests.mdp_support import random_model
from tui_gym.core.mdp import (
    FiniteMDP,
    evaluate,
    model_from_env,
    optimal_actions,
    solve,
    with_horizon,
)

STAY, GO = 0, 1


def two_rooms(stay_reward: float, horizon: int | None = None) -> FiniteMDP:
    """Room 0 (the start) and room 1; "stay" loops in place, "go" moves on.

    Room 0: stay pays `stay_reward`; go pays -1 and reaches room 1 with
    probability 1/2, else pays 2 and ends. Room 1: stay pays 0; go pays 10 and ends.
    """
    table = {
        0: {
            STAY: [(1.0, 0, stay_reward, False)],
            GO: [(0.5, 1, -1.0, False), (0.5, 0, 2.0, True)],
        },
        1: {STAY: [(1.0, 1, 0.0, False)], GO: [(1.0, 1, 10.0, True)]},
    }
    return FiniteMDP.from_table(table, [1.0, 0.0], horizon=horizon)


def test_with_a_limit_the_optimum_may_change_plan_as_the_limit_nears():
    # One step left: staying (1) beats going (0.5). Two: going (5.5). Three: stay, then go.
    for horizon, optimum in [(1, 1.0), (2, 5.5), (3, 6.5), (10, 13.5)]:
        assert solve(two_rooms(1.0, horizon)).value == pytest.approx(optimum)
    solution = solve(two_rooms(1.0, 3))
    np.testing.assert_allclose(solution.q, [[6.5, 5.5], [10.0, 10.0]])
    assert solution.steps_left == 3
    # No fixed policy reaches 6.5 in three steps: the best of them, "go", gets 5.5.
    fixed = [
        evaluate(two_rooms(1.0, 3), np.array(p)).value for p in itertools.product((0, 1), repeat=2)
    ]
    assert max(fixed) == pytest.approx(5.5)
    # Halfway through an episode the coach asks with the steps that are left.
    np.testing.assert_allclose(solve(two_rooms(1.0, 3), steps_left=1).q, [[1.0, 0.5], [0.0, 10.0]])
    with pytest.raises(ValueError, match="steps_left"):
        solve(two_rooms(1.0, 3), steps_left=4)


def test_discounted_with_no_limit():
    solution = solve(two_rooms(1.0), gamma=0.5)
    # Staying forever is worth 2; going is worth 1/2 (-1 + 10/2) + 1/2 * 2 = 3.
    np.testing.assert_allclose(solution.q, [[2.5, 3.0], [5.0, 10.0]])
    assert solution.value == pytest.approx(3.0)
    assert list(solution.policy) == [GO, GO]


def test_undiscounted_with_no_limit_counts_only_play_that_ends():
    solution = solve(two_rooms(-1.0))
    assert solution.value == pytest.approx(5.5)
    np.testing.assert_allclose(solution.q, [[4.5, 5.5], [10.0, 10.0]])
    # Staying for nothing is as bad as never ending: the best that ends is still 5.5.
    assert solve(two_rooms(0.0)).value == pytest.approx(5.5)
    # A loop that pays can be repeated at will before ending: no best, the optimum is unbounded.
    unbounded = solve(two_rooms(1.0))
    assert unbounded.unbounded and unbounded.value == np.inf


def test_no_policy_that_ends():
    table = {
        0: {0: [(1.0, 0, -1.0, False)], 1: [(1.0, 1, 0.0, False)]},
        1: {0: [(1.0, 1, 0.0, False)], 1: [(1.0, 0, 0.0, False)]},
    }
    model = FiniteMDP.from_table(table, [1.0, 0.0])
    solution = solve(model)
    assert solution.value == -np.inf
    assert (solution.q == -np.inf).all()
    assert solve(with_horizon(model, 4)).value == 0.0


def forward_value(model: FiniteMDP, plan: tuple, gamma: float) -> float:
    """The value of a plan (one [S] policy per step), by pushing the state distribution forward."""
    alive = model.initial.copy()
    total = 0.0
    for t, policy in enumerate(plan):
        states = np.arange(model.n_states)
        prob = model.prob[states, policy]
        total += gamma**t * float(alive @ (prob * model.reward[states, policy]).sum(axis=1))
        moving = alive[:, None] * np.where(model.terminal[states, policy], 0.0, prob)
        alive = np.bincount(
            model.next_state[states, policy].ravel(), moving.ravel(), model.n_states
        )
    return total


@pytest.mark.parametrize("gamma", [1.0, 0.8])
def test_backward_induction_matches_brute_force_over_every_plan(gamma):
    rng = np.random.default_rng(7)
    for _ in range(3):
        model = random_model(rng, n_states=3, n_actions=2, outcomes=2, horizon=3)
        policies = [np.array(p) for p in itertools.product(range(2), repeat=3)]
        best = max(
            forward_value(model, plan, gamma) for plan in itertools.product(policies, repeat=3)
        )
        assert solve(model, gamma).value == pytest.approx(best, abs=1e-12)
        for policy in policies:
            exact = evaluate(model, policy, gamma).value
            assert exact == pytest.approx(forward_value(model, (policy,) * 3, gamma), abs=1e-12)


def test_policy_iteration_agrees_with_a_long_limit():
    rng = np.random.default_rng(11)
    for _ in range(5):
        model = random_model(rng, n_states=8, n_actions=3, end_chance=0.1)
        exact = solve(model, gamma=0.9)
        long = solve(with_horizon(model, 600), gamma=0.9)
        np.testing.assert_allclose(exact.q, long.q, atol=1e-9)
    # Undiscounted: every step may end here, so values converge as the limit grows.
    model = random_model(np.random.default_rng(5), n_states=8, n_actions=3, end_chance=0.3)
    np.testing.assert_allclose(solve(model).q, solve(with_horizon(model, 2000)).q, atol=1e-9)


def test_frozen_lake_known_optima():
    deterministic = model_from_env(gym.make("FrozenLake-v1", is_slippery=False))
    assert solve(deterministic).value == 1.0
    # The goal is six steps from the start: five are not enough.
    assert solve(with_horizon(deterministic, 5)).value == 0.0
    assert solve(with_horizon(deterministic, 6)).value == 1.0
    # Gymnasium's registration notes the slippery optima as 0.74 and 0.91.
    assert solve(model_from_env(gym.make("FrozenLake-v1"))).value == pytest.approx(0.7442, abs=1e-4)
    assert solve(model_from_env(gym.make("FrozenLake8x8-v1"))).value == pytest.approx(
        0.9132, abs=1e-4
    )


def test_cliff_walking_known_optima():
    cliff = model_from_env(gym.make("CliffWalking-v1"))
    assert cliff.horizon is None
    assert solve(cliff).value == -13.0
    assert solve(with_horizon(cliff, 200)).value == -13.0
    # In 12 steps the goal is out of reach: the best is 12 safe steps.
    assert solve(with_horizon(cliff, 12)).value == -12.0
    slippery = model_from_env(gym.make("CliffWalking-v1", is_slippery=True))
    no_limit = solve(slippery).value
    assert -70 < no_limit < -60
    # A limit can only help (being cut off saves the cost of the steps not taken),
    # and a long one comes to the same thing.
    assert solve(with_horizon(slippery, 200)).value >= no_limit
    assert solve(with_horizon(slippery, 3000)).value == pytest.approx(no_limit, abs=1e-9)


def test_taxi_optimum_is_the_shortest_ride_from_each_start():
    model = model_from_env(gym.make("Taxi-v4"))
    # Every step pays -1 and the drop-off +20, so the best return is 21 - (fewest steps).
    fewest = np.full(model.n_states, np.inf)
    ends = [s for s in range(model.n_states) if any(model.outcomes(s, a)[0][3] for a in range(6))]
    queue = deque(ends)
    fewest[ends] = 1
    predecessors = [[] for _ in range(model.n_states)]
    for s in range(model.n_states):
        for a in range(6):
            ((_, nxt, _, done),) = model.outcomes(s, a)
            if not done and nxt != s:
                predecessors[nxt].append(s)
    while queue:
        state = queue.popleft()
        for before in predecessors[state]:
            if fewest[before] == np.inf:
                fewest[before] = fewest[state] + 1
                queue.append(before)
    expected = float(model.initial @ np.where(model.initial > 0, 21 - fewest, 0.0))
    assert solve(model).value == pytest.approx(expected, abs=1e-12)
    assert solve(model).value == pytest.approx(7.93, abs=1e-9)


def test_optimal_actions_with_a_tolerance():
    q = np.array(
        [
            [1.0, 1.0 - 1e-12, 0.5],
            [-np.inf, -np.inf, -np.inf],
            [-np.inf, 3.0, 3.0],
            [np.inf, 1.0, np.inf],
            [100.0, 100.0 - 1e-6, 99.0],
        ]
    )
    marks = optimal_actions(q)
    assert marks.tolist() == [
        [True, True, False],
        [True, True, True],
        [False, True, True],
        [True, False, True],
        [True, False, False],
    ]
    assert optimal_actions(q, atol=0.0, rtol=1e-6)[4].tolist() == [True, True, False]
