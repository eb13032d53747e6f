"""`model_from_env`: the exact model of a Gymnasium env that carries its own table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import (
    ClipReward,
    OrderEnforcing,
    PassiveEnvChecker,
    RecordEpisodeStatistics,
    RenderCollection,
)

from tui_gym.core.mdp.model import (
    FiniteMDP,
    ModelError,
    clip_reward,
    scale_reward,
    step_penalty,
    with_horizon,
)
from tui_gym.core.wrappers.chain import env_label, layers, time_limit

__all__ = ["NotAvailable", "model_from_env"]

# Wrappers that only check, record or render: the game they wrap is the game.
_NEUTRAL = (OrderEnforcing, PassiveEnvChecker, RecordEpisodeStatistics, RenderCollection)


@dataclass(frozen=True)
class NotAvailable:
    """There is no exact model; `reason` is one sentence saying what is missing."""

    reason: str


def _reward_layer(model: FiniteMDP, layer: gym.Wrapper) -> FiniteMDP | None:
    """The model under one reward wrapper, or None for a wrapper that is not one we model."""
    from tui_gym.core.wrappers.catalog import ScaleReward, StepPenalty

    if type(layer) is ScaleReward:
        return scale_reward(model, layer.factor)
    if type(layer) is StepPenalty:
        return step_penalty(model, layer.penalty)
    if type(layer) is ClipReward:
        saved: dict[str, Any] = getattr(layer, "_saved_kwargs", {})
        return clip_reward(model, saved.get("min_reward"), saved.get("max_reward"))
    return None


def _discrete_size(name: str, role: str, space: gym.Space[Any]) -> int | NotAvailable:
    if not isinstance(space, spaces.Discrete):
        return NotAvailable(f"{name} has no exact model: its {role} space is {space}, not Discrete")
    if int(space.start) != 0:
        return NotAvailable(
            f"{name} has no exact model: its {role} space starts at {space.start}, not 0"
        )
    return int(space.n)


def _table_model(
    env: gym.Env, initial: np.ndarray | None, action_names: Sequence[str] | None,
) -> FiniteMDP | NotAvailable:
    name = env_label(env)
    n_states = _discrete_size(name, "observation", env.observation_space)
    if isinstance(n_states, NotAvailable):
        return n_states
    n_actions = _discrete_size(name, "action", env.action_space)
    if isinstance(n_actions, NotAvailable):
        return n_actions
    table = getattr(env, "P", None)
    if table is None:
        return NotAvailable(f"{name} has no exact model: it has no transition table P")
    if initial is not None:
        if initial.shape != (n_states,):
            raise ValueError(f"initial must have shape ({n_states},), got {initial.shape}")
    else:
        initial = getattr(env, "initial_state_distrib", getattr(env, "isd", None))
        if initial is None:
            return NotAvailable(
                f"{name} has no exact model: it has no initial-state distribution "
                "(initial_state_distrib or isd); pass one"
            )
    if action_names is not None and len(action_names) != n_actions:
        raise ValueError(f"{len(action_names)} action names for {n_actions} actions")
    try:
        return FiniteMDP.from_table(
            table, initial, n_states=n_states, n_actions=n_actions, action_names=action_names
        )
    except ModelError as error:
        return NotAvailable(f"{name} has no exact model: {error}")


def model_from_env(
    env: gym.Env, *, initial: Sequence[float] | np.ndarray | None = None,
    horizon: int | None | Literal["env"] = "env", action_names: Sequence[str] | None = None,
) -> FiniteMDP | NotAvailable:
    """The exact model of `env` and its wrappers, or `NotAvailable` saying why there is none.

    Args:
        env: a Gymnasium env, wrapped or not.
        initial: the initial-state distribution, for an env that does not carry one
            (it replaces the env's own when given).
        horizon: the episode limit: "env" reads it from the env's `TimeLimit`
            wrappers (none: no limit); an int or None sets it.
        action_names: a name per action, kept on the model.

    Raises `ValueError` only for bad arguments (a horizon below 1, an initial
    distribution of the wrong size or that does not sum to 1).
    """
    if (
        horizon != "env"
        and horizon is not None
        and (isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 1)
    ):
        raise ValueError(f"horizon must be 'env', None or an integer >= 1, got {horizon!r}")
    given = None
    if initial is not None:
        given = np.asarray(initial, dtype=np.float64)
        if not np.isfinite(given).all() or (given < 0).any() or abs(given.sum() - 1) > 1e-9:
            raise ValueError("initial must be a probability distribution over the states")
    if not isinstance(env, gym.Env):
        return NotAvailable(f"{type(env).__name__} is not a Gymnasium env")
    stack = layers(env)
    model = _table_model(env.unwrapped, given, action_names)
    if isinstance(model, NotAvailable):
        return model
    limit: int | None = None
    for layer in stack:
        if type(layer) in _NEUTRAL:
            continue
        steps = time_limit(layer)
        if steps is not None:
            limit = steps if limit is None else min(limit, steps)
            continue
        try:
            transformed = _reward_layer(model, layer)
        except (TypeError, ValueError) as error:
            return NotAvailable(
                f"{env_label(env)} has no exact model with {type(layer).__name__}: {error}"
            )
        if transformed is None:
            return NotAvailable(
                f"{env_label(env)} has no exact model with {type(layer).__name__}: only TimeLimit, "
                "ScaleReward, StepPenalty and ClipReward have exact forms"
            )
        model = transformed
    return with_horizon(model, limit if horizon == "env" else horizon)
