"""Our own reward wrappers: `ScaleReward`, `StepPenalty` and `DistanceShaping`."""

from __future__ import annotations

from typing import Any, SupportsFloat

import gymnasium as gym
from gymnasium.core import ActType, ObsType

from tui_gym.core.params import finite_number

__all__ = ["DistanceShaping", "ScaleReward", "StepPenalty"]


class ScaleReward(gym.RewardWrapper[ObsType, ActType], gym.utils.RecordConstructorArgs):
    """Multiplies every reward by a constant `factor`.

    For `factor > 0` the optimal policy is unchanged; what changes is the size
    of the values the agent learns (and so how its fixed learning rate and its
    zero-initialised table behave). A negative factor turns goals into things
    to avoid.

    Args:
        env: the environment to wrap.
        factor: the multiplier, any finite number.
    """

    def __init__(self, env: gym.Env[ObsType, ActType], factor: float) -> None:
        factor = finite_number("ScaleReward factor", factor)
        gym.utils.RecordConstructorArgs.__init__(self, factor=factor)
        gym.RewardWrapper.__init__(self, env)
        self.factor = factor

    def reward(self, reward: SupportsFloat) -> float:
        return self.factor * float(reward)


class StepPenalty(gym.RewardWrapper[ObsType, ActType], gym.utils.RecordConstructorArgs):
    """Subtracts a fixed `penalty` from the reward of every step, the last one included.

    It is the tutorial's reward "Option 1" applied from outside the env: a
    cost for time makes shorter episodes worth more.

    Args:
        env: the environment to wrap.
        penalty: the cost of one step, finite and `>= 0`.
    """

    def __init__(self, env: gym.Env[ObsType, ActType], penalty: float) -> None:
        penalty = finite_number("StepPenalty penalty", penalty, minimum=0.0)
        gym.utils.RecordConstructorArgs.__init__(self, penalty=penalty)
        gym.RewardWrapper.__init__(self, env)
        self.penalty = penalty

    def reward(self, reward: SupportsFloat) -> float:
        return float(reward) - self.penalty


class DistanceShaping(
    gym.Wrapper[ObsType, ActType, ObsType, ActType], gym.utils.RecordConstructorArgs
):
    """Adds `-k * info["distance"]` (the distance after the move) to each step's reward.

    This is the tutorial's reward "Option 2", distance-based shaping: a dense
    hint that points the agent at the target. On the step that reaches the
    target the distance is 0, so the goal reward comes through unchanged. The
    hint is not potential-based, so a large `k` can change what the agent
    thinks is best (it learns to stay near, not to arrive).

    The wrapped env must put the distance in `info["distance"]` on every step,
    as envs with `reports_distance` do.

    Args:
        env: the environment to wrap.
        k: the weight of the distance, finite and `>= 0`.
    """

    def __init__(self, env: gym.Env[ObsType, ActType], k: float) -> None:
        k = finite_number("DistanceShaping k", k, minimum=0.0)
        gym.utils.RecordConstructorArgs.__init__(self, k=k)
        gym.Wrapper.__init__(self, env)
        self.k = k

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        if "distance" not in info:
            raise KeyError(
                "DistanceShaping needs info['distance'] from every step; "
                f"{self.env} returned info keys {sorted(info)!r}"
            )
        shaped = float(reward) - self.k * float(info["distance"])
        return observation, shaped, terminated, truncated, info
