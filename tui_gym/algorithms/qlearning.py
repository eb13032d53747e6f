"""Q-learning (Sutton & Barto, 2nd ed., section 6.5): off-policy TD control.

    Q(s, a) <- Q(s, a) + α [r + γ max_a' Q(s', a') - Q(s, a)]

The target bootstraps from the best action in s' whatever the behaviour
policy does next, so Q approaches the optimal action values while the agent
explores. After termination the target is r alone; after a truncation it
still bootstraps (the time limit is not part of the game).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from tui_gym.algorithms.base import Learner, Transition, UpdateRecord
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, note, register, step_size

__all__ = ["QLearning", "q_update"]


class Params(NamedTuple):
    learning_rate: float
    discount: float
    by_visits: bool


@kernel
def q_update(q: Any, counts: Any, visits: Any, learning_rate: float, by_visits: bool,
             discount: float, s: int, a: int, r: float, s2: int, terminated: bool,
             log: Any) -> float:
    """Move Q(s, a) toward r + γ max Q(s', ·) (r alone after termination); |TD error|."""
    future = 0.0
    if not terminated:
        future = q[s2, 0]
        for b in range(1, q.shape[1]):
            future = max(future, q[s2, b])
    target = r + discount * future
    counts[s, a] += 1
    visits[s] += 1
    alpha = step_size(learning_rate, by_visits, counts[s, a])
    before = q[s, a]
    q[s, a] = before + alpha * (target - before)
    note(log, target, future, before, q[s, a], alpha, counts[s, a])
    return abs(target - before)


@kernel
def update(tables: Any, hp: Any, rng: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits = tables
    return q_update(q, counts, visits, hp.learning_rate, hp.by_visits, hp.discount,
                    s, a, r, s2, terminated, log)


register(Params, Rule(update))


class QLearning(Learner):
    """Tabular Q-learning with epsilon-greedy exploration."""

    name = "q-learning"
    title = "Q-learning"
    summary = "off-policy TD: learns the optimal values while it explores"
    formula = "r + γ·max Q(s',·)"
    Params = Params

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        return self._td_record(step, log, "max Q(s',·)")
