"""TD(λ) prediction (Sutton & Barto, 2nd ed., section 12.2): V of a fixed policy with
eligibility traces.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, note
from tui_gym.algorithms.prediction import PREDICTION_PARAMS, Predictor
from tui_gym.algorithms.settings import TRACES
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, step_size
from tui_gym.core.params import Param

__all__ = ["TDLambda"]


@kernel(inline=True)
def begin(tables: Any, hp: Any) -> None:
    tables[4][:] = 0.0


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    v, visits, trace = tables[3], tables[2], tables[4]
    decay = hp.discount * hp.lambda_
    for i in range(trace.shape[0]):
        trace[i] *= decay
    trace[s] = 1.0 if hp.replacing else trace[s] + 1.0
    visits[s] += 1
    future = 0.0 if terminated else v[s2]
    target = r + hp.discount * future
    before = v[s]
    delta = target - before
    alpha = step_size(hp.learning_rate, hp.by_visits, visits[s])
    for i in range(v.shape[0]):
        if trace[i] != 0.0:
            v[i] += alpha * delta * trace[i]
    note(log, 0, s, target, before, v[s], alpha, visits[s])
    log[0, 6] = trace[s]
    if terminated or truncated:
        begin(tables, hp)
    return abs(delta)


class TDLambda(Predictor):
    """TD(λ): V of the policy followed, the TD error spread back along the traces."""

    name = "td-lambda"
    title = "TD(λ)"
    summary = "prediction: V of a fixed policy, each TD error spread over the states' traces"
    formula = "δ = r + γ·V(s') - V(s), V += α·δ·e"
    target_text = "r + γ·V(s')"
    rule = Rule(update, begin=begin)
    has_traces = True
    params = (
        *PREDICTION_PARAMS,
        Param("lambda", float, 0.8, 0.0, 1.0, "trace decay: 0 is TD(0), 1 nears Monte Carlo",
              title="λ"),
        dataclasses.replace(TRACES, default="accumulating"),
    )
    extras = (*Predictor.extras, Extra("_trace", "rows"))  # per state, this episode
    _trace: np.ndarray

    def eligibility(self) -> np.ndarray:
        return np.repeat(self._trace[: self.rows_used, None], self.n_actions, axis=1)
