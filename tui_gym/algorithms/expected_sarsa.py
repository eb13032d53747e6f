"""Expected SARSA (Sutton & Barto, 2nd ed., section 6.6).

    Q(s, a) <- Q(s, a) + α [r + γ Σ_a' π(a'|s') Q(s', a') - Q(s, a)]

π is the current epsilon-greedy policy, tie-breaking included: every action
has probability ε/|A|, and the greedy share 1 - ε is split evenly among the
actions tied for the best value in s'. The expectation replaces SARSA's
sampled a', so the target varies less: the same on-policy values with less
noise, which tolerates larger step sizes. After termination the target is r
alone; after a truncation it bootstraps from the expectation in s'.
"""

from __future__ import annotations

import numpy as np

from tui_gym.algorithms.base import Learner, Transitions, UpdateRecord
from tui_gym.algorithms.exploration import expected_values

__all__ = ["ExpectedSarsa"]


class ExpectedSarsa(Learner):
    """Tabular Expected SARSA under the learner's own epsilon-greedy policy."""

    name = "expected-sarsa"
    title = "Expected SARSA"
    summary = "SARSA with the expectation over the next action: the same values, less noise"
    formula = "r + γ·Σ π(a|s')·Q(s',a)"

    def update(self, batch: Transitions) -> np.ndarray:
        hp = self.hp
        future = expected_values(self.q[batch.next_state], self.epsilon)
        future[batch.terminated] = 0.0
        targets = batch.reward + hp.discount * future
        return self._move_q(batch, targets, future, self.epsilon)

    def _describe(self, batch: Transitions, *numbers: float) -> UpdateRecord:
        target, future, before, after, n, epsilon = numbers
        r = float(batch.reward[0])
        terms: tuple[tuple[str, float], ...] = (("r", r),)
        formula = "r"
        if not batch.terminated[0]:
            formula = self.formula
            terms = (("r", r), ("γ", self.hp.discount), ("ε", float(epsilon)),
                     ("Σ π(a|s')·Q(s',a)", float(future)))
        return self._record(batch, formula, terms, target, before, after, int(n))
