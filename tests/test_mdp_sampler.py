"""The engine's one sampler: outcomes and starts that agree in distribution with the env."""

from __future__ import annotations

from collections import defaultdict

import gymnasium as gym
import numpy as np
import pytest

from tests.mdp_support import sampled_returns, within_standard_errors
from tui_gym.core.engine.loop import ModelArrays, sample_outcome, sample_start
from tui_gym.core.mdp import FiniteMDP, evaluate, model_from_env, solve


def frequencies_agree(counts: dict, expected: dict, n: int, sigmas: float = 5.0) -> bool:
    """Every outcome's count within `sigmas` binomial standard deviations of n * p, none extra."""
    if set(counts) - set(expected):
        return False
    for key, p in expected.items():
        spread = sigmas * np.sqrt(n * p * (1 - p)) + 1.0
        if abs(counts.get(key, 0) - n * p) > spread:
            return False
    return True


def draws(model: FiniteMDP, state: int, action: int, n: int, rng) -> list[tuple]:
    """`n` outcomes of one state-action pair drawn by the engine's sampler."""
    arrays = ModelArrays.of(model)
    base = (state * model.n_actions + action) * arrays.outcomes
    found = []
    for _ in range(n):
        at = base + sample_outcome(arrays.cumulative, arrays.guide, base, arrays.outcomes, rng)
        found.append((int(arrays.next_state[at]), float(arrays.reward[at]),
                      bool(arrays.terminal[at])))
    return found


def table_distribution(table, state, action) -> dict:
    merged = defaultdict(float)
    for p, nxt, reward, terminated in table[state][action]:
        merged[int(nxt), float(reward), bool(terminated)] += p
    return merged


@pytest.mark.parametrize("map_name", ["4x4", "8x8"])
def test_every_state_action_follows_the_table(map_name):
    env = gym.make("FrozenLake-v1", map_name=map_name, is_slippery=True)
    model = model_from_env(env)
    n = 1500
    rng = np.random.default_rng(0)
    for state in range(model.n_states):
        for action in range(model.n_actions):
            counts = defaultdict(int)
            for key in draws(model, state, action, n, rng):
                counts[key] += 1
            expected = table_distribution(env.unwrapped.P, state, action)
            assert frequencies_agree(counts, expected, n), (state, action, dict(counts))


def test_the_real_env_follows_the_model():
    """Step the real slippery lake from every state-action pair: its frequencies are the model's."""
    env = gym.make("FrozenLake-v1", is_slippery=True).unwrapped
    model = model_from_env(env)
    env.reset(seed=5)
    n = 300
    for state in range(model.n_states):
        for action in range(model.n_actions):
            counts = defaultdict(int)
            for _ in range(n):
                env.s = state
                nxt, reward, terminated, _, _ = env.step(action)
                counts[int(nxt), float(reward), bool(terminated)] += 1
            expected = {(s, r, t): p for p, s, r, t in model.outcomes(state, action)}
            assert frequencies_agree(counts, expected, n), (state, action)


def test_resets_follow_the_initial_distribution():
    model = model_from_env(gym.make("Taxi-v4"))
    arrays = ModelArrays.of(model)
    n = 60_000
    rng = np.random.default_rng(1)
    starts = np.array([sample_start(arrays.starts, arrays.start_cumulative, rng)
                       for _ in range(n)])
    counts = np.bincount(starts, minlength=model.n_states)
    assert (counts[model.initial == 0] == 0).all()
    expected = n * model.initial
    spread = 5 * np.sqrt(expected * (1 - model.initial)) + 1
    assert (np.abs(counts - expected) <= spread).all()


