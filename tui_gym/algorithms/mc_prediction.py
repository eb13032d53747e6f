"""Constant-α Monte Carlo prediction (Sutton & Barto, 2nd ed., section 6.1): V of a fixed
policy from whole-episode returns.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from tui_gym.algorithms.prediction import Predictor, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, register

__all__ = ["EpisodePredictor", "MonteCarloPrediction"]

_FIRST_BUFFER = 64  # steps of an episode kept before the buffer doubles


class Params(NamedTuple):
    learning_rate: float
    discount: float
    by_visits: bool


@kernel(inline=True)
def begin(tables: Any, hp: Any) -> None:
    tables[6][0] = 0


@kernel(inline=True)
def full(tables: Any, hp: Any) -> bool:
    return tables[6][0] >= tables[4].shape[0]


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
    g = 0.0 if terminated else v[s2]
    total = 0.0
    for t in range(steps - 1, -1, -1):
        g = rewards[t] + hp.discount * g
        total += v_update(v, visits, hp, states[t], g, log, steps - 1 - t)
    length[0] = 0
    return total


register(Params, Rule(update, begin=begin, full=full))


class EpisodePredictor(Predictor):
    """A predictor that keeps each episode's states and rewards until its end (`begin` and
    `full` above, tables 4 to 6)."""

    def arrays(self) -> tuple[np.ndarray, ...]:
        return (*super().arrays(), self._states, self._rewards, self._length)

    def _make_extra(self, capacity: int) -> None:
        super()._make_extra(capacity)
        self._states = np.zeros(_FIRST_BUFFER, dtype=np.int64)  # the episode so far
        self._rewards = np.zeros(_FIRST_BUFFER, dtype=np.float64)
        self._length = np.zeros(1, dtype=np.int64)

    def make_room(self) -> None:
        """Twice the room for the episode in progress."""
        self._states = np.concatenate([self._states, np.zeros_like(self._states)])
        self._rewards = np.concatenate([self._rewards, np.zeros_like(self._rewards)])

    def log_rows(self) -> int:
        return int(self._length[0]) + 1


class MonteCarloPrediction(EpisodePredictor):
    """Constant-α MC: V of the policy followed, from each episode's returns at its end."""

    name = "mc-prediction"
    title = "Constant-α MC"
    summary = "prediction: V of a fixed policy, toward whole-episode returns at their end"
    formula = "G = r + γ·G'"
    target_text = formula
    Params = Params
