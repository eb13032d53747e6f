"""n-step SARSA (Sutton & Barto, 2nd ed., section 7.2): on-policy control with n-step returns."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, Learner, Transition, UpdateRecord, note, restart
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, step_size
from tui_gym.core.params import Param

__all__ = ["NStepSarsa"]

MAX_N = 64


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits, states, actions, rewards, length = tables
    n = hp.n
    t = length[0]  # transitions of the episode before this one: this is step t
    states[t % n] = s
    actions[t % n] = a
    rewards[t % n] = r
    t += 1
    length[0] = t
    ended = terminated or truncated
    tail = 0.0 if terminated else q[s2, a2]
    oldest = max(0, t - n)  # the window holds steps oldest .. t - 1
    stop = t if ended else t - n + 1  # the pairs updated now: oldest .. stop - 1
    for k in range(oldest, t):  # the window's rewards, and which pairs are updated now
        if k - oldest + 1 < log.shape[0]:
            log[k - oldest + 1, 6] = rewards[k % n]
            log[k - oldest + 1, 7] = 1.0 if k < stop else 0.0
    total = 0.0
    for tau in range(oldest, stop):
        g = tail
        for k in range(t - 1, tau - 1, -1):
            g = rewards[k % n] + hp.discount * g
        ps, pa = states[tau % n], actions[tau % n]
        counts[ps, pa] += 1
        visits[ps] += 1
        alpha = step_size(hp.learning_rate, hp.by_visits, counts[ps, pa])
        before = q[ps, pa]
        q[ps, pa] = before + alpha * (g - before)
        total += abs(g - before)
        note(log, tau - oldest + 1, ps, pa, g, alpha, before, q[ps, pa])
    if ended:
        length[0] = 0
    note(log, 0, max(0, stop - oldest), t - oldest, tail, q[s, a], 0.0, 0.0)
    return total


class NStepSarsa(Learner):
    """n-step SARSA: SARSA whose target waits n rewards."""

    name = "n-step-sarsa"
    title = "n-step SARSA"
    summary = "between SARSA and Monte Carlo: n real rewards, then bootstrap"
    formula = "G = r + γ·r' + … + γⁿ·Q(sₙ,aₙ)"
    rule = Rule(update, begin=restart, next_first=True)
    params = (
        *COMMON_PARAMS,
        Param("n", int, 4, 1, MAX_N, "rewards summed before the target bootstraps",
              title="Steps n"),
    )

    extras = (Extra("_states", MAX_N, np.int64), Extra("_actions", MAX_N, np.int64),  # the
              Extra("_rewards", MAX_N), Extra("_length", 1, np.int64))  # window, a ring of n

    def log_rows(self) -> int:
        return int(self.hp.n) + 1

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        n, gamma = int(self.hp.n), float(self.hp.discount)
        made, width, tail, now = int(log[0, 0]), int(log[0, 1]), float(log[0, 2]), float(log[0, 3])
        window = log[1 : 1 + width]
        updates = self._logged(window[window[:, 7] > 0])
        rewards = ", ".join(f"{w[6]:+.4g}" for w in window)
        notes: tuple[tuple[str, str], ...] = (("window", f"r = {rewards}  ({width} of n = {n})"),)
        if made:
            back = width - 1 if made == 1 else 0
            what = (f"the pair {back} step{'s' if back != 1 else ''} back moves toward its G"
                    if made == 1 else f"the episode ended: all {made} pairs move toward their G")
            notes += (("update", what),)
        bootstrap: tuple[tuple[str, float], ...] = (
            () if step.terminated else (("γ", gamma), ("Q(s',a')", tail)))
        own = window[-1]  # this transition's own pair: updated when n = 1 or at the end
        shown: dict[str, Any] = {"episode_updates": updates, "notes": notes,
                 "target_action": None if step.terminated else step.next_action}
        if not own[7]:
            more = f"{n - 1} more reward{'s' if n > 2 else ''}"
            return self._record(step, f"G of (s,a), after {more}", bootstrap, None, now, now,
                                **shown)
        formula = "G = r" if step.terminated else "G = r + γ·Q(s',a')"
        return self._record(step, formula, (("r", step.reward), *bootstrap), float(own[2]),
                            float(own[4]), float(own[5]), float(own[3]), **shown)
