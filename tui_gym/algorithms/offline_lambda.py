"""The offline λ-return algorithm (Sutton & Barto, 2nd ed., section 12.1): V of a fixed
policy toward λ-returns, at each episode's end.
"""

from __future__ import annotations

from typing import Any

from tui_gym.algorithms.base import filled, restart
from tui_gym.algorithms.mc_prediction import EpisodePredictor
from tui_gym.algorithms.prediction import PREDICTION_PARAMS, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule
from tui_gym.core.params import Param

__all__ = ["OfflineLambdaReturn"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    v, visits, states, rewards, length = tables[3], tables[2], tables[4], tables[5], tables[6]
    steps = length[0] + 1
    states[steps - 1] = s
    rewards[steps - 1] = r
    length[0] = steps
    log[0, 4] = 0.0  # nothing learned yet
    if not (terminated or truncated):
        return 0.0
    lam = hp.lambda_
    g = 0.0 if terminated else v[s2]
    following = g  # V of the state after step t, as the episode had it
    for t in range(steps - 1, -1, -1):  # the λ-returns, backwards, in place of the rewards
        g = rewards[t] + hp.discount * ((1.0 - lam) * following + lam * g)
        following = v[states[t]]
        rewards[t] = g
    total = 0.0
    for t in range(steps):
        total += v_update(v, visits, hp, states[t], rewards[t], log, steps - 1 - t)
    length[0] = 0
    return total


class OfflineLambdaReturn(EpisodePredictor):
    """Offline λ-return: V of the policy followed, toward λ-returns at each episode's end."""

    name = "offline-lambda-return"
    title = "Offline λ-return"
    summary = "prediction: V of a fixed policy, toward λ-returns at each episode's end"
    formula = "G^λ = r + γ·((1-λ)·V(s') + λ·G^λ')"
    rule = Rule(update, begin=restart, full=filled)
    params = (
        *PREDICTION_PARAMS,
        Param("lambda", float, 0.8, 0.0, 1.0, "weight of longer returns: 0 is TD(0), "
              "1 Monte Carlo", title="λ"),
    )
