"""Tests for `tui_gym.games.gridworld.batched`: batched GridWorld moves like the env.

Every (agent, target, action) on sizes 2..6 is stepped in both engines and
compared; the time limit, the starting distribution (a chi-square bound from
the sample size) and the catalog's reward wrappers, read from a built env by
`plan_for_env`, are checked against the scalar stack.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from tests.game_support import form_of
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.vector import NoBatchedForm, plan_for_env
from tui_gym.core.wrappers import WrapperChoice, build_env
from tui_gym.envs.gridworld import GridWorldEnv
from tui_gym.games.gridworld.batched import BatchedGridWorld
from tui_gym.games.gridworld.paths import all_pairs
from tui_gym.session.session import vector_support


def chi2_bound(df: int, z: float = 4.5) -> float:
    """The upper z-sigma quantile of chi-square(df), by the Wilson-Hilferty approximation."""
    c = 2.0 / (9.0 * df)
    return df * (1.0 - c + z * math.sqrt(c)) ** 3


def _flat(obs: dict[str, np.ndarray]) -> tuple[int, ...]:
    return (*(int(v) for v in obs["agent"]), *(int(v) for v in obs["target"]))


@pytest.mark.parametrize("size", [2, 3, 4, 5, 6])
@pytest.mark.parametrize("rewards", [(1.0, 0.0), (2.5, 0.1)], ids=["default", "scaled"])
def test_every_transition_matches_the_env(size: int, rewards: tuple[float, float]) -> None:
    reward_scale, step_penalty = rewards
    pairs = all_pairs(size)
    starts = np.repeat(pairs, 4, axis=0)
    actions = np.tile(np.arange(4), len(pairs))
    batched = BatchedGridWorld(len(starts), size, reward_scale, step_penalty, seed=0)
    batched.state[:] = starts
    result = batched.step(actions, autoreset=False)

    scalar = GridWorldEnv(size=size, reward_scale=reward_scale, step_penalty=step_penalty)
    keyer = ObservationKeyer(scalar.observation_space)
    keys = keyer.keys(result.next_obs)
    for i, (start, action) in enumerate(zip(starts, actions, strict=True)):
        scalar.reset(options={"agent": start[:2], "target": start[2:]})
        obs, reward, terminated, truncated, info = scalar.step(int(action))
        assert tuple(result.next_obs[i]) == _flat(obs)
        assert keys[i] == keyer.key(obs)
        assert result.reward[i] == reward
        assert bool(result.terminated[i]) == terminated
        assert not result.truncated[i] and not truncated
        assert result.info["distance"][i] == info["distance"]
    assert result.terminated.any()


def test_truncation_at_the_time_limit_like_the_registered_env() -> None:
    steps = 7
    scalar = gym.make("tui_gym/GridWorld-v0", size=5, max_episode_steps=steps)
    batched = BatchedGridWorld(3, 5, max_episode_steps=steps, seed=0)
    batched.state[:] = [[0, 0, 4, 4], [0, 0, 4, 4], [4, 4, 0, 4]]
    scalar.reset(options={"agent": (0, 0), "target": (4, 4)})
    for step in range(1, steps + 1):
        # env 0 walks into the wall; env 1 too; env 2 reaches its target on step 4
        result = batched.step(np.array([2, 3, 2]), autoreset=False)
        _, _, terminated, truncated, _ = scalar.step(2)
        assert bool(result.truncated[0]) == truncated == (step == steps)
        assert not result.terminated[0] and not terminated
        if step == 4:
            assert result.terminated[2]
            batched.state[2] = [4, 4, 0, 4]  # start it over by hand, elapsed keeps counting
    assert batched.elapsed.tolist() == [steps, steps, steps]


def test_autoreset_reports_the_end_then_a_fresh_start() -> None:
    env = BatchedGridWorld(4, 3, max_episode_steps=2, seed=5)
    env.state[:] = [[0, 0, 1, 0], [0, 0, 2, 2], [1, 1, 1, 2], [2, 2, 0, 0]]
    result = env.step(np.array([0, 0, 3, 1]))
    assert result.terminated.tolist() == [True, False, False, False]
    assert tuple(result.next_obs[0]) == (1, 0, 1, 0)  # the final observation
    assert tuple(result.obs[0]) == tuple(env.state[0])  # the new start
    assert env.elapsed.tolist() == [0, 1, 1, 1]
    result = env.step(np.array([0, 0, 3, 1]))
    assert result.truncated[1:].all()
    assert (env.elapsed[1:] == 0).all()
    assert ((env.state[:, :2] != env.state[:, 2:]).any(axis=1)).all()


@pytest.mark.parametrize("size", [2, 3, 4])
def test_starts_are_uniform_over_distinct_placements(size: int) -> None:
    n = 300_000
    env = BatchedGridWorld(n, size, seed=size)
    rows = env.reset()
    assert ((rows[:, :2] != rows[:, 2:]).any(axis=1)).all()
    assert rows.min() >= 0 and rows.max() < size
    cells = ((rows[:, 0] * size + rows[:, 1]) * size + rows[:, 2]) * size + rows[:, 3]
    counts = np.bincount(cells, minlength=size**4)
    pairs = all_pairs(size)
    allowed = ((pairs[:, 0] * size + pairs[:, 1]) * size + pairs[:, 2]) * size + pairs[:, 3]
    assert counts.sum() == counts[allowed].sum()
    expected = n / len(allowed)
    chi2 = float(((counts[allowed] - expected) ** 2 / expected).sum())
    assert chi2 < chi2_bound(len(allowed) - 1)


def test_starts_match_the_scalar_env() -> None:
    """Distance from agent to target at reset: scalar env vs batched, two-sample bounds."""
    scalar = GridWorldEnv(size=5)
    n_scalar = 20_000
    scalar.reset(seed=3)
    d_scalar = np.array([scalar.reset()[1]["distance"] for _ in range(n_scalar)])
    env = BatchedGridWorld(200_000, 5, seed=3)
    env.reset()
    d_batched = env.distances()
    for d in range(1, 9):
        p_a = np.count_nonzero(d_scalar == d) / n_scalar
        p_b = np.count_nonzero(d_batched == d) / len(d_batched)
        p = (p_a * n_scalar + p_b * len(d_batched)) / (n_scalar + len(d_batched))
        bound = 4 * math.sqrt(p * (1 - p) * (1 / n_scalar + 1 / len(d_batched)))
        assert abs(p_a - p_b) < bound


WRAPPED = [
    WrapperChoice.make("StepPenalty", penalty=0.05),
    WrapperChoice.make("DistanceShaping", k=0.2),
    WrapperChoice.make("ScaleReward", factor=3.0),
    WrapperChoice.make("ClipReward", min_reward=-0.9, max_reward=2.0),
    WrapperChoice.make("TimeLimit", max_episode_steps=12),
]


def test_reward_wrappers_and_time_limit_match_the_built_env() -> None:
    """Random walks in lockstep through the catalog's stack and the batched plan."""
    env = build_env("tui_gym/GridWorld-v0", {"size": 4, "reward_scale": 2.0}, WRAPPED)
    plan = plan_for_env(env, form_of(env))
    assert plan.max_episode_steps == 12
    assert [t.name for t in plan.rewards] == [
        "StepPenalty",
        "DistanceShaping",
        "ScaleReward",
        "ClipReward",
    ]
    batched = plan.make_env(1, seed=0)
    rng = np.random.default_rng(8)
    endings = {"terminated": 0, "truncated": 0}
    for episode in range(300):
        obs, _ = env.reset(seed=episode)
        batched.reset()
        batched.state[0] = _flat(obs)
        done = False
        while not done:
            action = int(rng.integers(4))
            obs, reward, terminated, truncated, _ = env.step(action)
            result = batched.step(np.array([action]), autoreset=False)
            shaped = plan.transform_rewards(result.reward, result.info)
            assert tuple(result.next_obs[0]) == _flat(obs)
            assert shaped[0] == pytest.approx(reward, abs=1e-12)
            assert (bool(result.terminated[0]), bool(result.truncated[0])) == (
                terminated,
                truncated,
            )
            done = terminated or truncated
        endings["terminated" if terminated else "truncated"] += 1
    assert min(endings.values()) > 20


