"""What each wrapper needs from the env it wraps, as reasons a person can act on.

Each `fits_*` function takes the env built so far and the wrapper's validated
values (or None when only the env is known) and returns None when the wrapper
applies, else one sentence saying why not and what to do about it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import gymnasium as gym
from gymnasium import spaces
from gymnasium.wrappers.utils import create_zero_array

from tui_gym.core.wrappers.chain import layers, time_limit

__all__ = [
    "env_label", "fits_any", "fits_delay", "fits_distance", "fits_flatten", "fits_time_aware",
    "fits_time_limit",
]


def env_label(env: gym.Env) -> str:
    """How an env is named in messages: its id, else its class name."""
    spec = env.spec
    return spec.id if spec is not None else type(env.unwrapped).__name__


def _time_limits(env: gym.Env) -> list[int]:
    """The limits of every `TimeLimit` in the stack, outermost first."""
    found = (time_limit(layer) for layer in reversed(layers(env)))
    return [limit for limit in found if limit is not None]


def fits_time_limit(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    # An outermost TimeLimit is replaced, not stacked on; only the ones below count.
    limits = _time_limits(getattr(env, "env", env) if time_limit(env) else env)
    if values is None or not limits:
        return None
    steps, inner = values["max_episode_steps"], min(limits)
    if steps > inner:
        return (
            f"TimeLimit of {steps} steps cannot lengthen the {inner}-step limit of "
            f"{env_label(env)} from outside other wrappers: put TimeLimit first, "
            f"or choose at most {inner}"
        )
    return None


def fits_flatten(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    try:
        spaces.flatten_space(env.observation_space)
    except (NotImplementedError, TypeError, ValueError):
        return (
            f"FlattenObservation cannot flatten the {type(env.observation_space).__name__} "
            f"observations of {env_label(env)}"
        )
    return None


def fits_time_aware(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    spec = env.spec
    if (spec is None or spec.max_episode_steps is None) and not _time_limits(env):
        return (
            "TimeAwareObservation needs a time limit: add TimeLimit before it "
            f"({env_label(env)} has none)"
        )
    space = env.observation_space
    if isinstance(space, spaces.Dict) and "time" in space.spaces:
        return (
            f"TimeAwareObservation adds a 'time' entry, and the observations of "
            f"{env_label(env)} already have one"
        )
    if values is not None and values["flatten"] and fits_flatten(env, values) is not None:
        return (
            f"TimeAwareObservation(flatten=true) cannot flatten the "
            f"{type(space).__name__} observations of {env_label(env)}"
        )
    return None


def fits_delay(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    try:
        create_zero_array(env.observation_space)
    except (gym.error.CustomSpaceError, TypeError, NotImplementedError):
        return (
            "DelayObservation needs an observation space it can fill with zeros; "
            f"the {type(env.observation_space).__name__} of {env_label(env)} is not one"
        )
    return None


def fits_distance(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    if getattr(env.unwrapped, "reports_distance", False):  # info["distance"] every step
        return None
    return (
        "DistanceShaping needs an env that reports info['distance'] each step; "
        f"{env_label(env)} does not"
    )


def fits_any(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    return None
