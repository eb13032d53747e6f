"""SARSA (Sutton & Barto, 2nd ed., section 6.4): on-policy TD control.

    Q(s, a) <- Q(s, a) + α [r + γ Q(s', a') - Q(s, a)]

a' is the action the agent will really take in s': the engine chooses it
(epsilon-greedy, from the table before this update) before calling `update`,
passes it as `next_action`, and then takes it (`needs_next_action`). So Q
learns the values of the policy being followed, exploration included: near
a cliff it prefers the safer path that an occasional random step does not
spoil. After termination the target is r alone; after a truncation it
bootstraps from Q(s', a') with the a' the policy picked there.
"""

from __future__ import annotations

import numpy as np

from tui_gym.algorithms.base import Learner, Transitions, UpdateRecord

__all__ = ["Sarsa"]


class Sarsa(Learner):
    """Tabular SARSA with epsilon-greedy exploration."""

    name = "sarsa"
    title = "SARSA"
    summary = "on-policy TD: learns the values of the exploring policy it follows"
    formula = "r + γ·Q(s',a')"
    needs_next_action = True

    def update(self, batch: Transitions) -> np.ndarray:
        if batch.next_action is None:
            raise ValueError("SARSA needs the next action of every transition (next_action)")
        hp = self.hp
        future = self.q[batch.next_state, batch.next_action]
        future[batch.terminated] = 0.0
        targets = batch.reward + hp.discount * future
        return self._move_q(batch, targets, future)

    def _describe(self, batch: Transitions, *numbers: float) -> UpdateRecord:
        target, future, before, after, n = numbers
        r = float(batch.reward[0])
        terms: tuple[tuple[str, float], ...] = (("r", r),)
        formula = "r"
        if not batch.terminated[0]:
            formula = self.formula
            terms = (("r", r), ("γ", self.hp.discount), ("Q(s',a')", float(future)))
        assert batch.next_action is not None  # checked by update
        picked = None if batch.terminated[0] else int(batch.next_action[0])
        return self._record(batch, formula, terms, target, before, after, int(n),
                            target_action=picked)
