"""A model as a reward or time-limit wrapper changes it."""

from __future__ import annotations

import numpy as np

from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.core.params import finite_number

__all__ = ["clip_reward", "scale_reward", "step_penalty", "with_horizon"]


def scale_reward(model: FiniteMDP, factor: float) -> FiniteMDP:
    """The model with every reward multiplied by `factor`."""
    factor = finite_number("ScaleReward factor", factor)
    noise = None if model.reward_std is None else abs(factor) * model.reward_std
    return model.replace(reward=factor * model.reward, reward_std=noise)


def step_penalty(model: FiniteMDP, penalty: float) -> FiniteMDP:
    """The model with `penalty` (>= 0) subtracted from every step's reward."""
    penalty = finite_number("StepPenalty penalty", penalty, minimum=0.0)
    return model.replace(reward=model.reward - penalty)


def clip_reward(model: FiniteMDP, low: float | None = None, high: float | None = None) -> FiniteMDP:
    """The model with every reward clipped to `[low, high]` (None: no bound on that side)."""
    if low is None and high is None:
        raise ValueError("ClipReward needs min_reward, max_reward or both")
    if model.reward_std is not None and model.reward_std.any():
        raise ValueError("ClipReward on rewards drawn with noise: the clipped mean is not "
                         "modelled")
    low = None if low is None else finite_number("ClipReward min_reward", low)
    high = None if high is None else finite_number("ClipReward max_reward", high)
    if low is not None and high is not None and low > high:
        raise ValueError(f"ClipReward min_reward ({low:g}) must be <= max_reward ({high:g})")
    return model.replace(reward=np.clip(model.reward, low, high))


def with_horizon(model: FiniteMDP, horizon: int | None) -> FiniteMDP:
    """The model with the episode cut off after `horizon` steps (None: no limit)."""
    return model.replace(horizon=horizon)