def test_an_impossible_outcome_is_never_drawn():
    table = {
        0: {0: [(0.5, 0, 1.0, False), (0.0, 1, 9.0, False), (0.5, 1, 2.0, True)]},
        1: {0: [(1.0, 1, 0.0, True)]},
    }
    model = FiniteMDP.from_table(table, [1.0, 0.0])
    # Keep the impossible outcome in the middle of the row, where round-off could reach it.
    prob = np.array([[[0.5, 0.0, 0.5]], [[1.0, 0.0, 0.0]]])
    padded = FiniteMDP(
        next_state=np.array([[[0, 1, 1]], [[1, 1, 1]]]),
        prob=prob,
        reward=np.array([[[1.0, 9.0, 2.0]], [[0.0, 0.0, 0.0]]]),
        terminal=np.array([[[False, False, True]], [[True, False, False]]]),
        initial=[1.0, 0.0],
    )
    for m in (model, padded):
        found = draws(m, 0, 0, 20_000, np.random.default_rng(2))
        assert {r for _, r, _ in found} == {1.0, 2.0}
        assert abs(np.mean([t for _, _, t in found]) - 0.5) < 0.02


def test_among_many_outcomes_the_guide_finds_the_outcome_the_scan_finds():
    # Jack's car rental (441 outcomes a move) and a row of many outcomes where every
    # other one is impossible: each draw is the first outcome whose cumulative
    # probability exceeds u, as a scan from the first finds it.
    from tui_gym.games import game_for

    rental = game_for("car-rental").base_model({})
    k = 40
    prob = np.zeros((1, 1, k))
    prob[0, 0, ::2] = np.linspace(1.0, 3.0, k // 2)
    prob /= prob.sum()
    sparse = FiniteMDP(np.zeros((1, 1, k), dtype=np.int64), prob, np.arange(k)[None, None, :],
                       np.ones((1, 1, k), dtype=bool), [1.0])
    for model, pairs in ((rental, range(0, rental.n_states * rental.n_actions, 97)),
                         (sparse, [0])):
        arrays = ModelArrays.of(model)
        assert arrays.outcomes > 16
        for pair in pairs:
            base = int(arrays.pair_rows[pair]) * arrays.outcomes
            row = arrays.cumulative[base: base + arrays.outcomes]
            drawn, again = np.random.default_rng(pair), np.random.default_rng(pair)
            for _ in range(300):
                scanned = min(int(np.searchsorted(row, again.random(), side="right")),
                              arrays.outcomes - 1)
                assert sample_outcome(arrays.cumulative, arrays.guide, base,
                                      arrays.outcomes, drawn) == scanned


def test_the_same_seed_gives_the_same_draws():
    model = model_from_env(gym.make("FrozenLake-v1"))
    assert draws(model, 5, 2, 200, np.random.default_rng(9)) == draws(
        model, 5, 2, 200, np.random.default_rng(9))


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("FrozenLake8x8-v1", {}),
        ("CliffWalking-v1", {"is_slippery": True, "max_episode_steps": 100}),
        ("Taxi-v4", {"is_rainy": True}),
    ],
)
def test_sampled_returns_agree_with_the_exact_value(env_id, kwargs):
    model = model_from_env(gym.make(env_id, **kwargs))
    policy = solve(model).policy
    exact = evaluate(model, policy).value
    returns = sampled_returns(model, policy, 10_000, np.random.default_rng(6))
    assert within_standard_errors(returns, exact)
    # A stochastic policy too: half the time a uniformly random action.
    mixed = np.full((model.n_states, model.n_actions), 0.5 / model.n_actions)
    mixed[np.arange(model.n_states), policy] += 0.5
    exact = evaluate(model, mixed).value
    returns = sampled_returns(model, mixed, 10_000, np.random.default_rng(7))
    assert within_standard_errors(returns, exact)


def test_sampled_discounted_returns_with_no_limit():
    model = model_from_env(gym.make("CliffWalking-v1", is_slippery=True))
    policy = solve(model, gamma=0.9).policy
    exact = evaluate(model, policy, gamma=0.9).value
    # Cut at 400 steps: 0.9^400 of any return left over is far below the sampling error.
    returns = sampled_returns(
        model, policy, 20_000, np.random.default_rng(8), gamma=0.9, max_steps=400
    )
    assert within_standard_errors(returns, exact)
