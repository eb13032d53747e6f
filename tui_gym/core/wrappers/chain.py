"""The one reader of a built env's wrapper chain, and how an env is named in messages."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
from gymnasium.wrappers import TimeLimit

__all__ = ["elapsed", "env_label", "layers", "time_limit"]


def layers(env: Any) -> list[gym.Wrapper]:
    """The wrappers of `env`, innermost first (none for a bare env)."""
    found: list[gym.Wrapper] = []
    while isinstance(env, gym.Wrapper):
        found.append(env)
        env = env.env
    found.reverse()
    return found


def time_limit(layer: Any) -> int | None:
    """The episode limit of a `TimeLimit` layer; None for any other layer."""
    return int(layer._max_episode_steps) if isinstance(layer, TimeLimit) else None


def elapsed(layer: Any) -> int:
    """The steps a `TimeLimit` layer has counted this episode (0 before the first)."""
    return int(getattr(layer, "_elapsed_steps", 0) or 0)


def env_label(env: gym.Env) -> str:
    """How an env is named in messages: its id, else its class name."""
    spec = env.spec
    return spec.id if spec is not None else type(env.unwrapped).__name__
