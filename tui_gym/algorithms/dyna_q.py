"""Tabular Dyna-Q (Sutton & Barto, 2nd ed., section 8.2): Q-learning plus planning.

Each real transition makes a Q-learning update, then teaches a model: for
the (state, action) just taken, the reward, next state and whether it
terminated. Then `planning_steps` simulated updates follow per real
transition: a (state, action) drawn uniformly from those seen so far, its
outcome read from the model, and the same Q-learning update applied to it.

The model keeps the last outcome of each (state, action), as the book's
tabular Dyna-Q does: exact for deterministic games; for stochastic ones
(Blackjack, slippery FrozenLake) planning repeats one sampled outcome until
the pair is tried again, so it speeds learning less and adds noise.

Planning updates use the step size of the pair's real updates (`counts`
counts experience, not simulation); a batch of B real transitions is
followed by `planning_steps` rounds of B simulated ones. Draws come from the
learner's seeded generator; with `planning_steps` = 0 this is Q-learning.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from tui_gym.algorithms.base import Learner, TableSpec, Transitions, UpdateRecord
from tui_gym.algorithms.qlearning import QLearning, q_learning_targets
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.core.params import Param

__all__ = ["DynaQ"]


class DynaQ(QLearning):
    """Q-learning with a learned last-outcome model and simulated updates."""

    name = "dyna-q"
    title = "Dyna-Q"
    summary = "planning: replays a learned model between real steps, learning from fewer episodes"
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

    model_reward: np.ndarray
    model_next: np.ndarray
    model_terminated: np.ndarray

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._tried = np.zeros(64, dtype=np.int64)  # flat cells in the order first tried
        self._n_tried = 0

    def update(self, batch: Transitions) -> np.ndarray:
        td = super().update(batch)
        if not len(batch):
            return td
        self._learn_model(batch)
        planned = self._plan(len(batch), batch.sequential)
        if self._last is not None:
            self._keep(batch, *self._last[1], planned)
        return td

    def _learn_model(self, batch: Transitions) -> None:
        cells = batch.state * self.n_actions + batch.action
        first = at = np.zeros(1, dtype=np.int64)
        if len(cells) > 1:
            # The model keeps the last of several transitions from one pair, and
            # pairs new to it join the tried list in the order they first appear.
            unique, first = np.unique(cells, return_index=True)
            _, from_end = np.unique(cells[::-1], return_index=True)
            cells, at = unique, len(batch.state) - 1 - from_end
        model_next = self.model_next.reshape(-1)
        fresh = model_next[cells] < 0
        new = cells[fresh][np.argsort(first[fresh], kind="stable")]
        model_next[cells] = batch.next_state[at]
        self.model_reward.reshape(-1)[cells] = batch.reward[at]
        self.model_terminated.reshape(-1)[cells] = batch.terminated[at]
        if new.size:
            need = self._n_tried + new.size
            if need > len(self._tried):
                grown = np.zeros(max(need, 2 * len(self._tried)), dtype=np.int64)
                grown[: self._n_tried] = self._tried[: self._n_tried]
                self._tried = grown
            self._tried[self._n_tried : need] = new
            self._n_tried = need

    def _plan(self, size: int, sequential: bool) -> int:
        """`planning_steps` rounds of `size` simulated updates; how many were made."""
        hp = self.hp
        if not hp.planning_steps or not self._n_tried:
            return 0
        for _ in range(hp.planning_steps):
            cells = self._tried[self.rng.integers(self._n_tried, size=size)]
            targets, _ = q_learning_targets(
                self.q,
                self.model_reward.reshape(-1)[cells],
                self.model_next.reshape(-1)[cells],
                self.model_terminated.reshape(-1)[cells],
                hp.discount,
            )
            self._move(self.q, self.counts, cells, targets, sequential, count=False)
        return hp.planning_steps * size

    def _describe(self, batch: Transitions, *numbers: float) -> UpdateRecord:
        *real, planned = numbers
        return replace(super()._describe(batch, *real), planning_updates=int(planned))

    # --- saving: the order pairs were first tried drives which ones planning draws --------
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {"model_tried": self._tried[: self._n_tried].copy()}

    def _check_arrays(self, arrays: Any, rows: int) -> None:
        super()._check_arrays(arrays, rows)
        model_next = np.asarray(arrays["model_next"])
        if model_next.size and model_next.max() >= rows:
            raise ValueError("saved 'model_next' names a state past the table")

    def _load_extra_arrays(self, arrays: Any, rows: int) -> None:
        if "model_tried" not in arrays:
            raise ValueError("the saved state has no 'model_tried' array")
        tried = np.asarray(arrays["model_tried"], dtype=np.int64)
        cells = rows * self.n_actions
        if tried.ndim != 1 or (tried.size and (tried.min() < 0 or tried.max() >= cells)):
            raise ValueError("saved 'model_tried' does not fit the table")
        if (np.asarray(arrays["model_next"]).reshape(-1)[tried] < 0).any():
            raise ValueError("saved 'model_tried' names a pair the model has never seen")
        self._tried = np.concatenate([tried, np.zeros(max(64, tried.size), dtype=np.int64)])
        self._n_tried = int(tried.size)
