"""The rule registry, and the exploration and step sizes every learner shares, as kernels.

Each algorithm's `Rule` is registered for its `Params` (its compiled hyperparameters).
The stubs below dispatch on the type of `hp`: in Python by looking the rule up, in
compiled code at compile time (`jit` registers them as overloads).

`offered`: each table row's one run of actions `lo` to `hi - 1`, an unsigned `[rows, 2]`
array, or `[0, 2]` (empty) when every row offers every action. Acting, the max and the
expectation range over the offered actions only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.core.engine.kernel import kernel

__all__ = [
    "RULES",
    "Rule",
    "act",
    "acting",
    "actions",
    "begin",
    "epsilon_at",
    "every",
    "expected_value",
    "full",
    "greedy",
    "max_value",
    "next_first",
    "offered_range",
    "offered_ranges",
    "register",
    "step_size",
    "td_update",
    "uniform",
    "update",
    "value",
]

LOG_WIDTH = 8  # numbers per row of an update's log


@dataclass(frozen=True)
class Rule:
    """One algorithm's compiled parts: `update(tables, hp, rng, offered, s, a, r, s2,
    terminated, truncated, a2, epsilon, log)` returns |TD error| and explains itself in
    `log`; `acting` (the tables summed to act on, default the first), `begin` (as an
    episode starts), `full` (whether it needs room first); `next_first`: SARSA's order."""

    update: Callable[..., float]
    acting: Callable[..., tuple[Any, ...]] | None = None
    begin: Callable[..., None] | None = None
    full: Callable[..., bool] | None = None
    next_first: bool = False


RULES: dict[type, Rule] = {}


def register(params: type, rule: Rule) -> None:
    """The rule of the algorithm whose compiled hyperparameters are `params`."""
    RULES[params] = rule


# --- the stubs the loop calls ------------------------------------------------------------


def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    return RULES[type(hp)].update(tables, hp, rng, offered, s, a, r, s2, terminated,
                                  truncated, a2, epsilon, log)


def acting(tables: Any, hp: Any) -> tuple[Any, ...]:
    own = RULES[type(hp)].acting
    return (tables[0],) if own is None else own(tables, hp)


def begin(tables: Any, hp: Any) -> None:
    own = RULES[type(hp)].begin
    if own is not None:
        own(tables, hp)


def full(tables: Any, hp: Any) -> bool:
    own = RULES[type(hp)].full
    return False if own is None else own(tables, hp)


def next_first(hp: Any) -> bool:
    return RULES[type(hp)].next_first


# --- shared by every learner ---------------------------------------------------------------


@kernel(inline=True)
def step_size(learning_rate: float, by_visits: bool, n: int) -> float:
    """The step size of the n-th update (n >= 1): the learning rate, or with `by_visits`
    max(learning rate, 1/n)."""
    if by_visits:
        return max(learning_rate, 1.0 / n)
    return learning_rate


@kernel(inline=True)
def epsilon_at(episode: float, start: float, final: float, decay_episodes: float) -> float:
    """Epsilon for a 0-based episode: from `start` to `final` over `decay_episodes`."""
    if decay_episodes <= 0.0 or episode >= decay_episodes:
        return final
    return start + episode / decay_episodes * (final - start)


@kernel(inline=True)
def uniform(rng: Any, n: int) -> int:
    """An integer drawn uniformly from 0 to n - 1 (one uniform double: quicker compiled
    than `Generator.integers`)."""
    return min(int(rng.random() * n), n - 1)


@kernel(inline=True)
def offered_range(offered: Any, s: int) -> tuple[Any, Any]:
    """The actions row `s` offers: `lo` to `hi - 1` (`offered` not empty: see `every`)."""
    return np.int64(offered[s, 0]), np.int64(offered[s, 1])  # unsigned: never below 0


@kernel(inline=True)
def every(offered: Any) -> bool:
    """Whether every row offers every action (`offered` empty)."""
    return offered.shape[0] == 0


@kernel(inline=True)
def value(values: Any, s: int, a: int) -> float:
    """The action value of (s, a): the sum over the tables `values` (see `acting`)."""
    total = values[0][s, a]
    for i in range(1, len(values)):
        total += values[i][s, a]
    return total


@kernel(inline=True)
def actions(offered: Any, s: int, n: int) -> tuple[Any, Any]:
    """The actions row `s` offers: `lo` to `hi - 1` (all `n` when `offered` is empty)."""
    if every(offered):
        return np.int64(0), np.int64(n)
    return offered_range(offered, s)


@kernel
def greedy(values: Any, rng: Any, offered: Any, s: int) -> int:
    """The best-valued action row `s` offers, ties broken uniformly (a draw only on one)."""
    lo, hi = actions(offered, s, values[0].shape[1])
    choice = lo
    best = value(values, s, lo)
    ties = 1
    for a in range(lo + 1, hi):
        v = value(values, s, a)
        if v > best:
            best, choice, ties = v, a, 1
        elif v == best:
            ties += 1
    if ties == 1:
        return choice
    pick = uniform(rng, ties)
    for a in range(lo, hi):
        if value(values, s, a) == best:
            if pick == 0:
                return a
            pick -= 1
    return choice


@kernel
def act(values: Any, rng: Any, offered: Any, s: int, epsilon: float) -> int:
    """Epsilon-greedy in row `s`: an offered action drawn uniformly with probability
    epsilon, else greedy."""
    if epsilon > 0.0 and rng.random() < epsilon:
        lo, hi = actions(offered, s, values[0].shape[1])
        return lo + uniform(rng, hi - lo)
    return greedy(values, rng, offered, s)


@kernel
def expected_value(values: Any, offered: Any, s: int, epsilon: float) -> float:
    """Σ_a π(a|s) value(s, a) under epsilon-greedy over the offered actions."""
    lo, hi = actions(offered, s, values[0].shape[1])
    best = value(values, s, lo)
    total = best
    for a in range(lo + 1, hi):
        v = value(values, s, a)
        total += v
        best = max(best, v)
    return epsilon * total / (hi - lo) + (1.0 - epsilon) * best


@kernel(inline=True)
def max_value(q: Any, offered: Any, s: int) -> float:
    """The largest value in row `s` of `q` among the actions it offers."""
    lo, hi = actions(offered, s, q.shape[1])
    top = q[s, lo]
    for b in range(lo + 1, hi):
        top = max(top, q[s, b])
    return top


@kernel(inline=True)
def td_update(q: Any, counts: Any, visits: Any, hp: Any, s: int, a: int, r: float,
              future: float, log: Any) -> float:
    """Move q[s, a] toward r + γ·future, counting the visit; log row 0: the target, the
    future term, Q before and after, the step size, the count. The |TD error|."""
    target = r + hp.discount * future
    counts[s, a] += 1
    visits[s] += 1
    alpha = step_size(hp.learning_rate, hp.by_visits, counts[s, a])
    before = q[s, a]
    q[s, a] = before + alpha * (target - before)
    log[0, 0] = target
    log[0, 1] = future
    log[0, 2] = before
    log[0, 3] = q[s, a]
    log[0, 4] = alpha
    log[0, 5] = counts[s, a]
    return abs(target - before)


def offered_ranges(mask: np.ndarray | None, n_actions: int) -> np.ndarray:
    """`offered` from a bool mask `[rows, n_actions]` (None: all); ValueError when a row
    offers none, or actions apart."""
    if mask is None:
        return np.zeros((0, 2), dtype=np.uint32)
    lo = np.argmax(mask, axis=1)
    hi = n_actions - np.argmax(mask[:, ::-1], axis=1)
    runs = np.arange(n_actions) >= lo[:, None]
    runs &= np.arange(n_actions) < hi[:, None]
    apart = np.flatnonzero((runs != mask).any(axis=1) | ~mask.any(axis=1))
    if len(apart):
        row = int(apart[0])
        raise ValueError(f"each row must offer one run of actions (row {row} offers "
                         f"{np.flatnonzero(mask[row]).tolist()}, out of {n_actions})")
    return np.stack([lo, hi], axis=1).astype(np.uint32)


def new_log(rows: int = 1) -> np.ndarray:
    """A log for `rows` rows of numbers (`LOG_WIDTH` each), zeros."""
    return np.zeros((max(1, rows), LOG_WIDTH), dtype=np.float64)
