"""Exact policy evaluation: `evaluate(model, policy)` and the `PolicyValue` it returns; which
episodes end (`policy_ends`, `surely_ending`: the graph facts behind values with no limit and
no discount); `PolicyArrays`, a policy's one-step Bellman expectation gathered once and swept
many times; and `return_range`, the lowest and highest return one episode can have."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import BoolArray, FiniteMDP, FloatArray, IntArray
from tui_gym.core.mdp.policy import policy_matrix

DENSE_LIMIT = 2000
"""Up to this many states a policy's value is one dense linear solve; above, an iteration."""

DOUBLING_STATES = 80
"""Up to this many states a long episode limit is summed by doubling (`PolicyArrays.over`)."""

_MAX_SWEEPS = 1_000_000


def check_gamma(gamma: float) -> float:
    """`gamma` as a float in (0, 1], else `ValueError`."""
    value = float(gamma)
    if not 0.0 < value <= 1.0:
        raise ValueError(f"gamma must be in (0, 1], got {gamma!r}")
    return value


@dataclass(frozen=True)
class PolicyValue:
    """The exact value of one policy: `v[s]` from each state, `value` over the start;
    `never_ends` (no limit, gamma 1): it may never end an episode, and `value` is -inf."""

    v: FloatArray
    value: float
    gamma: float
    horizon: int | None
    never_ends: bool = False

    def __post_init__(self) -> None:
        self.v.setflags(write=False)


def expected_value(model: FiniteMDP, v: FloatArray) -> float:
    """The initial distribution's average of `v`, with minus infinity where it puts mass on one."""
    weight = model.initial > 0
    if np.isneginf(v[weight]).any():
        return float("-inf")
    if np.isposinf(v[weight]).any():
        return float("inf")
    return float(model.initial[weight] @ v[weight])


def backup(model: FiniteMDP, v: FloatArray, gamma: float) -> FloatArray:
    """`[S, A]`: one step's expected reward plus the discounted value of where it leads (an
    infinite `v` an action may reach makes its value that infinity; -inf for both signs)."""
    finite = np.isfinite(v)
    if finite.all():
        ahead = (model.continue_prob * v[model.next_state]).sum(axis=2)
        return model.expected_reward + gamma * ahead
    q = backup(model, np.where(finite, v, 0.0), gamma)
    continues = model.continue_prob > 0
    q[(continues & np.isposinf(v)[model.next_state]).any(axis=2)] = np.inf
    q[(continues & np.isneginf(v)[model.next_state]).any(axis=2)] = -np.inf
    return q


def transition_matrix(weight: FloatArray, target: IntArray, n: int) -> FloatArray:
    """`[R, n]`: per row r of `weight` and `target` (`[R, ...]`), the summed weight of going
    on to each of `n` states."""
    rows = len(weight)
    weight, target = weight.reshape(rows, -1), target.reshape(rows, -1)
    keep = weight > 0
    flat = np.nonzero(keep)[0] * n + target[keep]
    counts = np.bincount(flat, weights=weight[keep], minlength=rows * n)
    return np.asarray(counts, dtype=np.float64).reshape(rows, n)


def solve_linear(
    model: FiniteMDP, matrix: FloatArray, gamma: float, rows: npt.NDArray[np.bool_]
) -> FloatArray:
    """The values on `rows` of `v = r + gamma P v`, for a policy that ends surely on `rows`
    and never leaves them: a dense solve up to `DENSE_LIMIT` states, else iterated."""
    n = int(rows.sum())
    if n == 0:
        return np.zeros(0)
    reward = (matrix[rows] * model.expected_reward[rows]).sum(axis=1)
    if n <= DENSE_LIMIT:
        index = np.full(model.n_states, -1, dtype=np.int64)
        index[rows] = np.arange(n)
        weight = matrix[rows][:, :, None] * model.continue_prob[rows]
        system = np.eye(n) - gamma * transition_matrix(weight, index[model.next_state[rows]], n)
        return np.linalg.solve(system, reward)
    v_full = np.zeros(model.n_states)
    for _ in range(_MAX_SWEEPS):
        step = (matrix * backup(model, v_full, gamma)).sum(axis=1)
        step[~rows] = 0.0
        change = np.abs(step - v_full).max()
        v_full = step
        if change <= 1e-13 * max(1.0, float(np.abs(v_full).max())):
            return v_full[rows]
    raise RuntimeError(f"policy evaluation did not settle in {_MAX_SWEEPS} sweeps")


