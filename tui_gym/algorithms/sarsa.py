"""SARSA (Sutton & Barto, 2nd ed., section 6.4): on-policy TD control."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Learner, Transition, UpdateRecord
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, td_update

__all__ = ["Sarsa"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits = tables
    future = 0.0 if terminated else q[s2, a2]
    return td_update(q, counts, visits, hp, s, a, r, future, log)


class Sarsa(Learner):
    """Tabular SARSA with epsilon-greedy exploration."""

    name = "sarsa"
    title = "SARSA"
    summary = "on-policy TD: learns the values of the exploring policy it follows"
    formula = "r + γ·Q(s',a')"
    rule = Rule(update, next_first=True)

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        picked = None if step.terminated else step.next_action
        return self._td_record(step, log, "Q(s',a')", target_action=picked)
