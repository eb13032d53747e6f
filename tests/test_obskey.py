"""Observation keys: dense ints for small integer spaces, tuples otherwise, clear refusals."""

from __future__ import annotations

import itertools
from collections.abc import Hashable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.core.obskey import DENSE_STATE_LIMIT, NotTabularError, ObservationKeyer
from tui_gym.core.wrappers import WrapperChoice, build_env

GRID = "tui_gym/GridWorld-v0"
W = WrapperChoice.make


def _all_blackjack_observations() -> list[tuple[int, int, int]]:
    return list(itertools.product(range(32), range(11), range(2)))


def _all_grid_observations(size: int = 5) -> list[dict[str, np.ndarray]]:
    rows = np.indices((size,) * 4).reshape(4, -1).T
    return [{"agent": row[:2].copy(), "target": row[2:].copy()} for row in rows]


# -- dense keys -----------------------------------------------------------------


def test_blackjack_tuple_keys_are_dense_distinct_and_decodable() -> None:
    keyer = ObservationKeyer(gym.make("Blackjack-v1").observation_space)
    assert keyer.dense and keyer.n_states == 32 * 11 * 2
    observations = _all_blackjack_observations()
    keys = [keyer.key(obs) for obs in observations]
    assert all(isinstance(k, int) for k in keys)
    assert sorted(keys) == list(range(keyer.n_states))  # distinct and covering the range
    for obs, key in zip(observations, keys, strict=True):
        assert keyer.decode(key) == obs
    batched = keyer.keys(np.array(observations))
    assert batched.tolist() == keys


def test_gridworld_dict_keys_are_dense_distinct_and_decodable() -> None:
    keyer = ObservationKeyer(gym.make(GRID).observation_space)
    assert keyer.dense and keyer.n_states == 5**4
    observations = _all_grid_observations()
    keys = [keyer.key(obs) for obs in observations]
    assert sorted(keys) == list(range(keyer.n_states))
    for obs, key in zip(observations, keys, strict=True):
        assert keyer.decode(key) == (*obs["agent"].tolist(), *obs["target"].tolist())
    flat = np.array([[*o["agent"], *o["target"]] for o in observations])
    assert keyer.keys(flat).tolist() == keys


def test_dense_keys_of_a_stepped_env_stay_in_range_and_follow_the_observation() -> None:
    env = gym.make("Blackjack-v1")
    keyer = ObservationKeyer(env.observation_space)
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=0)
    for _ in range(300):
        key = keyer.key(obs)
        assert 0 <= key < keyer.n_states
        assert keyer.decode(key) == tuple(int(v) for v in obs)
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(2)))
        if terminated or truncated:
            obs, _ = env.reset()


@pytest.mark.parametrize(
    ("space", "n_states", "example", "flat"),
    [
        (spaces.Discrete(3, start=-1), 3, -1, (-1,)),
        (spaces.MultiDiscrete([2, 3]), 6, np.array([1, 2]), (1, 2)),
        (spaces.MultiBinary(3), 8, np.array([1, 0, 1], dtype=np.int8), (1, 0, 1)),
        (spaces.Box(-3, 3, (2,), dtype=np.int8), 49, np.array([-3, 3], dtype=np.int8), (-3, 3)),
    ],
)
def test_other_integer_spaces_are_dense(
    space: spaces.Space, n_states: int, example: Any, flat: tuple[int, ...]
) -> None:
    keyer = ObservationKeyer(space)
    assert keyer.n_states == n_states
    key = keyer.key(example)
    assert 0 <= key < n_states
    assert keyer.decode(key) == flat
    space.seed(0)
    samples = [space.sample() for _ in range(50)]
    assert all(0 <= keyer.key(s) < n_states for s in samples)


