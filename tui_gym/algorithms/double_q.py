"""Double Q-learning (Sutton & Barto, 2nd ed., section 6.7).

Two tables, Q_A and Q_B. For each transition a fair coin picks the table to
update; the other one evaluates the action the picked one thinks best:

    with probability 1/2:
        Q_A(s, a) <- Q_A(s, a) + α [r + γ Q_B(s', argmax_a' Q_A(s', a')) - Q_A(s, a)]
    otherwise the same with A and B swapped.

Choosing and evaluating the next action with independent estimates removes
the maximization bias of Q-learning's max over noisy estimates. The policy
acts on Q_A + Q_B; the values shown and saved are their mean, which has the
same best actions (halving is exact) on the scale of one table. The coins and
the tie-breaks of argmax come from the learner's seeded generator.
"""

from __future__ import annotations

import numpy as np

from tui_gym.algorithms.base import Learner, TableSpec, Transitions, UpdateRecord
from tui_gym.algorithms.exploration import greedy_batch

__all__ = ["DoubleQLearning"]

_NAMES = ("A", "B")


class DoubleQLearning(Learner):
    """Tabular Double Q-learning; acts epsilon-greedily on the sum of its two tables."""

    name = "double-q"
    title = "Double Q-learning"
    summary = "two tables, a coin per update: Q-learning without the maximization bias"
    formula = "r + γ·Q_B(s', a*), a* = argmax Q_A(s',·)"
    tables = (
        TableSpec("q_a", np.float64),
        TableSpec("q_b", np.float64),
        TableSpec("counts_a", np.int64),
        TableSpec("counts_b", np.int64),
    )

    q_a: np.ndarray
    q_b: np.ndarray
    counts_a: np.ndarray
    counts_b: np.ndarray

    def action_values(self, rows: np.ndarray | slice) -> np.ndarray:
        return (self.q_a[rows] + self.q_b[rows]) / 2.0

    def update_counts(self) -> np.ndarray:
        used = self.rows_used
        return self.counts_a[:used] + self.counts_b[:used]

    def update(self, batch: Transitions) -> np.ndarray:
        hp = self.hp
        n = len(batch)
        update_a = self._coins(n)
        cells = batch.state * self.n_actions + batch.action
        pairs = (
            (np.flatnonzero(update_a), self.q_a, self.counts_a, self.q_b),
            (np.flatnonzero(~update_a), self.q_b, self.counts_b, self.q_a),
        )
        # Every target is read from both tables as they are before the batch.
        planned = []
        for rows, chooser, counts, judge in pairs:
            next_states = batch.next_state[rows]
            best = greedy_batch(chooser[next_states], self.rng)
            future = judge[next_states, best]
            future[batch.terminated[rows]] = 0.0
            planned.append((rows, chooser, counts, batch.reward[rows] + hp.discount * future,
                            best, future))
        before = self._flat_value(cells[0], bool(update_a[0])) if n == 1 else None
        td = np.empty(n)
        for rows, table, counts, targets, _, _ in planned:
            td[rows] = self._move(table, counts, cells[rows], targets, batch.sequential)
        if before is None:
            self._last = None
        else:
            which = 0 if update_a[0] else 1
            _, _, counts, targets, best, future = planned[which]
            self._keep(batch, which, targets[0], best[0], future[0], before,
                       self._flat_value(cells[0], which == 0), counts.reshape(-1)[cells[0]])
        return td

    def _coins(self, n: int) -> np.ndarray:
        """For each of n updates, whether it goes to Q_A: a fair coin from the generator."""
        return self.rng.random(n) < 0.5

    def _flat_value(self, cell: int, table_a: bool) -> float:
        return (self.q_a if table_a else self.q_b).reshape(-1)[cell]

    def _describe(self, batch: Transitions, *numbers: float) -> UpdateRecord:
        which, target, best, future, before, after, n = numbers
        mine, other = _NAMES[int(which)], _NAMES[1 - int(which)]
        r = float(batch.reward[0])
        terms: tuple[tuple[str, float], ...] = (("r", r),)
        formula, picked = "r", None
        if not batch.terminated[0]:
            formula = f"r + γ·Q_{other}(s', a*), a* = argmax Q_{mine}(s',·)"
            terms = (("r", r), ("γ", self.hp.discount), (f"Q_{other}(s',a*)", float(future)))
            picked = int(best)
        return self._record(batch, formula, terms, target, before, after, int(n), table=mine,
                            target_action=picked)
