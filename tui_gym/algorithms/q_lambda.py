"""Watkins's Q(λ) (Sutton & Barto, 2nd ed., section 12.10): Q-learning with eligibility traces."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Transition, UpdateRecord
from tui_gym.algorithms.sarsa_lambda import TracedLearner, clear, spread
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, max_value

__all__ = ["WatkinsQLambda"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q = tables[0]
    future = 0.0 if terminated else max_value(q, offered, s2)
    greedy = terminated or q[s2, a2] == future  # judged before the update, as the book does
    decay = hp.discount * hp.lambda_ if greedy else 0.0
    td = spread(tables, hp, s, a, r + hp.discount * future, future, decay, log)
    log[0, 7] = 1.0 if greedy else 0.0
    if terminated or truncated:
        clear(tables, hp)
    return td


class WatkinsQLambda(TracedLearner):
    """Watkins's Q(λ): off-policy control; traces cut after an exploratory action."""

    name = "q-lambda"
    title = "Watkins's Q(λ)"
    summary = "Q-learning with traces, cut whenever the agent explores"
    formula = "r + γ·max Q(s',·)"
    rule = Rule(update, begin=clear, next_first=True)

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        if step.terminated or step.truncated:
            return self._traced_record(step, log, "max Q(s',·)")
        what = "greedy: the traces go on" if log[0, 7] else "exploratory: the traces are cut"
        return self._traced_record(step, log, "max Q(s',·)", ("a'", what))