def test_the_registered_time_limit_is_300() -> None:
    grid = build_env("tui_gym/GridWorld-v0", {"size": 5})
    plan = plan_for_env(grid, form_of(grid))
    assert plan.max_episode_steps == 300
    assert plan.describe() == "vector engine: GridWorld 5x5"
    longer = build_env(
        "tui_gym/GridWorld-v0",
        {"size": 5},
        [WrapperChoice.make("TimeLimit", max_episode_steps=500)],
    )
    assert plan_for_env(longer, form_of(longer)).max_episode_steps == 500


@pytest.mark.parametrize(
    ("env_id", "choices", "supported", "words"),
    [
        ("Blackjack-v1", [], True, "vector engine: Blackjack"),
        ("Blackjack-v1", [WrapperChoice.make("StepPenalty")], True, "Blackjack with StepPenalty"),
        ("Blackjack-v1", [WrapperChoice.make("TimeLimit", max_episode_steps=5)], True, "TimeLimit"),
        ("tui_gym/GridWorld-v0", WRAPPED, True, "GridWorld 5x5 with StepPenalty, DistanceShaping"),
        ("tui_gym/GridWorld-v0", [WrapperChoice.make("ClipReward")], True, "ClipReward"),
        ("Blackjack-v1", [WrapperChoice.make("DelayObservation")], False, "DelayObservation"),
        ("Blackjack-v1", [WrapperChoice.make("FlattenObservation")], False, "FlattenObservation"),
        ("tui_gym/GridWorld-v0", [WrapperChoice.make("StickyAction")], False, "StickyAction"),
        (
            "tui_gym/GridWorld-v0",
            [WrapperChoice.make("TimeAwareObservation")],
            False,
            "TimeAwareObservation",
        ),
        ("CartPole-v1", [], False, "CartPole-v1 does not fit"),
    ],
)
def test_vector_support_says_what_and_why(
    env_id: str, choices: list[WrapperChoice], supported: bool, words: str
) -> None:
    ok, reason = vector_support(env_id, {"size": 5} if "Grid" in env_id else {}, choices)
    assert ok is supported
    assert words in reason
    assert reason.startswith("vector engine: " if supported else "scalar engine: ")


def test_an_unbatchable_env_raises_with_the_reason() -> None:
    env = build_env("Blackjack-v1", {}, [WrapperChoice.make("StickyAction")])
    with pytest.raises(NoBatchedForm, match="StickyAction has no batched form"):
        plan_for_env(env, form_of(env))


def test_bad_arguments_are_rejected() -> None:
    with pytest.raises(ValueError):
        BatchedGridWorld(4, size=1)
    with pytest.raises(ValueError):
        BatchedGridWorld(4, step_penalty=-1.0)
    env = BatchedGridWorld(2, 3, seed=0)
    env.reset()
    with pytest.raises(ValueError):
        env.step(np.array([0, 4]))
