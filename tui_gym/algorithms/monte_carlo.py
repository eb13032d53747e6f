"""Monte Carlo control with an epsilon-soft policy (Sutton & Barto, 2nd ed., section 5.4);
a truncated episode ends on its last state's expected value under the current policy."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, Learner, Transition, UpdateRecord, filled, note, restart
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, expected_value, step_size
from tui_gym.core.params import Param

__all__ = ["MonteCarlo"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, visits, first, cells, rewards, length = tables
    n_actions = q.shape[1]
    steps = length[0] + 1
    cells[steps - 1] = s * n_actions + a
    rewards[steps - 1] = r
    length[0] = steps
    if not (terminated or truncated):
        log[0, 0] = 0.0  # nothing learned yet
        log[0, 3] = q[s, a]
        return 0.0
    g = 0.0 if terminated else expected_value((q,), offered, s2, epsilon)
    tail = g
    if hp.first_visit:
        for t in range(steps):
            if first[cells[t]] < 0:
                first[cells[t]] = t
    total = 0.0
    made = 0
    for t in range(steps - 1, -1, -1):
        g = rewards[t] + hp.discount * g
        cell = cells[t]
        if hp.first_visit and first[cell] != t:
            continue
        ps, pa = cell // n_actions, cell % n_actions
        counts[ps, pa] += 1
        visits[ps] += 1
        alpha = step_size(hp.learning_rate, hp.by_visits, counts[ps, pa])
        before = q[ps, pa]
        q[ps, pa] = before + alpha * (g - before)
        total += abs(g - before)
        made += 1
        note(log, made, ps, pa, g, alpha, before, q[ps, pa])
    if hp.first_visit:
        for t in range(steps):
            first[cells[t]] = -1
    length[0] = 0
    note(log, 0, 1.0, g, tail, q[s, a], made, 0.0)  # learned: G from the start, its tail
    return total


class MonteCarlo(Learner):
    """On-policy Monte Carlo control; learns from whole episodes."""

    name = "monte-carlo"
    title = "Monte Carlo control"
    summary = "no bootstrapping: learns from whole-episode returns, at each episode's end"
    formula = "G = r + γ·G'"
    rule = Rule(update, begin=restart, full=filled)
    params = (
        *COMMON_PARAMS,
        Param("first_visit", bool, True,
              help="update a state-action once per episode, from its first visit",
              title="First visit"),
    )
    extras = (Extra("_first", "cells", np.int64, -1),  # scratch
              Extra("_cells", "episode", np.int64), Extra("_rewards", "episode"),  # the episode
              Extra("_length", 1, np.int64))
    _length: np.ndarray

    def log_rows(self) -> int:
        return int(self._length[0]) + 2

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        head = log[0]
        now = float(head[3])
        if not head[0]:  # the episode goes on: nothing learned yet
            return self._record(step, "G, at the episode's end", (("r", step.reward),), None,
                                now, now)
        updates = self._logged(log[1 : 1 + int(head[4])])
        # This transition's own update: the first one of its (state, action) in the
        # book's backward order (its only one with first visits).
        own = next(u for u in updates if (u.state, u.action) == (step.state, step.action))
        terms: tuple[tuple[str, float], ...] = (("r", step.reward),)
        if not step.terminated:
            terms += (("γ", self.hp.discount), ("Σ π(a|s')·Q(s',a)", float(head[2])))
        formula = "G = r" if step.terminated else "G = r + γ·Σ π(a|s')·Q(s',a)"
        return self._record(step, formula, terms, own.target, own.before, now,
                            own.step_size, episode_return=float(head[1]),
                            episode_updates=updates)