def test_integer_spaces_too_big_for_an_array_go_sparse_instead_of_overflowing() -> None:
    big = ObservationKeyer(spaces.Box(0, 10**6, (2,), dtype=np.int64))
    assert DENSE_STATE_LIMIT < (10**6 + 1) ** 2
    assert not big.dense and big.key(np.array([5, 7])) == (5, 7)
    # A range as wide as the dtype once wrapped round to a negative state count.
    huge = ObservationKeyer(spaces.Box(0, np.iinfo(np.int64).max, (1,), dtype=np.int64))
    assert not huge.dense and huge.n_states is None
    assert huge.key(np.array([2**62])) == (2**62,)


# -- sparse keys from wrapped envs ----------------------------------------------


WRAPPED = {
    "flatten blackjack": ("Blackjack-v1", [W("FlattenObservation")]),
    "flatten gridworld": (GRID, [W("FlattenObservation")]),
    "time-aware flat": (GRID, [W("TimeAwareObservation")]),
    "time-aware dict": (GRID, [W("TimeAwareObservation", flatten=False)]),
    "time-aware normalized": (
        GRID,
        [W("TimeLimit", max_episode_steps=40), W("TimeAwareObservation", normalize_time=True)],
    ),
    "time-aware blackjack tuple": (
        "Blackjack-v1",
        [
            W("TimeLimit", max_episode_steps=5),
            W("TimeAwareObservation", flatten=False, normalize_time=True),
        ],
    ),
    "delay gridworld": (GRID, [W("DelayObservation", delay=2)]),
    "delay blackjack": ("Blackjack-v1", [W("DelayObservation")]),
}


def _fingerprint(space: spaces.Space, obs: Any) -> tuple[float, ...]:
    """The observation's content, independently of the keyer, to compare observations."""
    return tuple(np.asarray(spaces.flatten(space, obs), dtype=np.float64).tolist())


@pytest.mark.parametrize("case", list(WRAPPED))
def test_wrapped_observations_give_hashable_keys_equal_exactly_when_observations_are(
    case: str,
) -> None:
    env_id, choices = WRAPPED[case]
    env = build_env(env_id, choices=choices)
    keyer = ObservationKeyer(env.observation_space)
    rng = np.random.default_rng(1)
    seen: dict[Hashable, tuple[float, ...]] = {}
    obs, _ = env.reset(seed=1)
    for _ in range(400):
        key = keyer.key(obs)
        hash(key)
        if keyer.dense:
            assert 0 <= key < keyer.n_states
        else:
            assert isinstance(key, tuple)
            assert all(type(v) in (int, float) for v in key)  # plain Python numbers
        content = _fingerprint(env.observation_space, obs)
        assert seen.setdefault(key, content) == content, "one key for two different observations"
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(env.action_space.n)))
        if terminated or truncated:
            obs, _ = env.reset()
    by_print: dict[tuple[float, ...], Hashable] = {}
    for key, content in seen.items():
        assert by_print.setdefault(content, key) == key, "two keys for one observation"
    assert len(seen) > 10


def test_flattened_blackjack_is_sparse_and_keys_its_one_hot_vector() -> None:
    env = build_env("Blackjack-v1", choices=[W("FlattenObservation")])
    keyer = ObservationKeyer(env.observation_space)
    assert not keyer.dense  # 2**45 one-hot combinations: too many rows for an array
    obs, _ = env.reset(seed=0)
    key = keyer.key(obs)
    assert key == tuple(int(v) for v in obs) and sum(key) == 3
    assert keyer.key(obs.copy()) == key
    with pytest.raises(NotTabularError, match="dense"):
        keyer.keys(obs[None, :])
    with pytest.raises(NotTabularError, match="dense"):
        keyer.decode(0)


