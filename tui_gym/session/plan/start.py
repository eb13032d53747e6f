"""Where planning starts: the policy a person or `tui-gym plan` picks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp import greedy_policy, optimal_actions, solve
from tui_gym.games import Game
from tui_gym.games.planning import PlanModel

__all__ = ["START_POLICIES", "StartError", "saved_agent_q", "start_policy"]

START_POLICIES = ("random", "optimal", "agent")
FloatArray = npt.NDArray[np.float64]


class StartError(ValueError):
    """A start policy that cannot be had (no agent table, another game's agent)."""


def start_policy(
    plan: PlanModel, choice: str, gamma: float, agent_q: npt.ArrayLike | None = None
) -> FloatArray:
    """The `[S, A]` policy `choice` names on `plan`'s states, among the actions each offers."""
    model, allowed = plan.model, plan.allowed()
    weights: npt.NDArray[np.generic]
    if choice == "random":
        weights = allowed
    elif choice == "optimal":
        weights = optimal_actions(np.where(allowed, solve(model, gamma).q, -np.inf))
    elif choice == "agent":
        if agent_q is None:
            raise StartError("no agent table here (wrappers hide the states)")
        q = np.asarray(agent_q, dtype=np.float64)
        if q.shape != (plan.n_base, model.n_actions):
            raise StartError(f"the agent's table has shape {q.shape}, the game "
                             f"{(plan.n_base, model.n_actions)}")
        weights = plan.model_policy(greedy_policy(np.where(
            plan.allowed()[plan.shown], q, -np.inf)))
    else:
        raise StartError(f"the start policy is one of {', '.join(START_POLICIES)}, "
                         f"not {choice!r}")
    chances = np.asarray(weights, dtype=np.float64)
    return chances / chances.sum(axis=1, keepdims=True)


def saved_agent_q(path: str | Path, game: Game, kwargs: dict) -> FloatArray:
    """The base states' Q-table rows of the agent of `game` with `kwargs` saved at `path`."""
    from tui_gym.session.session import Session

    session = Session.load(path)
    if session.game is not game or session.env_kwargs != kwargs:
        raise StartError(f"{path} holds an agent of {session.game.title} "
                         f"{session.env_kwargs}, not {game.title} {kwargs}")
    q = session.base_q()
    if q is None:
        raise StartError(f"{path}: {session.hidden_reason()}")
    return q
