"""Exact policy evaluation and the gap: by hand, against the real envs, never negative."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import TimeLimit

from tests.mdp_support import env_returns, random_model, within_standard_errors
from tests.test_mdp_solve import GO, STAY, two_rooms
from tui_gym.core.mdp import (
    FiniteMDP,
    PolicyError,
    evaluate,
    exact_gap,
    greedy_policy,
    model_from_env,
    policy_matrix,
    solve,
    with_horizon,
)

LEFT, DOWN, RIGHT, UP = 0, 1, 2, 3  # FrozenLake
C_UP, C_RIGHT, C_DOWN, C_LEFT = 0, 1, 2, 3  # CliffWalking


def test_values_by_hand():
    go = np.array([GO, GO])
    assert evaluate(two_rooms(1.0, 1), go).value == pytest.approx(0.5)
    assert evaluate(two_rooms(1.0, 7), go).value == pytest.approx(5.5)
    # Staying forever never ends, yet over a limit of 5 steps it is worth 5.
    staying = evaluate(two_rooms(1.0, 5), np.array([STAY, STAY]))
    assert staying.value == 5.0 and not staying.never_ends
    # Half stay, half go in room 0; go in room 1.
    mixed = np.array([[0.5, 0.5], [0.0, 1.0]])
    assert evaluate(two_rooms(1.0, 2), mixed).value == pytest.approx(3.625)
    assert evaluate(two_rooms(-1.0), mixed).value == pytest.approx(4.5)
    assert evaluate(two_rooms(1.0), np.array([STAY, GO]), gamma=0.5).value == pytest.approx(2.0)


def test_with_no_limit_a_policy_that_may_never_end_is_said_to():
    # Go on from room 0, then stay in room 1 for ever: half of the episodes never end.
    result = evaluate(two_rooms(-1.0), np.array([GO, STAY]))
    assert result.never_ends and result.value == -np.inf
    assert result.v[1] == -np.inf and result.v[0] == -np.inf
    gap = exact_gap(two_rooms(-1.0), np.array([GO, STAY]))
    assert gap.gap == np.inf and gap.never_ends and gap.optimal_value == pytest.approx(5.5)
    # Discounted, or over a limit, the same policy has a finite value.
    assert evaluate(two_rooms(-1.0), np.array([GO, STAY]), gamma=0.9).value == pytest.approx(
        0.5 * (-1.0) + 0.5 * 2.0
    )
    assert evaluate(two_rooms(-1.0, 50), np.array([GO, STAY])).value == pytest.approx(0.5)


def test_cliff_walking_policies_that_never_end():
    cliff = model_from_env(gym.make("CliffWalking-v1"))
    walls = evaluate(cliff, np.full(48, C_LEFT))
    assert walls.never_ends and walls.value == -np.inf
    # A fresh table's greedy policy picks among all actions at random: that walk ends surely.
    fresh = evaluate(cliff, greedy_policy(np.zeros((48, 4))))
    assert not fresh.never_ends and np.isfinite(fresh.value) and fresh.value < -13
    # The same wall-hugging over a 200-step limit costs 200.
    assert evaluate(with_horizon(cliff, 200), np.full(48, C_LEFT)).value == -200.0


def test_deterministic_and_one_hot_policies_agree():
    rng = np.random.default_rng(2)
    model = random_model(rng, n_states=7, n_actions=3, horizon=9)
    policy = rng.integers(0, 3, size=7)
    one_hot = policy_matrix(model, policy)
    assert one_hot.sum() == 7 and (one_hot[np.arange(7), policy] == 1).all()
    np.testing.assert_allclose(evaluate(model, policy).v, evaluate(model, one_hot).v)


def test_greedy_policy_shares_ties_and_mixes_epsilon():
    q = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 2.0, -1.0], [5.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(greedy_policy(q)[:2], [[0.25] * 4, [0.0, 0.5, 0.5, 0.0]])
    mixed = greedy_policy(q, epsilon=0.2)
    np.testing.assert_allclose(mixed[2], [0.85, 0.05, 0.05, 0.05])
    np.testing.assert_allclose(mixed.sum(axis=1), 1.0)
    with pytest.raises(PolicyError, match="epsilon"):
        greedy_policy(q, epsilon=1.5)


@pytest.mark.parametrize(
    ("policy", "message"),
    [
        (np.array([0, 2]), "in \\[0, 1\\]"),
        (np.array([0.0, 1.0]), "integer actions"),
        (np.array([[0.5, 0.6], [0.0, 1.0]]), "state 0 sum to 1.1"),
        (np.array([[1.5, -0.5], [0.0, 1.0]]), "probabilities in \\[0, 1\\]"),
        (np.zeros(3, dtype=int), "S=2, A=2"),
    ],
)
def test_bad_policies_are_refused(policy, message):
    with pytest.raises(PolicyError, match=message):
        evaluate(two_rooms(1.0, 3), policy)


def test_bad_gamma_is_refused():
    for gamma in (0.0, 1.5, -0.1):
        with pytest.raises(ValueError, match="gamma"):
            evaluate(two_rooms(1.0, 3), np.array([0, 0]), gamma=gamma)


@pytest.mark.parametrize(
    ("horizon", "gamma", "end_chance"),
    [(12, 1.0, 0.2), (12, 0.9, 0.2), (None, 0.9, 0.2), (None, 1.0, 0.3)],
)
def test_the_gap_of_any_policy_is_never_negative(horizon, gamma, end_chance):
    rng = np.random.default_rng(17)
    for _ in range(10):
        model = random_model(rng, n_states=6, n_actions=3, horizon=horizon, end_chance=end_chance)
        optimum = solve(model, gamma)
        for _ in range(10):
            stochastic = rng.dirichlet(np.ones(3) * 0.5, size=6)
            for policy in (rng.integers(0, 3, size=6), stochastic):
                gap = exact_gap(model, policy, gamma, optimum)
                assert gap.optimal_value - gap.exact_value >= -1e-12
                assert gap.gap >= 0.0
        if horizon is None and np.isfinite(optimum.value):
            # With no limit an optimal policy is a fixed one: its gap is 0.
            assert exact_gap(model, optimum.policy, gamma, optimum).gap == 0.0


@pytest.mark.parametrize(
    ("env_id", "kwargs", "fixed_reaches_it"),
    [
        ("FrozenLake-v1", {}, False),
        ("FrozenLake-v1", {"is_slippery": False}, True),
        ("CliffWalking-v1", {"is_slippery": True, "max_episode_steps": 100}, False),
        ("Taxi-v4", {"is_rainy": True}, True),
    ],
)
def test_greedy_policies_of_the_games_are_never_above_the_optimum(env_id, kwargs, fixed_reaches_it):
    model = model_from_env(gym.make(env_id, **kwargs))
    optimum = solve(model)
    rng = np.random.default_rng(4)
    for _ in range(5):
        q = rng.integers(-2, 3, size=(model.n_states, model.n_actions)).astype(float)
        for epsilon in (0.0, 0.1):
            assert exact_gap(model, greedy_policy(q, epsilon), optimum=optimum).gap >= 0.0
    # Near the limit the optimum may play differently: then no fixed policy reaches it,
    # and the solution's own fixed policy comes close.
    gap = exact_gap(model, optimum.policy, optimum=optimum)
    assert (gap.gap == 0.0) == fixed_reaches_it
    assert gap.gap < 0.01 * abs(gap.optimal_value)


def test_the_solution_policy_does_not_waste_time_on_ties():
    # Deterministic FrozenLake, gamma = 1, 100 steps: bumping a wall at the start is worth
    # as much as moving on (there is time), but always bumping it never arrives.
    lake = model_from_env(gym.make("FrozenLake-v1", is_slippery=False))
    solution = solve(lake)
    assert solution.q[0, LEFT] == solution.q[0, DOWN] == 1.0
    assert evaluate(lake, solution.policy).value == 1.0
    no_limit = solve(with_horizon(lake, None))
    assert no_limit.q[0, LEFT] == 1.0
    result = evaluate(with_horizon(lake, None), no_limit.policy)
    assert result.value == 1.0 and not result.never_ends


def test_the_optimum_given_must_match():
    model = two_rooms(-1.0, 5)
    with pytest.raises(ValueError, match="gamma=0.9"):
        exact_gap(model, np.array([0, 1]), gamma=1.0, optimum=solve(model, 0.9))
    with pytest.raises(ValueError, match="steps left"):
        exact_gap(model, np.array([0, 1]), optimum=solve(model, steps_left=2))


def test_exact_values_agree_with_returns_played_on_the_real_envs():
    # FrozenLake, slippery, 100-step limit: right along each row, down at its end.
    lake = gym.make("FrozenLake-v1")
    policy = np.where(np.arange(16) % 4 == 3, DOWN, RIGHT)
    exact = evaluate(model_from_env(lake), policy).value
    assert 0.0 < exact < 1.0
    assert within_standard_errors(env_returns(lake, policy, 3000, seed=1), exact)
    # Slippery cliff with a 40-step limit: up, along the top row, then down.
    cliff = TimeLimit(gym.make("CliffWalking-v1", is_slippery=True), 40)
    column = np.arange(48) % 12
    row = np.arange(48) // 12
    policy = np.where(column == 11, C_DOWN, np.where(row == 0, C_RIGHT, C_UP))
    exact = evaluate(model_from_env(cliff), policy).value
    assert within_standard_errors(env_returns(cliff, policy, 1500, seed=2), exact)


def test_large_models_iterate_to_the_same_values(monkeypatch):
    import tui_gym.core.mdp.evaluation as evaluation

    cliff = model_from_env(gym.make("CliffWalking-v1", is_slippery=True))
    policy = solve(cliff).policy
    for gamma in (1.0, 0.9):
        dense = evaluate(cliff, policy, gamma).v
        monkeypatch.setattr(evaluation, "DENSE_LIMIT", 10)
        np.testing.assert_allclose(evaluate(cliff, policy, gamma).v, dense, rtol=1e-9)
        monkeypatch.setattr(evaluation, "DENSE_LIMIT", 2000)


@pytest.mark.parametrize("horizon", [1, 2, 7, 64, 1000, 4099])
@pytest.mark.parametrize("gamma", [1.0, 0.97])
def test_a_long_limit_summed_at_once_is_the_limits_sweeps(horizon, gamma, monkeypatch):
    import tui_gym.core.mdp.evaluation as evaluation

    rng = np.random.default_rng(horizon)
    model = random_model(rng, n_states=12, horizon=horizon, end_chance=0.002)
    policy = rng.dirichlet(np.ones(model.n_actions), size=model.n_states)
    swept = np.zeros(model.n_states)
    matrix = policy_matrix(model, policy)
    for _ in range(horizon):  # the definition: `horizon` backward steps
        swept = (matrix * (model.expected_reward + gamma * (
            model.continue_prob * swept[model.next_state]).sum(axis=2))).sum(axis=1)
    np.testing.assert_allclose(evaluate(model, policy, gamma).v, swept, rtol=1e-10, atol=1e-12)
    monkeypatch.setattr(evaluation, "DOUBLING_STATES", 0)  # sweeps only, as many as it takes
    np.testing.assert_allclose(evaluate(model, policy, gamma).v, swept, rtol=1e-10, atol=1e-12)


def test_a_policy_that_rarely_ends_is_valued_over_the_whole_limit():
    # Room 0 pays 1 a step and is left with chance 1/1000: over 5,000 steps it is worth
    # the sum of 0.999^t, which sweeps settle on only after thousands of them.
    prob = np.array([[[0.999, 0.001]]])
    model = FiniteMDP(np.array([[[0, 0]]]), prob, np.ones((1, 1, 2)),
                      np.array([[[False, True]]]), np.ones(1), horizon=5000)
    value = evaluate(model, np.array([0])).value
    assert value == pytest.approx((1 - 0.999**5000) / 0.001, rel=1e-12)


def test_a_model_survives_pickling():
    import pickle

    taxi = model_from_env(gym.make("Taxi-v4", is_rainy=True))
    copy = pickle.loads(pickle.dumps(taxi))
    assert copy.horizon == taxi.horizon
    np.testing.assert_array_equal(copy.prob, taxi.prob)
    assert solve(copy).value == solve(taxi).value
