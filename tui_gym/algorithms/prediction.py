"""Prediction: learners that estimate V of a fixed policy, scored against its exact values."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from tui_gym.algorithms.base import Extra, Learner, Transition, UpdateRecord, note
from tui_gym.algorithms.settings import COMMON_PARAMS, Field
from tui_gym.core.engine import loop
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.engine.rules import step_size
from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.core.mdp.policy import greedy_policy
from tui_gym.core.mdp.prediction import Truth

__all__ = ["PREDICTION_PARAMS", "Predictor", "rms_curve", "v_update"]

# The book's prediction settings: a constant step, no discount, the random policy.
_DEFAULTS = {"learning_rate": 0.1, "discount": 1.0, "epsilon_start": 1.0,
             "epsilon_final": 1.0, "episodes": 100, "learning_rate_schedule": "constant"}

PREDICTION_PARAMS: tuple[Field, ...] = tuple(
    dataclasses.replace(f, default=_DEFAULTS[f.name]) if f.name in _DEFAULTS  # type: ignore[arg-type]
    else dataclasses.replace(f, help="every state's value before learning",  # type: ignore[arg-type]
                             title="Initial V") if f.name == "initial_value" else f
    for f in COMMON_PARAMS
)


@kernel(inline=True)
def v_update(v: Any, visits: Any, hp: Any, s: int, target: float, log: Any, row: int) -> float:
    """Move v[s] toward `target`, counting the visit; log row `row` (when there is one):
    the state, target, V before and after, the step size, the count. The |error|."""
    visits[s] += 1
    alpha = step_size(hp.learning_rate, hp.by_visits, visits[s])
    before = v[s]
    v[s] = before + alpha * (target - before)
    note(log, row, s, target, before, v[s], alpha, visits[s])
    return abs(target - before)


class Predictor(Learner):
    """A learner of V for the fixed policy it follows (see the module docstring)."""

    params: ClassVar[tuple[Field, ...]] = PREDICTION_PARAMS
    extras: ClassVar[tuple[Extra, ...]] = (Extra("v", "rows", fill=None),)
    v: np.ndarray

    def action_values(self, rows: np.ndarray | slice) -> np.ndarray:
        """V of each row, the same in every action (what the heatmaps show)."""
        return np.repeat(self.v[rows][:, None], self.n_actions, axis=1)

    # --- the policy followed and the ruler ------------------------------------------------
    def follow(self, action_values: np.ndarray, epsilon: float) -> None:
        """Follow the epsilon-greedy policy on `action_values` (as `table()` gives them)."""
        values = np.asarray(action_values, dtype=np.float64)
        if values.shape != (self.rows_used, self.n_actions):
            raise ValueError(f"a policy to follow has one row of {self.n_actions} action "
                             f"values per state ({self.rows_used}), got {values.shape}")
        self.q[: self.rows_used] = values
        self.set_hyperparameters(self.hp.replace(epsilon_start=epsilon, epsilon_final=epsilon))

    def policy(self, rows: np.ndarray) -> np.ndarray:
        """`[len(rows), A]`: the probabilities of the policy followed now, per row."""
        return greedy_policy(self.q[rows], self.epsilon)

    def truth(self, model: FiniteMDP, rows: np.ndarray | None = None) -> Truth:
        """The exact values of the policy followed on `model` (state s is row `rows[s]`)."""
        at = np.arange(model.n_states) if rows is None else np.asarray(rows)
        if self.hp.discount <= 0.0:
            raise ValueError("exact values need a discount above 0")
        return Truth.of(model, self.policy(at), self.hp.discount)

    def rms_error(self, truth: Truth, rows: np.ndarray | None = None) -> float:
        """The RMS error of V against `truth` (model state s is table row `rows[s]`)."""
        return truth.rms(self.v if rows is None else self.v[np.asarray(rows)])

    # --- the step-by-step view -------------------------------------------------------------
    target_text: ClassVar[str | None] = None  # the step panel's target, when not `formula`

    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        """The update of V(s) the rule logged in row 0, when there was one."""
        written, terms = self.target_text or self.formula, (("r", step.reward),)
        if not log[0, 4]:  # no step size: V did not move
            now = float(self.v[step.state])
            return self._record(step, written, terms, None, now, now)
        state, target, before, after, alpha = (float(x) for x in log[0, :5])
        earlier = f"V of row {int(state)}" if int(state) != step.state else ""  # n-step, MC
        return self._record(step, written, terms, target, before, after, alpha, table=earlier)

    # --- saving ----------------------------------------------------------------------------
    def _extra_arrays(self) -> dict[str, np.ndarray]:
        return {"v": self.v[: self.rows_used].copy()}

    def _load_extra_arrays(self, arrays: Mapping[str, np.ndarray], rows: int,
                           capacity: int) -> None:
        if "v" not in arrays:
            raise ValueError("the saved state has no 'v' array")
        v = np.asarray(arrays["v"])
        if v.shape != (rows,) or v.dtype.kind not in "fiu" or not np.isfinite(v).all():
            raise ValueError("saved 'v' does not fit the table")
        self._make_extra(capacity)
        self.v[:rows] = v


def rms_curve(learner: Predictor, model: ModelArrays, truth: Truth, episodes: int) -> np.ndarray:
    """Play `episodes` episodes on `model`: the RMS error of V against `truth` after each."""
    where = np.flatnonzero(truth.reached)
    scored_rows, values = model.rows[where], np.array(truth.v[where])
    cursor, out, log = loop.Cursor(), np.zeros((1, loop.COLUMNS)), np.zeros((1, 8))
    curve = np.zeros(episodes)
    done = 0
    while done < episodes:
        if loop.play(learner, model, cursor, 1, 1 << 62, out, log)[0]:
            total = 0.0
            for error in (learner.v[scored_rows] - values).tolist():  # in order, as compiled
                total += error * error
            curve[done] = np.sqrt(total / len(values))
            done += 1
    return curve
