"""model_from_env: Gymnasium's toy-text tables become exact models; misfits say why."""

from __future__ import annotations

from collections import defaultdict

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.wrappers import ClipReward, StickyAction, TimeLimit

from tui_gym.core.mdp import FiniteMDP, NotAvailable, model_from_env
from tui_gym.core.wrappers.catalog import DistanceShaping, ScaleReward, StepPenalty

GAMES = [
    ("FrozenLake-v1", {"is_slippery": False}, 100),
    ("FrozenLake-v1", {"is_slippery": True}, 100),
    ("FrozenLake-v1", {"map_name": "8x8", "is_slippery": False}, 100),
    ("FrozenLake8x8-v1", {"is_slippery": True}, 200),
    ("CliffWalking-v1", {"is_slippery": False}, None),
    ("CliffWalking-v1", {"is_slippery": True}, None),
    ("Taxi-v4", {}, 200),
    ("Taxi-v4", {"is_rainy": True}, 200),
]


def merged_table(table, state, action):
    merged = defaultdict(float)
    for p, nxt, reward, terminated in table[state][action]:
        if p > 0:
            merged[int(nxt), float(reward), bool(terminated)] += p
    return merged


@pytest.mark.parametrize(("env_id", "kwargs", "limit"), GAMES)
def test_model_holds_the_table_and_the_limit(env_id, kwargs, limit):
    env = gym.make(env_id, **kwargs)
    model = model_from_env(env)
    assert isinstance(model, FiniteMDP)
    base = env.unwrapped
    assert (model.n_states, model.n_actions) == (base.observation_space.n, base.action_space.n)
    assert model.horizon == limit
    np.testing.assert_array_equal(model.initial, base.initial_state_distrib)
    for state in range(model.n_states):
        for action in range(model.n_actions):
            expected = merged_table(base.P, state, action)
            got = {(n, r, t): p for p, n, r, t in model.outcomes(state, action)}
            assert got.keys() == expected.keys(), (state, action)
            for key, p in expected.items():
                assert got[key] == pytest.approx(p, abs=1e-12), (state, action, key)


def test_the_limit_can_be_overridden_and_the_tightest_counts():
    assert model_from_env(gym.make("CliffWalking-v1"), horizon=50).horizon == 50
    assert model_from_env(gym.make("FrozenLake-v1"), horizon=None).horizon is None
    assert model_from_env(gym.make("FrozenLake-v1", max_episode_steps=7)).horizon == 7
    stacked = TimeLimit(StepPenalty(gym.make("FrozenLake-v1"), 0.1), 30)
    assert model_from_env(stacked).horizon == 30
    assert model_from_env(TimeLimit(gym.make("FrozenLake-v1"), 300)).horizon == 100
    with pytest.raises(ValueError, match="horizon"):
        model_from_env(gym.make("FrozenLake-v1"), horizon=0)


def test_reward_wrappers_apply_innermost_first():
    base = model_from_env(gym.make("CliffWalking-v1"))
    env = ClipReward(StepPenalty(ScaleReward(gym.make("CliffWalking-v1"), 0.1), 0.5), -5.0, 0.0)
    model = model_from_env(env)
    assert isinstance(model, FiniteMDP)
    # -1 -> -0.1 -> -0.6; -100 -> -10 -> -10.5 -> clipped to -5.
    expected = np.clip(0.1 * base.reward - 0.5, -5.0, 0.0)
    possible = base.prob > 0
    np.testing.assert_allclose(model.reward[possible], expected[possible])


def test_an_initial_distribution_can_be_given():
    env = gym.make("FrozenLake-v1", is_slippery=False)
    start = np.zeros(16)
    start[5 - 1] = 1.0
    model = model_from_env(env, initial=start)
    assert isinstance(model, FiniteMDP)
    np.testing.assert_array_equal(model.initial, start)
    with pytest.raises(ValueError, match="shape"):
        model_from_env(env, initial=np.ones(4) / 4)
    with pytest.raises(ValueError, match="probability distribution"):
        model_from_env(env, initial=np.ones(16))


class TableOnly(gym.Env):
    """Discrete spaces and a table, but no initial distribution."""

    def __init__(self, with_table: bool = True):
        self.observation_space = spaces.Discrete(2)
        self.action_space = spaces.Discrete(1)
        if with_table:
            self.P = {0: {0: [(1.0, 1, 1.0, False)]}, 1: {0: [(1.0, 1, 0.0, True)]}}


def test_an_env_without_an_initial_distribution_needs_one_passed():
    missing = model_from_env(TableOnly())
    assert isinstance(missing, NotAvailable)
    assert "initial-state distribution" in missing.reason
    model = model_from_env(TableOnly(), initial=[1.0, 0.0])
    assert isinstance(model, FiniteMDP) and model.outcomes(0, 0) == [(1.0, 1, 1.0, False)]


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: gym.make("CartPole-v1"), "observation space is Box"),
        (lambda: gym.make("Blackjack-v1"), "observation space is Tuple"),
        (lambda: TableOnly(with_table=False), "no transition table P"),
        (lambda: StickyAction(gym.make("FrozenLake-v1"), 0.25), "with StickyAction"),
        (lambda: DistanceShaping(gym.make("FrozenLake-v1"), 0.1), "with DistanceShaping"),
        (lambda: object(), "not a Gymnasium env"),
        (
            lambda: ClipReward(gym.make("FrozenLake-v1"), np.zeros(2), np.ones(2)),
            "with ClipReward",
        ),
    ],
)
def test_an_env_that_does_not_fit_gets_one_line_saying_why(make, words):
    result = model_from_env(make())
    assert isinstance(result, NotAvailable)
    assert words in result.reason and "\n" not in result.reason


def test_a_broken_table_is_not_available_rather_than_an_error():
    env = TableOnly()
    env.P[1][0] = [(0.5, 1, 0.0, True)]
    result = model_from_env(env, initial=[1.0, 0.0])
    assert isinstance(result, NotAvailable)
    assert "sum to 0.5" in result.reason


def test_taxi_fickle_passenger_is_not_in_its_table():
    """The fickle passenger changes destination inside `step`, outside `P`: no exact model."""
    plain = model_from_env(gym.make("Taxi-v4"))
    fickle_env = gym.make("Taxi-v4", fickle_passenger=True, fickle_probability=1.0)
    fickle = model_from_env(fickle_env)
    assert isinstance(plain, FiniteMDP) and isinstance(fickle, FiniteMDP)
    np.testing.assert_array_equal(plain.next_state, fickle.next_state)
    # Play it: pick the passenger up and drive off; the table never changes a destination.
    base = fickle_env.unwrapped
    state, _ = fickle_env.reset(seed=3)
    row, col, passenger, destination = base.decode(state)
    base.s = base.encode(*base.locs[passenger], passenger, destination)
    state, *_ = fickle_env.step(4)  # pickup
    moved = [
        a
        for a in range(4)
        if base.decode(plain.outcomes(state, a)[0][1])[:2] != base.locs[passenger]
    ]
    after, *_ = fickle_env.step(moved[0])
    assert base.decode(after)[3] != destination
    assert all(base.decode(n)[3] == destination for _, n, _, _ in plain.outcomes(state, moved[0]))
