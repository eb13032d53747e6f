"""n-step TD prediction (Sutton & Barto, 2nd ed., section 7.1): V of a fixed policy."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from tui_gym.algorithms.prediction import PREDICTION_PARAMS, Predictor, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule, register
from tui_gym.core.params import Param

__all__ = ["NStepTD"]


class Params(NamedTuple):
    learning_rate: float
    discount: float
    by_visits: bool
    n: int


@kernel(inline=True)
def begin(tables: Any, hp: Any) -> None:
    tables[6][0] = 0


@kernel(inline=True)
def full(tables: Any, hp: Any) -> bool:
    return tables[4].shape[0] < hp.n


@kernel(inline=True)
def n_step_return(rewards: Any, first: int, last: int, discount: float) -> float:
    """r_{first+1} + γ r_{first+2} + ... + γ^{last-first} r_{last+1}: the rewards of steps
    `first` to `last`, held in the ring `rewards`."""
    size = rewards.shape[0]
    g = 0.0
    weight = 1.0
    for t in range(first, last + 1):
        g += weight * rewards[t % size]
        weight *= discount
    return g


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
        g = n_step_return(rewards, tau, t, hp.discount)
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


register(Params, Rule(update, begin=begin, full=full))


class NStepTD(Predictor):
    """n-step TD: V of the policy followed, toward n-step returns."""

    name = "n-step-td"
    title = "n-step TD"
    summary = "prediction: V of a fixed policy, toward n rewards and then V (TD(0) to MC)"
    formula = "r + … + γⁿ⁻¹·r' + γⁿ·V(s_{τ+n})"
    target_text = formula
    Params = Params
    params = (
        *PREDICTION_PARAMS,
        Param("n", int, 4, 1, 10_000, "rewards in each target before it bootstraps",
              title="n (steps)"),
    )

    def arrays(self) -> tuple[np.ndarray, ...]:
        return (*super().arrays(), self._states, self._rewards, self._step)

    def _make_extra(self, capacity: int) -> None:
        super()._make_extra(capacity)
        self._states = np.zeros(int(self.hp.n), dtype=np.int64)  # the last n, in a ring
        self._rewards = np.zeros(int(self.hp.n), dtype=np.float64)
        self._step = np.zeros(1, dtype=np.int64)  # steps of the episode so far

    def make_room(self) -> None:
        """A ring for the larger n; the episode in progress is dropped."""
        self._states = np.zeros(int(self.hp.n), dtype=np.int64)
        self._rewards = np.zeros(int(self.hp.n), dtype=np.float64)
        self._step[0] = 0

    def log_rows(self) -> int:
        return int(self.hp.n) + 1
