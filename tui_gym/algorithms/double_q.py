"""Double Q-learning (Sutton & Barto, 2nd ed., section 6.7)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Learner, TableSpec, Transition, UpdateRecord
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, greedy, td_update

__all__ = ["DoubleQLearning"]


@kernel(inline=True)
def acting(tables: Any, hp: Any) -> tuple[Any, ...]:
    return tables[0], tables[1]  # acting on their sum


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q_a, q_b, counts_a, counts_b, visits = tables
    first = rng.random() < 0.5
    mine, other, counts = (q_a, q_b, counts_a) if first else (q_b, q_a, counts_b)
    chosen = greedy((mine,), rng, offered, s2)
    future = 0.0 if terminated else other[s2, chosen]
    td = td_update(mine, counts, visits, hp, s, a, r, future, log)
    log[0, 6] = 0.0 if first else 1.0
    log[0, 7] = chosen
    return td


class DoubleQLearning(Learner):
    """Tabular Double Q-learning; acts epsilon-greedily on the sum of its two tables."""

    name = "double-q"
    title = "Double Q-learning"
    summary = "two tables, a coin per update: Q-learning without the maximization bias"
    formula = "r + γ·Q_B(s', a*), a* = argmax Q_A(s',·)"
    rule = Rule(update, acting=acting)
    tables = (
        TableSpec("q_a", np.float64), TableSpec("q_b", np.float64), TableSpec("counts_a", np.int64),
        TableSpec("counts_b", np.int64),
    )

    value_tables = ("q_a", "q_b")

    q_a: np.ndarray
    q_b: np.ndarray
    counts_a: np.ndarray
    counts_b: np.ndarray

    def action_values(self, rows: np.ndarray | slice) -> np.ndarray:
        return (self.q_a[rows] + self.q_b[rows]) / 2.0

    def update_counts(self) -> np.ndarray:
        used = self.rows_used
        return self.counts_a[:used] + self.counts_b[:used]

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        mine, other = ("B", "A") if log[0, 6] else ("A", "B")  # the table updated, the other
        picked = None if step.terminated else int(log[0, 7])
        return self._td_record(
            step, log, f"Q_{other}(s',a*)",
            formula=f"r + γ·Q_{other}(s', a*), a* = argmax Q_{mine}(s',·)",
            table=mine, target_action=picked,
        )
