"""Exact policy evaluation: `evaluate(model, policy)` and the `PolicyValue` it returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.ending import policy_ends
from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.core.mdp.policy import policy_matrix
from tui_gym.core.mdp.policy_arrays import PolicyArrays

__all__ = [
    "DENSE_LIMIT", "PolicyValue", "backup", "check_gamma", "evaluate", "expected_value",
    "solve_linear",
]

FloatArray = npt.NDArray[np.float64]

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
    """The exact value of one policy.

    `v[s]`: the value of an episode started in `s`; `value`: the initial
    distribution's average of it. `never_ends`: with no limit and gamma = 1,
    the policy may never end an episode from the initial distribution, and
    `value` is minus infinity (likewise `v` at every state it may not end from).
    """

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
    """`[S, A]`: one step's expected reward plus the discounted value of where it leads.

    An infinite `v` at a state an action may continue to makes that action's
    value the same infinity (minus infinity when both signs are possible).
    """
    finite = np.isfinite(v)
    if finite.all():
        return model.expected_reward + gamma * (model.continue_prob * v[model.next_state]).sum(
            axis=2
        )
    q = backup(model, np.where(finite, v, 0.0), gamma)
    continues = model.continue_prob > 0
    q[(continues & np.isposinf(v)[model.next_state]).any(axis=2)] = np.inf
    q[(continues & np.isneginf(v)[model.next_state]).any(axis=2)] = -np.inf
    return q


def _transition_matrix(
    model: FiniteMDP, matrix: FloatArray, rows: npt.NDArray[np.bool_]
) -> FloatArray:
    """The `[n, n]` matrix of continuing from each of `rows` to each of `rows` under a policy."""
    index = np.full(model.n_states, -1, dtype=np.int64)
    index[rows] = np.arange(int(rows.sum()))
    weight = matrix[rows][:, :, None] * model.continue_prob[rows]
    target = index[model.next_state[rows]]
    n = int(rows.sum())
    source = np.broadcast_to(np.arange(n)[:, None, None], weight.shape)
    keep = weight > 0
    flat = source[keep] * n + target[keep]
    counts = np.bincount(flat, weights=weight[keep], minlength=n * n)
    return np.asarray(counts, dtype=np.float64).reshape(n, n)


def solve_linear(
    model: FiniteMDP, matrix: FloatArray, gamma: float, rows: npt.NDArray[np.bool_]
) -> FloatArray:
    """The values on `rows` of `v = r + gamma P v`, for a policy that ends surely on `rows`.

    Every continuation from `rows` must stay in `rows`. Dense up to
    `DENSE_LIMIT` states; above it, the Bellman expectation is iterated until
    it stops changing at round-off.
    """
    n = int(rows.sum())
    if n == 0:
        return np.zeros(0)
    reward = (matrix[rows] * model.expected_reward[rows]).sum(axis=1)
    if n <= DENSE_LIMIT:
        system = np.eye(n) - gamma * _transition_matrix(model, matrix, rows)
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
    if gamma < 1.0:
        every = np.ones(model.n_states, dtype=bool)
        v = solve_linear(model, matrix, gamma, every)
        return PolicyValue(v, expected_value(model, v), gamma, None)
    ends = policy_ends(model, matrix)
    v = np.full(model.n_states, -np.inf)
    v[ends] = solve_linear(model, matrix, gamma, ends)
    value = expected_value(model, v)
    return PolicyValue(v, value, gamma, None, never_ends=value == -np.inf)
