"""Planning on a game's exact model: headless (`tui-gym plan`, the book) and live (Plan view)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp import NotAvailable
from tui_gym.core.mdp.planning import Planner, check_method
from tui_gym.games import Game
from tui_gym.games.planning import PlanModel
from tui_gym.session.plan.start import start_policy

__all__ = ["PlanResult", "plan", "plan_json"]


@dataclass(frozen=True)
class PlanResult:
    """A method run to its end (or to `MAX_SWEEPS`) on a game's model."""

    game: Game
    kwargs: Mapping[str, Any]
    model: PlanModel
    planner: Planner
    method: str
    start: str
    converged: bool


def plan(
    game: Game, kwargs: Mapping[str, Any], method: str, *, start: str = "random",
    gamma: float | None = None, theta: float = 1e-6, in_place: bool = False,
    agent_q: npt.ArrayLike | None = None, max_sweeps: int = 100_000,
) -> PlanResult:
    """Run `method` from the `start` policy (see `start.START_POLICIES`; an agent's policy
    from `agent_q`) on the game's model; `ValueError` with one line when it cannot."""
    check_method(method)
    model = game.plan_model(kwargs)
    if isinstance(model, NotAvailable):
        raise ValueError(model.reason)
    gamma = model.gamma if gamma is None else gamma
    planner = Planner(model.model, gamma=gamma, theta=theta, in_place=in_place,
                      policy=start_policy(model, start, gamma, agent_q))
    converged = planner.run(method, max_sweeps)
    return PlanResult(game, kwargs, model, planner, method, start, converged)


def plan_json(result: PlanResult) -> dict[str, Any]:
    """`tui-gym plan --json`: the settings, the counts, and per base state (named as
    `tui-gym optimal --json` names it) its value and the actions the policy takes."""
    game, model, planner = result.game, result.model, result.planner
    observations = game.states.base_observations(result.kwargs)
    if isinstance(observations, NotAvailable):
        raise ValueError(observations.reason)
    names = game.action_names
    values = model.base_values(planner.v)
    policy = model.base_rows(planner.policy)
    states = [game.states.json_observation(obs) for obs in observations]
    return {
        "game": game.name, "env_kwargs": dict(result.kwargs), "method": result.method,
        "start": result.start, "gamma": planner.gamma, "theta": planner.theta,
        "in_place": planner.in_place, "converged": result.converged, "sweeps": planner.sweeps,
        "iterations": planner.iterations, "start_value": model.start_value(planner.v),
        "limited_value": model.limited_value(planner.policy), "episode_limit": model.horizon,
        "values": [{"state": s, "value": float(v)} for s, v in zip(states, values, strict=True)],
        "policy": [{"state": s, "actions": [names[a] for a in np.flatnonzero(row > 0)]}
                   for s, row in zip(states, policy, strict=True)],
    }
