"""Tabular Dyna-Q (Sutton & Barto, 2nd ed., section 8.2): Q-learning plus planning.

The model keeps the last outcome of each pair, as the book's tabular Dyna-Q does, so
on stochastic games planning repeats one sampled outcome until the pair is tried again.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, Learner, TableSpec, Transition, UpdateRecord, note
from tui_gym.algorithms.qlearning import QLearning
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, max_value, step_size, td_update, uniform
from tui_gym.core.params import Param

__all__ = ["DynaQ"]


@kernel(inline=True)
def replay(tables: Any, hp: Any, offered: Any, ps: int, pa: int, reward: float, log: Any,
           row: int) -> None:
    """A simulated update of Q(ps, pa) toward `reward` + γ·max Q where the model says it
    leads, logged in row `row`."""
    q, counts, model_next, model_terminated = tables[0], tables[1], tables[3], tables[4]
    future = 0.0 if model_terminated[ps, pa] else max_value(q, offered, model_next[ps, pa])
    target = reward + hp.discount * future
    alpha = step_size(hp.learning_rate, hp.by_visits, max(counts[ps, pa], 1))
    before = q[ps, pa]
    q[ps, pa] = before + alpha * (target - before)
    note(log, row, ps, pa, target, alpha, before, q[ps, pa])


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    q, counts, model_reward, model_next, model_terminated, visits, tried, n_tried = tables
    future = 0.0 if terminated else max_value(q, offered, s2)
    td = td_update(q, counts, visits, hp, s, a, r, future, log)
    n_actions = q.shape[1]
    if model_next[s, a] < 0:  # a pair new to the model joins the tried list
        tried[n_tried[0]] = s * n_actions + a
        n_tried[0] += 1
    model_reward[s, a] = r
    model_next[s, a] = s2
    model_terminated[s, a] = terminated
    for i in range(hp.planning_steps):
        cell = tried[uniform(rng, n_tried[0])]
        ps, pa = cell // n_actions, cell % n_actions
        replay(tables, hp, offered, ps, pa, model_reward[ps, pa], log, i + 1)
    log[0, 6] = hp.planning_steps
    return td


class DynaQ(Learner):
    """Q-learning with a learned last-outcome model and simulated updates."""

    name = "dyna-q"
    title = "Dyna-Q"
    summary = "planning: replays a learned model between real steps, learning from fewer episodes"
    formula = QLearning.formula
    rule = Rule(update)
    params = (
        *COMMON_PARAMS,
        Param("planning_steps", int, 10, 0, 1000,
              "simulated updates from the model per real step", title="Planning steps"),
    )
    tables = (
        *Learner.tables,
        TableSpec("model_reward", np.float64),
        TableSpec("model_next", np.int64, -1),  # -1: never tried
        TableSpec("model_terminated", bool),
    )
    extras = (*Learner.extras, Extra("_tried", "cells", np.int64),  # in order first tried
              Extra("_n_tried", 1, np.int64))

    model_reward: np.ndarray
    model_next: np.ndarray
    model_terminated: np.ndarray
    _tried: np.ndarray
    _n_tried: np.ndarray

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        return self._td_record(step, log, "max Q(s',·)", planning_updates=int(log[0, 6]))

    # --- saving: the order pairs were first tried drives which ones planning draws --------
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {"model_tried": self._tried[: int(self._n_tried[0])].copy()}

    def _check_arrays(self, arrays: Any, rows: int) -> None:
        super()._check_arrays(arrays, rows)
        model_next = np.asarray(arrays["model_next"])
        if model_next.size and model_next.max() >= rows:
            raise ValueError("saved 'model_next' names a state past the table")

    def _load_extra_arrays(self, arrays: Any, rows: int, capacity: int) -> None:
        if "model_tried" not in arrays:
            raise ValueError("the saved state has no 'model_tried' array")
        tried = np.asarray(arrays["model_tried"], dtype=np.int64)
        cells = rows * self.n_actions
        if tried.ndim != 1 or (tried.size and (tried.min() < 0 or tried.max() >= cells)):
            raise ValueError("saved 'model_tried' does not fit the table")
        if (np.asarray(arrays["model_next"]).reshape(-1)[tried] < 0).any():
            raise ValueError("saved 'model_tried' names a pair the model has never seen")
        if len(np.unique(tried)) != tried.size:
            raise ValueError("saved 'model_tried' names a pair twice")
        self._make_extra(capacity)
        self._tried[: tried.size] = tried
        self._n_tried[0] = tried.size
