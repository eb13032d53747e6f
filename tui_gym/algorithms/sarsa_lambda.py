"""Sarsa(λ) (Sutton & Barto, 2nd ed., section 12.7): SARSA with eligibility traces."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import CellUpdate, Extra, Learner, Transition, UpdateRecord, note
from tui_gym.algorithms.settings import COMMON_PARAMS, TRACES
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, step_size
from tui_gym.core.params import Param

__all__ = ["TRACE_PARAMS", "SarsaLambda", "TracedLearner", "spread"]

FADED = 1e-10  # a trace below this is dropped

TRACE_PARAMS = (
    *COMMON_PARAMS,
    Param("lambda", float, 0.9, 0.0, 1.0, "how far back each TD error reaches (trace decay)",
          title="λ"),
    TRACES,
)


@kernel(inline=True)
def clear(tables: Any, hp: Any) -> None:
    """Every trace back to 0."""
    trace, cells, n_cells = tables[3], tables[4], tables[5]
    n_actions = trace.shape[1]
    for i in range(n_cells[0]):
        trace[cells[i] // n_actions, cells[i] % n_actions] = 0.0
    n_cells[0] = 0


@kernel
def spread(tables: Any, hp: Any, s: int, a: int, target: float, future: float, decay: float,
           log: Any) -> float:
    """Mark (s, a) eligible, move every traced pair by α δ e, then decay the traces by
    `decay` (0 cuts them). Log row 0 as `td_update` writes it, then a row per pair."""
    q, counts, visits, trace, cells, n_cells = tables[:6]
    n_actions = q.shape[1]
    before = q[s, a]
    delta = target - before
    if trace[s, a] == 0.0:
        cells[n_cells[0]] = s * n_actions + a
        n_cells[0] += 1
    trace[s, a] = 1.0 if hp.replacing else trace[s, a] + 1.0
    counts[s, a] += 1
    visits[s] += 1
    kept = 0
    for i in range(n_cells[0]):
        cell = cells[i]
        x, b = cell // n_actions, cell % n_actions
        alpha = step_size(hp.learning_rate, hp.by_visits, max(counts[x, b], 1))
        was = q[x, b]
        q[x, b] = was + alpha * delta * trace[x, b]
        note(log, i + 1, x, b, trace[x, b], alpha, was, q[x, b])
        trace[x, b] *= decay
        if trace[x, b] >= FADED:
            cells[kept] = cell
            kept += 1
        else:
            trace[x, b] = 0.0
    note(log, 0, target, future, before, q[s, a],
         step_size(hp.learning_rate, hp.by_visits, counts[s, a]), n_cells[0])
    log[0, 6] = decay
    n_cells[0] = kept
    return abs(delta)


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    future = 0.0 if terminated else tables[0][s2, a2]
    td = spread(tables, hp, s, a, r + hp.discount * future, future, hp.discount * hp.lambda_, log)
    if terminated or truncated:
        clear(tables, hp)
    return td


class TracedLearner(Learner):
    """What the λ learners share: the traces, their list, and the record of an update."""

    params = TRACE_PARAMS
    has_traces = True
    extras = (Extra("_trace", "table"),  # e(s, a) in this episode
              Extra("_cells", "cells", np.int64), Extra("_n_cells", 1, np.int64))  # e > 0
    _trace: np.ndarray
    _n_cells: np.ndarray

    def log_rows(self) -> int:
        return int(self._n_cells[0]) + 2

    def eligibility(self) -> np.ndarray:
        """e(s, a) of the used rows (a copy): the episode's eligibility traces."""
        return self._trace[: self.rows_used].copy()

    def _traced_record(self, step: Transition, log: np.ndarray, future_term: str,
                       *notes: tuple[str, str], **extra: Any) -> UpdateRecord:
        pairs, decay = int(log[0, 5]), float(log[0, 6])
        target, before = float(log[0, 0]), float(log[0, 2])
        delta = target - before
        updates = tuple(CellUpdate(int(row[0]), int(row[1]), float(row[4] + delta * row[2]),
                                   float(row[3]), float(row[4]), float(row[5]), float(row[2]))
                        for row in log[1 : 1 + pairs])
        kind = self.hp.traces
        spread_note = (f"δ = {delta:+.4g} moves {pairs} pair{'s' if pairs != 1 else ''} "
                       f"by α·δ·e ({kind} traces)")
        ended = step.terminated or step.truncated
        then = ("the episode ended: the traces end" if ended
                else f"then every e × γλ = {decay:.4g}" if decay else "then every e is cut to 0")
        return self._td_record(step, log, future_term, episode_updates=updates,
                               notes=(*notes, ("traces", spread_note), ("", then)), **extra)


class SarsaLambda(TracedLearner):
    """Sarsa(λ): on-policy control with eligibility traces."""

    name = "sarsa-lambda"
    title = "Sarsa(λ)"
    summary = "SARSA with traces: each TD error reaches back along the path, decaying by γλ"
    formula = "r + γ·Q(s',a')"
    rule = Rule(update, begin=clear, next_first=True)

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        picked = None if step.terminated else step.next_action
        return self._traced_record(step, log, "Q(s',a')", target_action=picked)
