"""The rule registry, and the exploration and step sizes every learner shares, as kernels.

An algorithm registers a `Rule` for its `Params` (a NamedTuple of its compiled
hyperparameters, `register(Params, Rule(...))`):

- `update(tables, hp, rng, offered, s, a, r, s2, terminated, truncated, a2, epsilon,
  log)`: its update rule for one transition from table row `s` by action `a` to row
  `s2` (`a2`: the next action when `next_first`, else -1), returning |TD error|
  (Monte Carlo: the sum over the episode's updates at its end, else 0); it
  writes the numbers the step-by-step view explains into `log[0]` (and more
  rows when there is room: Monte Carlo's updates at an episode's end);
- `acting(tables, hp)`: the tables whose sum is the action values it acts on
  (default: `(tables[0],)`);
- `begin(tables, hp)`: what it does as an episode starts (default: nothing);
- `full(tables, hp)`: whether it needs room before one more step (default: never);
- `next_first`: the next action is chosen before the update (SARSA).

The stubs below dispatch on the type of `hp`: in plain Python by looking the
rule up; in compiled code at compile time (`jit.start` registers them as Numba
overloads), so each algorithm gets a specialisation of the one loop, cached.
`act` is epsilon-greedy with a random tie-break, drawing only what it needs;
it and `greedy` read the action values through `acting`, so one compiled form
serves every algorithm that acts on the same number of tables.

**Offered actions.** Where a game's states do not all offer every action,
`offered[row, action]` (a bool array) marks those each table row offers;
`None` where every row offers every action. Acting (`act`, `greedy`,
`draw`), the max (`max_value`) and the
ε-greedy expectation (`expected_value`) range over the offered actions only;
a rule passes `offered` on to them and needs nothing else. `offers` and
`draw` are stubs compiled by the type of `offered`: for `None` they are the
constant True and `uniform(rng, n)`, so a game that offers every action runs
no mask code at all; a mask that offers everything draws the same numbers.
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
    "begin",
    "draw",
    "epsilon_at",
    "expected_value",
    "full",
    "greedy",
    "max_value",
    "next_first",
    "offers",
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
    """One algorithm's compiled parts (see the module docstring)."""

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


def offers(offered: Any, s: int, a: int) -> bool:
    """Whether row `s` offers action `a` (`offered` None: every row offers every action;
    compiled, that is the constant True)."""
    return offered is None or bool(offered[s, a])


def draw(rng: Any, offered: Any, s: int, n: int) -> int:
    """An action drawn uniformly from those row `s` offers (of `n`): `uniform(rng, n)` when
    every action is offered."""
    return uniform(rng, n) if offered is None else draw_offered(rng, offered, s, n)


# --- shared by every learner ---------------------------------------------------------------


@kernel(inline=True)
def step_size(learning_rate: float, by_visits: bool, n: int) -> float:
    """The step size of the n-th update (n >= 1) of one (state, action): the learning
    rate, or with `by_visits` max(learning rate, 1/n), a plain average until 1/n reaches it."""
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
    """An integer drawn uniformly from 0 to n - 1 (one uniform double; several times
    quicker in compiled code than `Generator.integers`)."""
    return min(int(rng.random() * n), n - 1)


@kernel(inline=True)
def first_offered(offered: Any, s: int, n: int) -> int:
    """The first action row `s` offers (0 when every action is offered)."""
    a = 0
    while a < n - 1 and not offers(offered, s, a):
        a += 1
    return a


@kernel
def draw_offered(rng: Any, offered: Any, s: int, n: int) -> int:
    """An action drawn uniformly from those `offered[s]` marks."""
    count = 0
    for a in range(n):
        if offered[s, a]:
            count += 1
    pick = uniform(rng, count)
    for a in range(n):
        if offered[s, a]:
            if pick == 0:
                return a
            pick -= 1
    return n - 1


@kernel(inline=True)
def value(values: Any, s: int, a: int) -> float:
    """The action value of (s, a): the sum over the tables `values` (see `acting`)."""
    total = values[0][s, a]
    for i in range(1, len(values)):
        total += values[i][s, a]
    return total


@kernel
def greedy(values: Any, rng: Any, offered: Any, s: int) -> int:
    """The best-valued action row `s` offers (`values`: the tables `acting` gives), ties
    broken uniformly (a draw only on a tie)."""
    n = values[0].shape[1]
    choice = first_offered(offered, s, n)
    best = value(values, s, choice)
    ties = 1
    for a in range(choice + 1, n):
        if not offers(offered, s, a):
            continue
        v = value(values, s, a)
        if v > best:
            best, choice, ties = v, a, 1
        elif v == best:
            ties += 1
    if ties == 1:
        return choice
    pick = uniform(rng, ties)
    for a in range(n):
        if offers(offered, s, a) and value(values, s, a) == best:
            if pick == 0:
                return a
            pick -= 1
    return choice


@kernel
def act(values: Any, rng: Any, offered: Any, s: int, epsilon: float) -> int:
    """Epsilon-greedy in row `s`: an offered action drawn uniformly with probability
    epsilon, else greedy."""
    if epsilon > 0.0 and rng.random() < epsilon:
        return draw(rng, offered, s, values[0].shape[1])
    return greedy(values, rng, offered, s)


@kernel
def expected_value(values: Any, offered: Any, s: int, epsilon: float) -> float:
    """Σ_a π(a|s) value(s, a) under epsilon-greedy over the offered actions, ties sharing
    the greedy part: epsilon times their mean value plus (1 - epsilon) times the best."""
    n = values[0].shape[1]
    first = first_offered(offered, s, n)
    best = value(values, s, first)
    total = best
    count = 1
    for a in range(first + 1, n):
        if offers(offered, s, a):
            v = value(values, s, a)
            total += v
            best = max(best, v)
            count += 1
    return epsilon * total / count + (1.0 - epsilon) * best


@kernel(inline=True)
def max_value(q: Any, offered: Any, s: int) -> float:
    """The largest value in row `s` of `q` among the actions it offers."""
    n = q.shape[1]
    first = first_offered(offered, s, n)
    top = q[s, first]
    for b in range(first + 1, n):
        if offers(offered, s, b):
            top = max(top, q[s, b])
    return top


@kernel(inline=True)
def td_update(q: Any, counts: Any, visits: Any, hp: Any, s: int, a: int, r: float,
              future: float, log: Any) -> float:
    """Move q[s, a] toward r + γ·future by the step size of its next update, counting the
    visit; row 0 of `log` gets the target, the future term, Q before and after, the step
    size and the cell's count. The |TD error|."""
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


def new_log(rows: int = 1) -> np.ndarray:
    """A log for `rows` rows of numbers (`LOG_WIDTH` each), zeros."""
    return np.zeros((max(1, rows), LOG_WIDTH), dtype=np.float64)