def evaluate(model: FiniteMDP, policy: npt.ArrayLike, gamma: float = 1.0) -> PolicyValue:
    """The exact value of `policy` (`[S]` actions or `[S, A]` probabilities) on `model`."""
    gamma = check_gamma(gamma)
    matrix = policy_matrix(model, policy)
    horizon = model.horizon
    if horizon is not None:
        arrays = PolicyArrays.of(model, matrix)
        # Sweeps until they settle; where that takes long, the whole limit by doubling:
        # two matrix products per binary digit of it, which up to `DOUBLING_STATES`
        # states cost about as much as a sweep each.
        limit = horizon
        if arrays.dense is not None and model.n_states <= DOUBLING_STATES:
            limit = min(horizon, 4 * horizon.bit_length())
        v = np.zeros(model.n_states)
        for _ in range(limit):
            step = arrays.sweep(v, gamma)
            if np.array_equal(step, v):  # the same sweep from the same values: settled
                break
            v = step
        else:
            if limit < horizon:
                v = arrays.over(horizon, gamma)
        return PolicyValue(v, expected_value(model, v), gamma, horizon)
    # Discounted, every state has a value; else only those from which the policy ends surely.
    ends = np.ones(model.n_states, dtype=bool) if gamma < 1.0 else policy_ends(model, matrix)
    v = np.full(model.n_states, -np.inf)
    v[ends] = solve_linear(model, matrix, gamma, ends)
    value = expected_value(model, v)
    return PolicyValue(v, value, gamma, None, never_ends=value == -np.inf)


def _backward_reach(
    targets: BoolArray, edges: BoolArray, next_state: npt.NDArray[np.int64]
) -> BoolArray:
    """States that reach `targets` (or start there) along `edges` `[S, A, K]`."""
    reached = targets.copy()
    while True:
        grown = reached | np.any(edges & reached[next_state], axis=(1, 2))
        if (grown == reached).all():
            return reached
        reached = grown


def policy_ends(model: FiniteMDP, matrix: npt.NDArray[np.float64]) -> BoolArray:
    """`[S]`: the states from which the policy `matrix` (`[S, A]`) ends the episode surely:
    those that cannot reach a state from which it can never end."""
    possible = (matrix[:, :, None] > 0) & (model.prob > 0)
    moves = possible & ~model.terminal
    ends_now: BoolArray = np.any(possible & model.terminal, axis=(1, 2))
    can_end = _backward_reach(ends_now, moves, model.next_state)
    return ~_backward_reach(~can_end, moves, model.next_state)


@dataclass(frozen=True)
class SurelyEnding:
    """Where the episode can be ended with probability 1 (`states`), the actions that stay
    inside them (`safe`), and a safe `policy` that ends it surely (0 outside `states`)."""

    states: BoolArray
    safe: BoolArray
    policy: npt.NDArray[np.int64]


def surely_ending(model: FiniteMDP) -> SurelyEnding:
    """The states from which the episode can be ended with probability 1 (almost-sure reach)."""
    possible = model.prob > 0
    moves = possible & ~model.terminal
    ends_now = (possible & model.terminal).any(axis=2)
    n_states = model.n_states
    inside = np.ones(n_states, dtype=bool)
    while True:
        # Safe actions never leave `inside`; from those, grow the set that reaches an end.
        safe = inside[:, None] & ~(moves & ~inside[model.next_state]).any(axis=2)
        policy = np.zeros(n_states, dtype=np.int64)
        step = safe & ends_now
        reached: BoolArray = np.any(step, axis=1)
        policy[reached] = np.argmax(step[reached], axis=1)
        while True:
            step = safe & (moves & reached[model.next_state]).any(axis=2) & ~reached[:, None]
            new: BoolArray = np.any(step, axis=1)
            if not new.any():
                break
            policy[new] = np.argmax(step[new], axis=1)
            reached |= new
        if (reached == inside).all():
            return SurelyEnding(states=inside, safe=safe, policy=policy)
        inside = reached


DENSE_STATES = 1000
SPARSE_SHARE = 16  # a sweep gathers (no dense product) where a state leads to 1/16 of all or fewer


