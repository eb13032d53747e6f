"""n-step TD prediction (Sutton & Barto, 2nd ed., section 7.1): V of a fixed policy."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, restart
from tui_gym.algorithms.prediction import PREDICTION_PARAMS, Predictor, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule
from tui_gym.core.params import Param

__all__ = ["NStepTD"]


@kernel(inline=True)
def full(tables: Any, hp: Any) -> bool:
    return tables[4].shape[0] < hp.n


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    v, visits, states, rewards, step = tables[3], tables[2], tables[4], tables[5], tables[6]
    size = states.shape[0]
    n = hp.n
    t = step[0]
    states[t % size] = s
    rewards[t % size] = r
    step[0] = t + 1
    log[0, 4] = 0.0  # nothing learned yet
    total = 0.0
    made = 0
    tau = t + 1 - n
    if tau >= 0:  # n rewards are in for the state of time τ
        g, weight = 0.0, 1.0
        for k in range(tau, t + 1):  # r_{τ+1} + γ·r_{τ+2} + … + γ^{n-1}·r_{τ+n}, in the ring
            g += weight * rewards[k % size]
            weight *= hp.discount
        if not terminated:
            g += hp.discount ** n * v[s2]
        total += v_update(v, visits, hp, states[tau % size], g, log, made)
        made += 1
    if terminated or truncated:  # the last n - 1 states, with the rewards there are
        first = max(0, t + 2 - n)
        g = 0.0 if terminated else v[s2]
        for tau in range(t, first - 1, -1):  # their returns, backwards, in the ring
            g = rewards[tau % size] + hp.discount * g
            rewards[tau % size] = g
        for tau in range(first, t + 1):  # their updates, in the book's order
            total += v_update(v, visits, hp, states[tau % size], rewards[tau % size], log, made)
            made += 1
        step[0] = 0
    return total


class NStepTD(Predictor):
    """n-step TD: V of the policy followed, toward n-step returns."""

    name = "n-step-td"
    title = "n-step TD"
    summary = "prediction: V of a fixed policy, toward n rewards and then V (TD(0) to MC)"
    formula = "r + … + γⁿ⁻¹·r' + γⁿ·V(s_{τ+n})"
    rule = Rule(update, begin=restart, full=full)
    params = (
        *PREDICTION_PARAMS,
        Param("n", int, 4, 1, 10_000, "rewards in each target before it bootstraps",
              title="n (steps)"),
    )

    extras = (*Predictor.extras, Extra("_states", "n", np.int64), Extra("_rewards", "n"),
              Extra("_step", 1, np.int64))  # the last n, in a ring; steps of the episode
    _step: np.ndarray

    def make_room(self) -> None:
        """A ring for the larger n; the episode in progress is dropped."""
        self._states = np.zeros(int(self.hp.n), dtype=np.int64)
        self._rewards = np.zeros(int(self.hp.n))
        self._step[0] = 0

    def log_rows(self) -> int:
        return int(self.hp.n) + 1
