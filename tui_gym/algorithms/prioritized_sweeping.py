"""Prioritized sweeping (Sutton & Barto, 2nd ed., section 8.4): planning where values change."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, Learner, Transition, UpdateRecord, note
from tui_gym.algorithms.dyna_q import DynaQ, replay
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, max_value
from tui_gym.core.params import Param

__all__ = ["PrioritizedSweeping"]

SHOWN = 4  # queue entries the step panel lists


@kernel(inline=True)
def swap(cells: Any, prio: Any, pos: Any, i: int, j: int) -> None:
    cells[i], cells[j] = cells[j], cells[i]
    prio[i], prio[j] = prio[j], prio[i]
    pos[cells[i]] = i
    pos[cells[j]] = j


@kernel
def push(cells: Any, prio: Any, pos: Any, size: Any, cell: int, p: float) -> None:
    """Put `cell` in the queue (a binary max-heap) with priority `p`, or raise it to `p`."""
    i = pos[cell]
    if i < 0:
        i = size[0]
        size[0] += 1
        cells[i] = cell
        pos[cell] = i
    elif p <= prio[i]:
        return
    prio[i] = p
    while i > 0 and prio[(i - 1) // 2] < prio[i]:
        swap(cells, prio, pos, i, (i - 1) // 2)
        i = (i - 1) // 2


@kernel
def pop(cells: Any, prio: Any, pos: Any, size: Any) -> int:
    """The cell of highest priority, taken out of the queue."""
    top = cells[0]
    size[0] -= 1
    n = size[0]
    pos[top] = -1
    if n > 0:
        cells[0], prio[0] = cells[n], prio[n]
        pos[cells[0]] = 0
        i = 0
        while True:
            big, left = i, 2 * i + 1
            if left < n and prio[left] > prio[big]:
                big = left
            if left + 1 < n and prio[left + 1] > prio[big]:
                big = left + 1
            if big == i:
                break
            swap(cells, prio, pos, i, big)
            i = big
    return top


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    (q, counts, model_reward, model_next, model_terminated, visits, cells, prio, pos, size,
     first_into, next_into) = tables
    n_actions = q.shape[1]
    cell = s * n_actions + a
    old = model_next[s, a]
    if old != s2:  # (s, a) now leads into s2: it moves to s2's list of predecessors
        if old >= 0:
            at, before_at = first_into[old], -1
            while at != cell:
                before_at, at = at, next_into[at]
            if before_at < 0:
                first_into[old] = next_into[cell]
            else:
                next_into[before_at] = next_into[cell]
        next_into[cell] = first_into[s2]
        first_into[s2] = cell
    model_reward[s, a] = r
    model_next[s, a] = s2
    model_terminated[s, a] = terminated
    counts[s, a] += 1
    visits[s] += 1
    td = abs(r + hp.discount * (0.0 if terminated else max_value(q, offered, s2)) - q[s, a])
    if td > hp.theta:
        push(cells, prio, pos, size, cell, td)
    done = 0
    while done < hp.planning_steps and size[0] > 0:
        top_priority = prio[0]
        c = pop(cells, prio, pos, size)
        ps, pa = c // n_actions, c % n_actions
        done += 1
        replay(tables, hp, offered, ps, pa, model_reward[ps, pa], log, done)
        if done < log.shape[0]:
            log[done, 6] = top_priority
        best = max_value(q, offered, ps)
        into = first_into[ps]
        while into >= 0:
            xs, xa = into // n_actions, into % n_actions
            reach = 0.0 if model_terminated[xs, xa] else best
            p = abs(model_reward[xs, xa] + hp.discount * reach - q[xs, xa])
            if p > hp.theta:
                push(cells, prio, pos, size, into, p)
            into = next_into[into]
    note(log, 0, td, done, size[0], prio[0] if size[0] > 0 else 0.0, q[s, a], 0.0)
    log[0, 7] += done  # the updates over every call with this log (a caller that counts them)
    return td


class PrioritizedSweeping(Learner):
    """Model-based planning in order of priority |TD error|, sweeping back to predecessors."""

    name = "prioritized-sweeping"
    title = "Prioritized sweeping"
    summary = "plans where values change: a queue by |TD error| sweeps back from the goal"
    formula = "r + γ·max Q(s',·)"
    rule = Rule(update)
    params = (
        *COMMON_PARAMS,
        DynaQ.params[-1],  # planning steps
        Param("theta", float, 0.0001, 0.0, 1000.0,
              "a pair enters the queue when its |TD error| exceeds this", title="Threshold θ"),
    )
    tables = DynaQ.tables
    extras = (
        Extra("_cells", "cells", np.int64), Extra("_prio", "cells"),  # the queue, a max-heap
        Extra("_pos", "cells", np.int64, -1),  # each cell's place in it, -1: out
        Extra("_size", 1, np.int64),
        Extra("_first_into", "rows", np.int64, -1),  # predecessors: lists
        Extra("_next_into", "cells", np.int64, -1),
    )

    model_reward: np.ndarray
    model_next: np.ndarray
    model_terminated: np.ndarray
    _cells: np.ndarray
    _prio: np.ndarray
    _pos: np.ndarray
    _size: np.ndarray
    _first_into: np.ndarray
    _next_into: np.ndarray

    def queue(self) -> list[tuple[int, int, float]]:
        """The queue's entries, highest priority first: (row, action, priority)."""
        order = sorted(range(int(self._size[0])), key=lambda i: -self._prio[i])
        return [(*divmod(int(self._cells[i]), self.n_actions), float(self._prio[i]))
                for i in order]

    def log_rows(self) -> int:
        return min(int(self.hp.planning_steps), SHOWN) + 1

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        p, done, left, top, now = log[0, :5]
        rows = log[1 : 1 + min(int(done), SHOWN)]
        updates = self._logged(rows)
        entered = "enters the queue" if p > self.hp.theta else "stays out (P ≤ θ)"
        taken = ", ".join(f"{w[6]:.4g}" for w in rows) + (" …" if done > len(rows) else "")
        notes = (
            ("P", f"|r + γ·max Q(s',·) − Q(s,a)| = {p:.4g}: (s,a) {entered}"),
            ("queue", f"{int(done)} taken from the top (P {taken or '–'}), "
                      f"{int(left)} left" + (f", the top at P {top:.4g}" if left else "")),
        )
        own = next((u for u in updates if (u.state, u.action) == (step.state, step.action)), None)
        if own is None:
            return self._record(step, "when (s,a) reaches the queue's top", (), None, now, now,
                                episode_updates=updates, notes=notes)
        return self._record(step, "r + γ·max Q(s',·), from the model", (), own.target,
                            own.before, own.after, own.step_size, episode_updates=updates,
                            notes=notes, planning_updates=int(done))

    # --- saving: the queue in its heap order (pushed back in that order, it is the same)
    # and the predecessor lists in their order (the order their pairs rise in the queue),
    # each link saved plus 1 (0: the list ends) ---
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        size, used = int(self._size[0]), self.rows_used
        return {"queue_cells": self._cells[:size].copy(),
                "queue_priorities": self._prio[:size].copy(),
                "model_first_into": self._first_into[:used] + 1,
                "model_next_into": self._next_into[: used * self.n_actions] + 1}

    def _load_extra_arrays(self, arrays: Any, rows: int, capacity: int) -> None:
        names = ("queue_cells", "queue_priorities", "model_first_into", "model_next_into")
        if any(name not in arrays for name in names):
            raise ValueError("the saved state has no priority queue or predecessor lists")
        cells, priorities, first, after = (np.asarray(arrays[name]) for name in names)
        first, after = first.astype(np.int64) - 1, after.astype(np.int64) - 1
        n_cells = rows * self.n_actions
        if (cells.ndim != 1 or cells.dtype.kind not in "iu" or priorities.shape != cells.shape
                or (cells.size and (cells.min() < 0 or cells.max() >= n_cells))
                or len(np.unique(cells)) != cells.size
                or not np.isfinite(priorities.astype(float)).all()):
            raise ValueError("saved 'queue_cells' or 'queue_priorities' do not fit the table")
        model_next = np.asarray(arrays["model_next"]).reshape(-1)
        if (first.shape != (rows,) or after.shape != (n_cells,)
                or np.asarray(arrays["model_first_into"]).dtype.kind not in "iu"
                or np.asarray(arrays["model_next_into"]).dtype.kind not in "iu"
                or sorted(_walk(first, after, model_next)) != np.flatnonzero(
                    model_next >= 0).tolist()):
            raise ValueError("saved predecessor lists do not follow 'model_next'")
        self._make_extra(capacity)
        self._first_into[:rows] = first
        self._next_into[:n_cells] = after
        for cell, priority in zip(cells.tolist(), priorities.tolist(), strict=True):
            push(self._cells, self._prio, self._pos, self._size, cell, priority)


def _walk(first: np.ndarray, after: np.ndarray, model_next: np.ndarray) -> list[int]:
    """Every cell on the lists, each leading into its list's state ([-1] at a loop or a
    cell out of range)."""
    seen: list[int] = []
    met: set[int] = set()
    for state, cell in enumerate(first.tolist()):
        while cell >= 0:
            if cell >= len(after) or cell in met or model_next[cell] != state:
                return [-1]
            met.add(cell)
            seen.append(cell)
            cell = int(after[cell])
    return seen
