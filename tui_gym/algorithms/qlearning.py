"""Q-learning (Sutton & Barto, 2nd ed., section 6.5): off-policy TD control."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Learner, Transition, UpdateRecord
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, max_value, td_update

__all__ = ["QLearning"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits = tables
    future = 0.0 if terminated else max_value(q, offered, s2)
    return td_update(q, counts, visits, hp, s, a, r, future, log)


class QLearning(Learner):
    """Tabular Q-learning with epsilon-greedy exploration."""

    name = "q-learning"
    title = "Q-learning"
    summary = "off-policy TD: learns the optimal values while it explores"
    formula = "r + γ·max Q(s',·)"
    rule = Rule(update)

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        return self._td_record(step, log, "max Q(s',·)")
