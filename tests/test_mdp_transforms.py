"""The model of a wrapped game: ScaleReward, StepPenalty, ClipReward and TimeLimit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import ClipReward, TimeLimit, TransformReward

from tests.mdp_support import env_returns, within_standard_errors
from tui_gym.core.mdp import evaluate, model_from_env, solve, with_horizon
from tui_gym.core.wrappers import get_spec
from tui_gym.core.wrappers.catalog import ScaleReward, StepPenalty


def lake(wrapper=None, *args, **kwargs):
    env = gym.make("FrozenLake-v1", **kwargs)
    return model_from_env(env if wrapper is None else wrapper(env, *args))


def test_scaling_scales_every_value():
    base = lake()
    scaled = lake(ScaleReward, 2.5)
    np.testing.assert_allclose(solve(scaled).q, 2.5 * solve(base).q)
    # A negative factor makes the goal a thing to avoid: the best is never to reach it.
    assert solve(lake(ScaleReward, -1.0)).value == 0.0


def test_a_step_penalty_makes_the_shortest_path_worth_most():
    penalised = lake(StepPenalty, 0.1, is_slippery=False)
    # Six steps to the goal: 1 - 6 * 0.1.
    assert solve(penalised).value == pytest.approx(0.4)
    # Over a 100-step limit, wandering for ever costs 100 * 0.1.
    assert evaluate(penalised, np.zeros(16, dtype=int)).value == pytest.approx(-10.0)


def test_clipping_is_per_outcome():
    taxi = model_from_env(gym.make("Taxi-v4"))
    clipped = model_from_env(ClipReward(gym.make("Taxi-v4"), -1.0, 1.0))
    assert set(np.unique(clipped.reward[clipped.prob > 0])) == {-1.0, 1.0}
    # Every ride: n - 1 steps at -1, then the drop-off at +1 instead of +20.
    assert solve(clipped).value == pytest.approx(solve(taxi).value - 19.0)
    only_low = model_from_env(ClipReward(gym.make("CliffWalking-v1"), min_reward=-1.0))
    assert only_low.reward.min() == -1.0


def test_a_different_limit():
    deterministic = lake(is_slippery=False)
    assert with_horizon(deterministic, 6).horizon == 6
    assert solve(with_horizon(deterministic, 5)).value == 0.0
    assert with_horizon(deterministic, None).horizon is None


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda m: ScaleReward(gym.make("FrozenLake-v1"), float("nan")),
         "ScaleReward factor must be a finite number"),
        (lambda m: StepPenalty(gym.make("FrozenLake-v1"), -0.5),
         "StepPenalty penalty must be a finite number >= 0"),
        (lambda m: get_spec("ClipReward").validate({"min_reward": 1.0, "max_reward": 0.0}),
         "min_reward \\(1.0\\) must be <= ClipReward.max_reward \\(0.0\\)"),
        (lambda m: with_horizon(m, 0), "horizon must be >= 1"),
    ],
)
def test_bad_arguments_say_which(call, message):
    with pytest.raises(ValueError, match=message):
        call(lake())


def test_clipping_needs_a_bound():
    with pytest.raises(gym.error.InvalidBound, match="min_reward"):
        ClipReward(gym.make("FrozenLake-v1"))


def test_the_model_of_a_wrapped_env_is_the_transformed_model():
    env = TimeLimit(
        ClipReward(StepPenalty(ScaleReward(gym.make("FrozenLake-v1"), 2.0), 0.1), -0.15, 5.0), 50
    )
    wrapped = model_from_env(env)
    base = lake()
    expected = with_horizon(base.replace(reward=np.clip(2.0 * base.reward - 0.1, -0.15, 5.0)), 50)
    np.testing.assert_array_equal(wrapped.reward, expected.reward)
    assert wrapped.horizon == 50
    assert solve(wrapped).value == solve(expected).value


def test_exact_values_of_a_wrapped_env_agree_with_its_returns():
    env = StepPenalty(ScaleReward(gym.make("FrozenLake-v1"), 10.0), 0.2)
    model = model_from_env(env)
    policy = solve(model).policy
    exact = evaluate(model, policy).value
    assert within_standard_errors(env_returns(env, policy, 800, seed=4), exact)


def test_any_reward_wrapper_is_followed_through_its_own_code():
    squared = model_from_env(TransformReward(gym.make("Taxi-v4"), lambda r: r * r))
    np.testing.assert_array_equal(squared.reward, model_from_env(gym.make("Taxi-v4")).reward ** 2)