@dataclass(frozen=True)
class PolicyArrays:
    """`reward[s]`: the policy's expected reward in `s`; `weight[s, j]` the chance of
    going on to `target[s, j]` (0 where the episode ends); `dense[s, t]`, when there
    are few states, the chance of going on from `s` to `t`."""

    reward: FloatArray
    weight: FloatArray
    target: IntArray
    dense: FloatArray | None = None

    @classmethod
    def of(cls, model: FiniteMDP, matrix: FloatArray) -> PolicyArrays:
        """The arrays of the policy `matrix` (`[S, A]` action probabilities) on `model`."""
        n_states = model.n_states
        reward = (matrix * model.expected_reward).sum(axis=1)
        # The actions the policy takes first, as many as the most any state takes.
        taken = matrix > 0
        actions = np.argsort(~taken, axis=1, kind="stable")[:, : max(1, taken.sum(axis=1).max())]
        rows = np.arange(n_states)[:, None]
        chance = np.take_along_axis(matrix, actions, axis=1)
        weight = (chance[:, :, None] * model.continue_prob[rows, actions]).reshape(n_states, -1)
        target = model.next_state[rows, actions].reshape(n_states, -1)
        width = max(1, int((weight > 0).sum(axis=1).max()))
        if width < weight.shape[1]:
            keep = np.argsort(weight <= 0, axis=1, kind="stable")[:, :width]
            weight = np.take_along_axis(weight, keep, axis=1)
            target = np.take_along_axis(target, keep, axis=1)
        dense = transition_matrix(weight, target, n_states) if n_states <= DENSE_STATES else None
        return cls(reward, np.ascontiguousarray(weight), np.ascontiguousarray(target), dense)

    def sweep(self, v: FloatArray, gamma: float) -> FloatArray:
        """One synchronous sweep: every state backed up from `v`."""
        sparse = self.weight.shape[1] * SPARSE_SHARE <= len(v)  # few outcomes a state
        if self.dense is not None and not sparse and np.isfinite(v).all():
            return self.reward + gamma * (self.dense @ v)
        return self.reward + gamma * (self.weight * v[self.target]).sum(axis=1)

    def over(self, steps: int, gamma: float) -> FloatArray:
        """The values over `steps` steps, from the dense matrix (see `horizon_sum`)."""
        assert self.dense is not None
        return horizon_sum(gamma * self.dense, self.reward, steps)

    def sweep_in_place(self, v: FloatArray, gamma: float) -> float:
        """One in-place sweep of `v`, state 0 first; the largest change."""
        reward, weight, target, dense = self.reward, self.weight, self.target, self.dense
        delta = 0.0
        for s in range(len(v)):
            if dense is not None:
                new = reward[s] + gamma * float(dense[s] @ v)
            else:
                new = reward[s] + gamma * float(weight[s] @ v[target[s]])
            delta = max(delta, abs(new - v[s]))
            v[s] = new
        return float(delta)


def horizon_sum(matrix: FloatArray, reward: FloatArray, steps: int) -> FloatArray:
    """`sum over t < steps of P^t r` for `P` = `matrix` `[..., S, S]` and `r` = `reward`
    `[..., S]`, by doubling: two matrix products per binary digit of `steps`."""
    total = np.zeros_like(reward)  # the sum over the first k steps
    power = np.broadcast_to(np.eye(reward.shape[-1]), matrix.shape)  # P^k
    for digit in bin(steps)[2:]:
        total = total + np.einsum("...st,...t->...s", power, total)  # k -> 2k
        power = power @ power
        if digit == "1":  # k -> k + 1
            total = reward + np.einsum("...st,...t->...s", matrix, total)
            power = matrix @ power
    return total


MAX_SWEEPS = 1_000  # without a limit, sweeps before a side still changing counts as unbounded


def _extreme(model: FiniteMDP, best: bool) -> float:
    possible = model.prob > 0
    rewards = np.where(possible, model.reward, -np.inf if best else np.inf)
    pick = np.max if best else np.min
    value = np.zeros(model.n_states)
    sweeps = model.horizon if model.horizon is not None else MAX_SWEEPS
    for _ in range(sweeps):
        after = np.where(model.terminal, 0.0, value[model.next_state])
        new = pick(pick(rewards + after, axis=2), axis=1)
        if np.array_equal(new, value):  # the sweeps left would change nothing either
            break
        value = new
    else:
        if model.horizon is None:
            return math.inf if best else -math.inf
    start = value[model.initial > 0]
    return float(start.max() if best else start.min())


def return_range(model: FiniteMDP) -> tuple[float, float]:
    """(lowest, highest) return of one episode of `model`; ±inf on a side with no bound."""
    return _extreme(model, best=False), _extreme(model, best=True)
