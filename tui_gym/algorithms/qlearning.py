"""Q-learning (Sutton & Barto, 2nd ed., section 6.5): off-policy TD control.

    Q(s, a) <- Q(s, a) + α [r + γ max_a' Q(s', a') - Q(s, a)]

The target bootstraps from the best action in s' whatever the behaviour
policy does next, so Q approaches the optimal action values while the agent
explores. After termination the target is r alone; after a truncation it
still bootstraps (the time limit is not part of the game).
"""

from __future__ import annotations

import numpy as np

from tui_gym.algorithms.base import Learner, Transitions, UpdateRecord
from tui_gym.algorithms.exploration import row_max

__all__ = ["QLearning", "q_learning_targets"]


def q_learning_targets(
    q: np.ndarray, reward: np.ndarray, next_state: np.ndarray, terminated: np.ndarray,
    discount: float,
) -> tuple[np.ndarray, np.ndarray]:
    """`r + γ max Q(s', ·)` per row (r alone after termination), and the max used."""
    future = row_max(q[next_state])
    future[terminated] = 0.0
    return reward + discount * future, future


class QLearning(Learner):
    """Tabular Q-learning with epsilon-greedy exploration."""

    name = "q-learning"
    title = "Q-learning"
    summary = "off-policy TD: learns the optimal values while it explores"
    formula = "r + γ·max Q(s',·)"

    def update(self, batch: Transitions) -> np.ndarray:
        hp = self.hp
        targets, future = q_learning_targets(
            self.q, batch.reward, batch.next_state, batch.terminated, hp.discount
        )
        return self._move_q(batch, targets, future)

    def _describe(self, batch: Transitions, *numbers: float) -> UpdateRecord:
        target, future, before, after, n = numbers
        r = float(batch.reward[0])
        terms: tuple[tuple[str, float], ...] = (("r", r),)
        formula = "r"
        if not batch.terminated[0]:
            formula = self.formula
            terms = (("r", r), ("γ", self.hp.discount), ("max Q(s',·)", float(future)))
        return self._record(batch, formula, terms, target, before, after, int(n))
