"""Expected SARSA (Sutton & Barto, 2nd ed., section 6.6)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Learner, Transition, UpdateRecord
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, expected_value, td_update

__all__ = ["ExpectedSarsa"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits = tables
    future = 0.0 if terminated else expected_value((q,), offered, s2, epsilon)
    return td_update(q, counts, visits, hp, s, a, r, future, log)


class ExpectedSarsa(Learner):
    """Tabular Expected SARSA under the learner's own epsilon-greedy policy."""

    name = "expected-sarsa"
    title = "Expected SARSA"
    summary = "SARSA with the expectation over the next action: the same values, less noise"
    formula = "r + γ·Σ π(a|s')·Q(s',a)"
    rule = Rule(update)

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        return self._td_record(step, log, "Σ π(a|s')·Q(s',a)", ("ε", step.epsilon))
