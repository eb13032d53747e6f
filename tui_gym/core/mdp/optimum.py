"""The optimum: `solve(model)` and the `Solution` it returns, `optimal_actions`, the
`Ladder` of optimal action values for every number of steps left, and how far a policy is
from the optimum (`exact_gap` and the `Gap` it returns, `gap_of`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.evaluation import (
    backup,
    check_gamma,
    evaluate,
    expected_value,
    policy_ends,
    solve_linear,
    surely_ending,
)
from tui_gym.core.mdp.model import BoolArray, FiniteMDP, FloatArray, IntArray
from tui_gym.core.mdp.policy import policy_matrix

_MAX_ITERATIONS = 100_000
TIE_GAMMA = 0.99  # the discount that breaks ties between moves of equal exact value
LADDER_LIMIT = 4_000_000  # Q-values kept per ladder (steps x states x actions) at most
CHOICES_KEPT = 8  # optimal-action masks (and rungs solved past LADDER_LIMIT) kept per ladder


@dataclass(frozen=True)
class Solution:
    """The optimum of a model.

    `q[s, a]`: the best value of taking `a` in `s`, with `steps_left` to go (None: no
    limit); `v` the best over actions; `value` its average over the start. `policy[s]`:
    an optimal action making a good fixed policy (with a limit, the one that stays
    optimal for the most step counts below). With no limit and gamma = 1, `v` is -inf
    where no policy surely ends, and +inf everywhere when the optimum is unbounded.
    """

    q: FloatArray
    v: FloatArray
    value: float
    gamma: float
    steps_left: int | None
    policy: IntArray

    @property
    def unbounded(self) -> bool:
        return self.value == np.inf


def optimal_actions(q: npt.ArrayLike, atol: float = 1e-9, rtol: float = 1e-9) -> BoolArray:
    """`[S, A]`: the actions within `atol + rtol * |best|` of each row's best value (equal
    to it where it is infinite)."""
    values = np.asarray(q, dtype=np.float64)
    best = values.max(axis=1, keepdims=True)
    finite = np.isfinite(best)
    slack = np.where(finite, atol + rtol * np.abs(np.where(finite, best, 0.0)), 0.0)
    with np.errstate(invalid="ignore"):
        close = values >= best - slack
    return np.where(finite, close, values == best)


def _solution(
    model: FiniteMDP, q: FloatArray, gamma: float, steps_left: int | None, policy: IntArray
) -> Solution:
    v = q.max(axis=1)
    for array in (q, v, policy):
        array.setflags(write=False)
    return Solution(q, v, expected_value(model, v), gamma, steps_left, policy)


def _backward_induction(model: FiniteMDP, gamma: float, steps: int) -> tuple[FloatArray, IntArray]:
    """Q with `steps` steps left, and the optimal action there that has been optimal longest
    (with gamma 1 a wasted step costs nothing: the one needing the least time to spare)."""
    v = np.zeros(model.n_states)
    # last_off[s, a]: the most steps left (so far) at which `a` was not optimal in `s`.
    last_off = np.zeros((model.n_states, model.n_actions), dtype=np.int64)
    for k in range(1, steps + 1):
        q = backup(model, v, gamma)
        off = ~optimal_actions(q)
        last_off[off] = k
        settled = q.max(axis=1)
        if np.array_equal(settled, v):
            # The same backup of the same values from here on: every later step
            # left gives this q again, and the actions not optimal now stay so.
            last_off[off] = steps
            break
        v = settled
    policy = np.argmin(last_off, axis=1).astype(np.int64)
    return q, policy


def _policy_iteration(
    model: FiniteMDP, gamma: float, rows: BoolArray, safe: BoolArray, policy: IntArray
) -> tuple[FloatArray, IntArray, bool]:
    """Q and a policy of the best over `rows` using `safe` actions from a safe `policy` that
    ends surely; True when a change closes a cycle that gains reward (the optimum is
    unbounded). Changes only for a clear gain, so it cannot cycle."""
    states = np.arange(model.n_states)
    for _ in range(_MAX_ITERATIONS):
        v = np.full(model.n_states, -np.inf)
        v[rows] = solve_linear(model, policy_matrix(model, policy), gamma, rows)
        q = backup(model, v, gamma)
        q[~safe] = -np.inf
        best = np.argmax(q, axis=1)
        tolerance = 1e-10 * max(1.0, float(np.abs(v[rows]).max(initial=0.0)))
        improves = rows & (q[states, best] > q[states, policy] + tolerance)
        if not improves.any():
            return q, policy, False
        policy = np.where(improves, best, policy)
        if gamma == 1.0 and not policy_ends(model, policy_matrix(model, policy))[rows].all():
            return q, policy, True
    raise RuntimeError("policy iteration did not settle")  # finite MDPs always settle


def solve(model: FiniteMDP, gamma: float = 1.0, *, steps_left: int | None = None) -> Solution:
    """The optimal action values, values and optimum of `model` (see the package docstring),
    with `steps_left` of an episode limit H to go (1 to H, default H; no limit: ignored)."""
    gamma = check_gamma(gamma)
    horizon = model.horizon
    if horizon is not None:
        steps = horizon if steps_left is None else int(steps_left)
        if not 1 <= steps <= horizon:
            raise ValueError(f"steps_left must be in [1, {horizon}], got {steps_left!r}")
        q, policy = _backward_induction(model, gamma, steps)
        return _solution(model, q, gamma, steps, policy)
    if gamma < 1.0:
        every = np.ones(model.n_states, dtype=bool)
        safe = np.ones((model.n_states, model.n_actions), dtype=bool)
        start = np.argmax(model.expected_reward, axis=1).astype(np.int64)
        q, policy, _ = _policy_iteration(model, gamma, every, safe, start)
        return _solution(model, q, gamma, None, policy)
    ending = surely_ending(model)
    if not ending.states.any():
        q = np.full((model.n_states, model.n_actions), -np.inf)
        return _solution(model, q, gamma, None, ending.policy)
    q, policy, unbounded = _policy_iteration(
        model, gamma, ending.states, ending.safe, ending.policy
    )
    if unbounded:
        q = np.where(ending.safe, np.inf, -np.inf)
    return _solution(model, q, gamma, None, policy)


class Ladder:
    """Optimal action values of a model for every number of steps left, kept: `q(k)` is Q*
    with `k` steps left (with no horizon, the stationary optimum), by backward induction;
    past `LADDER_LIMIT` values each rung is solved when asked for (the last few kept)."""

    def __init__(self, model: FiniteMDP) -> None:
        self.model = model
        self._rungs: dict[float, FloatArray] = {}
        self._stationary: dict[float, FloatArray] = {}
        self._choices: dict[int | None, tuple[BoolArray, BoolArray]] = {}
        self._solved: dict[tuple[int, float], FloatArray] = {}  # past LADDER_LIMIT, the last few

    def q(self, steps_left: int | None = None, gamma: float = 1.0) -> FloatArray:
        model = self.model
        horizon = model.horizon
        if horizon is None:
            if gamma not in self._stationary:
                self._stationary[gamma] = solve(model, gamma).q
            return self._stationary[gamma]
        k = horizon if steps_left is None else min(max(1, int(steps_left)), horizon)
        if horizon * model.n_states * model.n_actions > LADDER_LIMIT:
            found = self._solved.get((k, gamma))
            if found is None:
                if len(self._solved) >= CHOICES_KEPT:
                    self._solved.clear()
                found = self._solved[k, gamma] = solve(model, gamma, steps_left=k).q
            return found
        if gamma not in self._rungs:
            self._rungs[gamma] = _induction(model, gamma, horizon)
        return self._rungs[gamma][k - 1]

    def choices(self, steps_left: int | None = None) -> tuple[BoolArray, BoolArray]:
        """`[S, A]` twice, read-only: the actions of optimal value, and the quickest of
        them (kept for the last few `steps_left`: past `LADDER_LIMIT` each is two solves)."""
        found = self._choices.get(steps_left)
        if found is None:
            if len(self._choices) >= CHOICES_KEPT:
                self._choices.clear()
            found = self._choices[steps_left] = self._choose(steps_left)
        return found

    def _choose(self, steps_left: int | None) -> tuple[BoolArray, BoolArray]:
        best = optimal_actions(self.q(steps_left))
        tie = np.where(best, self.q(steps_left, TIE_GAMMA), -np.inf)
        with np.errstate(invalid="ignore"):
            quickest = best & optimal_actions(tie)
        # A row where the discounted values say nothing (all -inf) keeps every optimal action.
        quickest[~quickest.any(axis=1)] = best[~quickest.any(axis=1)]
        best.setflags(write=False)
        quickest.setflags(write=False)
        return best, quickest


def _induction(model: FiniteMDP, gamma: float, horizon: int) -> FloatArray:
    """`[H, S, A]`: Q* for 1 to H steps left, the numbers `backup` gives (outcomes added one
    by one in `sum`'s order, which is quicker than numpy's reduction over a short axis)."""
    reward = model.expected_reward
    going = [np.ascontiguousarray(model.continue_prob[..., k]) for k in range(model.max_outcomes)]
    following = [np.ascontiguousarray(model.next_state[..., k]) for k in range(model.max_outcomes)]
    rungs = np.empty((horizon, model.n_states, model.n_actions))
    v = np.zeros(model.n_states)
    for i in range(horizon):
        ahead = going[0] * v[following[0]]
        for k in range(1, len(going)):
            ahead += going[k] * v[following[k]]
        q = rungs[i]
        np.multiply(ahead, gamma, out=q)
        q += reward
        v = q.max(axis=1)
    rungs.setflags(write=False)
    return rungs


@dataclass(frozen=True)
class Gap:
    """A policy's exact value beside the optimum: `gap = optimal_value - exact_value`, at
    least 0 (inf for a policy that never ends against an optimum that does)."""

    exact_value: float
    optimal_value: float
    gap: float
    never_ends: bool = False


ROUND_OFF = 1e-9
"""Differences within this share of the optimum's magnitude (at least 1) count as 0."""


def gap_of(optimum: float, value: float) -> float:
    """The optimum minus a policy's value, never negative (round-off counts as 0)."""
    if optimum == value:
        return 0.0
    difference = optimum - value
    if math.isfinite(difference) and difference <= ROUND_OFF * max(1.0, abs(optimum)):
        return 0.0
    return difference


def exact_gap(
    model: FiniteMDP, policy: npt.ArrayLike, gamma: float = 1.0, optimum: Solution | None = None
) -> Gap:
    """The exact value of `policy`, the optimum (`optimum`, from `solve(model, gamma)`, to
    reuse one), and the gap between them."""
    if optimum is None:
        optimum = solve(model, gamma)
    elif optimum.gamma != float(gamma) or optimum.steps_left != model.horizon:
        raise ValueError(
            f"the optimum given is for gamma={optimum.gamma}, {optimum.steps_left} steps left; "
            f"this needs gamma={gamma}, {model.horizon} steps left"
        )
    value = evaluate(model, policy, gamma)
    return Gap(value.value, optimum.value, gap_of(optimum.value, value.value), value.never_ends)