def test_time_aware_observation_keys_include_the_time() -> None:
    choices = [W("TimeLimit", max_episode_steps=8), W("TimeAwareObservation", normalize_time=True)]
    env = build_env(GRID, choices=choices)
    keyer = ObservationKeyer(env.observation_space)
    obs, _ = env.reset(seed=0, options={"agent": (0, 0), "target": (4, 4)})
    first = keyer.key(obs)
    obs, *_ = env.step(2)  # into the wall: same cell, one step later
    second = keyer.key(obs)
    assert first[:4] == second[:4] == (0, 0, 4, 4)
    assert first[4] == 0.0 and second[4] == 0.125
    assert first != second


def test_delayed_observations_key_the_zeros_then_the_past() -> None:
    env = build_env(GRID, choices=[W("DelayObservation", delay=1)])
    keyer = ObservationKeyer(env.observation_space)
    obs, _ = env.reset(seed=0, options={"agent": (2, 2), "target": (4, 4)})
    assert keyer.decode(keyer.key(obs)) == (0, 0, 0, 0)
    obs, *_ = env.step(0)
    assert keyer.decode(keyer.key(obs)) == (2, 2, 4, 4)


# -- floats ---------------------------------------------------------------------


def test_float_rounding_makes_equal_values_equal_keys() -> None:
    keyer = ObservationKeyer(spaces.Box(-1.0, 1.0, (2,), dtype=np.float64))
    assert not keyer.dense
    assert keyer.key(np.array([0.1 + 0.2, 0.5])) == keyer.key(np.array([0.3, 0.5]))
    assert keyer.key(np.array([-0.0, 0.5])) == keyer.key(np.array([0.0, 0.5]))
    assert keyer.key(np.array([0.1, 0.5], dtype=np.float32)) == (0.1, 0.5)
    assert keyer.key(np.array([0.3, 0.5])) != keyer.key(np.array([0.3001, 0.5]))
    assert {keyer.key(np.array([0.3, 0.5])): "x"}[(0.3, 0.5)] == "x"


def test_mixed_tuple_of_discrete_and_float_is_sparse() -> None:
    keyer = ObservationKeyer(
        spaces.Tuple((spaces.Discrete(4), spaces.Box(0.0, 1.0, (1,), dtype=np.float32)))
    )
    assert not keyer.dense
    assert keyer.key((np.int64(3), np.array([0.25], dtype=np.float32))) == (3, 0.25)


# -- refusals -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("space", "fragment"),
    [
        (spaces.Text(8), "Text space"),
        (spaces.Graph(node_space=spaces.Box(0, 1, (2,)), edge_space=None), "Graph space"),
        (spaces.Sequence(spaces.Discrete(2)), "Sequence space"),
        (spaces.Box(0.0, 1.0, (100, 100), dtype=np.float32), "Box of 10000 floats"),
        (spaces.Box(-np.inf, np.inf, (2,), dtype=np.int64), "no finite range"),
        (spaces.Box(0, np.inf, (3,), dtype=np.int32), "no finite range"),
        (spaces.Tuple((spaces.Discrete(2), spaces.Text(4))), "observation[1] is a Text"),
        (spaces.Dict({"pos": spaces.Discrete(2), "name": spaces.Text(4)}), "['name']"),
    ],
)
def test_untabular_spaces_are_refused_with_the_reason(space: spaces.Space, fragment: str) -> None:
    with pytest.raises(NotTabularError) as caught:
        ObservationKeyer(space)
    message = str(caught.value)
    assert fragment in message
    assert "\n" not in message
    assert isinstance(caught.value, ValueError)  # front ends catch ValueError


def test_repr_says_dense_or_sparse() -> None:
    assert "dense, 704 states" in repr(ObservationKeyer(gym.make("Blackjack-v1").observation_space))
    assert "sparse" in repr(ObservationKeyer(spaces.Box(0.0, 1.0, (2,))))


def test_signature_tells_whether_keys_mean_the_same() -> None:
    a = ObservationKeyer(gym.make(GRID).observation_space)
    b = ObservationKeyer(gym.make(GRID).observation_space)
    c = ObservationKeyer(gym.make(GRID, size=4).observation_space)
    assert a.signature == b.signature != c.signature
