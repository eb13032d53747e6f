"""`model_from_env`: the exact model of a Gymnasium env that carries its own table."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from tui_gym.core.mdp.model import FiniteMDP, ModelError, with_horizon
from tui_gym.core.wrappers.chain import env_label

__all__ = ["NotAvailable", "model_from_env"]


@dataclass(frozen=True)
class NotAvailable:
    """There is no exact model; `reason` is one sentence saying what is missing."""

    reason: str


def _table_model(
    env: gym.Env, initial: np.ndarray | None, action_names: Sequence[str] | None
) -> FiniteMDP | NotAvailable:
    none = f"{env_label(env)} has no exact model"
    sizes = []
    for role, space in (("observation", env.observation_space), ("action", env.action_space)):
        if not isinstance(space, spaces.Discrete):
            return NotAvailable(f"{none}: its {role} space is {space}, not Discrete")
        if int(space.start) != 0:
            return NotAvailable(f"{none}: its {role} space starts at {space.start}, not 0")
        sizes.append(int(space.n))
    n_states, n_actions = sizes
    table = getattr(env, "P", None)
    if table is None:
        return NotAvailable(f"{none}: it has no transition table P")
    if initial is not None:
        if initial.shape != (n_states,):
            raise ValueError(f"initial must have shape ({n_states},), got {initial.shape}")
    else:
        initial = getattr(env, "initial_state_distrib", getattr(env, "isd", None))
        if initial is None:
            return NotAvailable(
                f"{none}: it has no initial-state distribution (initial_state_distrib or isd); "
                "pass one"
            )
    if action_names is not None and len(action_names) != n_actions:
        raise ValueError(f"{len(action_names)} action names for {n_actions} actions")
    try:
        return FiniteMDP.from_table(
            table, initial, n_states=n_states, n_actions=n_actions, action_names=action_names
        )
    except ModelError as error:
        return NotAvailable(f"{none}: {error}")


def model_from_env(
    env: gym.Env,
    *,
    initial: Sequence[float] | np.ndarray | None = None,
    horizon: int | None | Literal["env"] = "env",
    action_names: Sequence[str] | None = None,
) -> FiniteMDP | NotAvailable:
    """The exact model of `env` (its unwrapped states) under its wrappers as
    `GameChanges` reads them, or `NotAvailable` saying why there is none.

    `initial` replaces the env's start distribution; `horizon` "env" reads the limit
    from its `TimeLimit` wrappers, an int or None sets it. `ValueError` only for bad
    arguments (a horizon below 1, an initial distribution that does not fit).
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
    from tui_gym.core.wrappers.changes import GameChanges

    model = _table_model(env.unwrapped, given, action_names)
    if isinstance(model, NotAvailable):
        return model
    changes = GameChanges.of(env)
    none = f"{env_label(env)} has no exact model with"
    if changes.others:
        return NotAvailable(f"{none} {changes.others[0]}: it changes the game beyond its table")
    try:
        model = changes.model(model)
    except (TypeError, ValueError) as error:
        reason = " ".join(str(error).split())
        return NotAvailable(f"{none} {changes.reward_names()}: {reason}")
    return model if horizon == "env" else with_horizon(model, horizon)
