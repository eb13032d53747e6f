"""Dyna-Q+ (Sutton & Barto, 2nd ed., section 8.3): Dyna-Q that explores what it has not
tried for long.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, TableSpec, Transition, UpdateRecord
from tui_gym.algorithms.dyna_q import DynaQ, replay
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, actions, max_value, td_update, uniform
from tui_gym.core.params import Param

__all__ = ["DynaQPlus"]

SHOWN = 4  # simulated updates the step panel lists


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    (q, counts, model_reward, model_next, model_terminated, last_tried, visits, tried, n_tried,
     clock) = tables
    clock[0] += 1
    future = 0.0 if terminated else max_value(q, offered, s2)
    td = td_update(q, counts, visits, hp, s, a, r, future, log)
    n_actions = q.shape[1]
    if model_next[s, a] < 0:
        fresh = True  # a state new to the model: its untried offered actions join, going nowhere
        for b in range(n_actions):
            if model_next[s, b] >= 0:
                fresh = False
        lo, hi = actions(offered, s, n_actions)
        for b in range(n_actions):
            if b == a or (fresh and lo <= b < hi):
                tried[n_tried[0]] = s * n_actions + b
                n_tried[0] += 1
                model_next[s, b] = s
                model_reward[s, b] = 0.0
    model_reward[s, a] = r
    model_next[s, a] = s2
    model_terminated[s, a] = terminated
    last_tried[s, a] = clock[0]
    for i in range(hp.planning_steps):
        cell = tried[uniform(rng, n_tried[0])]
        ps, pa = cell // n_actions, cell % n_actions
        tau = clock[0] - last_tried[ps, pa]
        bonus = hp.kappa * np.sqrt(tau)
        replay(tables, hp, offered, ps, pa, model_reward[ps, pa] + bonus, log, i + 1)
        if i + 1 < log.shape[0]:
            log[i + 1, 6] = tau
            log[i + 1, 7] = bonus
    log[0, 6] = hp.planning_steps
    return td


class DynaQPlus(DynaQ):
    """Dyna-Q with an exploration bonus κ√τ in planning for pairs untried for τ steps."""

    name = "dyna-q-plus"
    title = "Dyna-Q+"
    summary = "Dyna-Q with a bonus κ√τ for what it has not tried for τ steps: finds a changed world"
    formula = "r + κ√τ + γ·max Q(s',·)"
    rule = Rule(update)
    params = (
        *DynaQ.params,
        Param("kappa", float, 0.0001, 0.0, 10.0,
              "exploration bonus κ√τ in planning for a pair untried for τ steps",
              title="Bonus κ"),
    )
    tables = (*DynaQ.tables, TableSpec("last_tried", np.int64))  # the real step, 0: never
    extras = (*DynaQ.extras, Extra("_clock", 1, np.int64))  # real steps taken

    last_tried: np.ndarray
    _clock: np.ndarray

    def log_rows(self) -> int:
        return min(int(self.hp.planning_steps), SHOWN) + 1

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        rows = log[1 : 1 + min(int(log[0, 6]), SHOWN)]
        bonuses = ", ".join(f"{w[7]:+.4g} (τ = {int(w[6])})" for w in rows)
        more = " …" if int(log[0, 6]) > len(rows) else ""
        notes = (("bonus", f"planning adds κ√τ (κ = {self.hp.kappa:g}): {bonuses}{more}"),
                 ) if len(rows) else ()
        return self._td_record(step, log, "max Q(s',·)", formula="r + γ·max Q(s',·)",
                               planning_updates=int(log[0, 6]), notes=notes)

    # --- saving: the clock the τ count from --------------------------------------------
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {**super()._extra_arrays(), "model_clock": self._clock.copy()}

    def _load_extra_arrays(self, arrays: Any, rows: int, capacity: int) -> None:
        clock = np.asarray(arrays.get("model_clock", [-1]), dtype=np.int64).reshape(-1)
        last = np.asarray(arrays["last_tried"])
        if clock.size != 1 or clock[0] < 0 or (last.size and last.max() > clock[0]):
            raise ValueError("saved 'model_clock' is missing or behind 'last_tried'")
        super()._load_extra_arrays(arrays, rows, capacity)
        self._clock[0] = clock[0]
