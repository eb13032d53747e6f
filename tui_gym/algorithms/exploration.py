"""Exploration shared by every learner: the epsilon schedule, epsilon-greedy and greedy choice.

- `linear_epsilon`: epsilon falls linearly from its start to its final value
  over a share of the episode budget, then stays there.
- `epsilon_greedy_batch` / `greedy_batch`: one action per row of action
  values; ties among the best broken uniformly at random (the highest of
  independent uniform draws among the tied actions wins).
- `epsilon_greedy_one` / `greedy_one`: the same policy for one state, drawing
  from the generator in the order a one-at-a-time agent does (a coin, then a
  random action or a tie-break only when needed). The two orders give the
  same distribution, not the same draws: the scalar engine uses the `_one`
  forms, the vector engine the batched ones.
- `policy_probabilities` / `expected_values`: the probability of each action
  under epsilon-greedy with uniform tie-breaking, and the expected action
  value under it (Expected SARSA's target, Monte Carlo's value at a cut-off).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "row_max",
    "row_sum",
    "epsilon_greedy_batch",
    "epsilon_greedy_one",
    "expected_values",
    "greedy_batch",
    "greedy_one",
    "linear_epsilon",
    "policy_probabilities",
]


def linear_epsilon(
    episode: int, start: float, final: float, decay_fraction: float, budget: int
) -> float:
    """Epsilon for a 0-based episode: from `start` to `final` over `decay_fraction * budget`."""
    decay_episodes = decay_fraction * budget
    if decay_episodes <= 0 or episode >= decay_episodes:
        return final
    frac = episode / decay_episodes
    return start + frac * (final - start)


# Below this many actions a loop over columns beats numpy's reduction along a short axis
# (several times over): every batch of a vector engine takes a few such row maxima.
_COLUMN_LOOP = 16


def row_max(values: np.ndarray) -> np.ndarray:
    """The maximum of each row of `values` (k, n), as `values.max(axis=1)`, only faster."""
    n = values.shape[1]
    if n > _COLUMN_LOOP or n == 0:
        return values.max(axis=1)
    out = values[:, 0].copy()
    for j in range(1, n):
        np.maximum(out, values[:, j], out=out)
    return out


def row_sum(values: np.ndarray) -> np.ndarray:
    """The sum of each row of `values` (k, n), adding the columns in order."""
    n = values.shape[1]
    if n > _COLUMN_LOOP or n == 0:
        return values.sum(axis=1)
    out = values[:, 0].astype(np.float64)
    for j in range(1, n):
        out += values[:, j]
    return out


def greedy_batch(values: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The best action of each row of `values` (k, n_actions), ties broken uniformly."""
    tied = values == row_max(values)[:, None]
    draws = rng.random(values.shape)
    return np.argmax(np.where(tied, draws, -1.0), axis=1)


def epsilon_greedy_batch(
    values: np.ndarray, epsilon: float, rng: np.random.Generator
) -> np.ndarray:
    """Epsilon-greedy actions for every row of `values` (k, n_actions)."""
    k, n_actions = values.shape
    actions = greedy_batch(values, rng)
    explore = np.flatnonzero(rng.random(k) < epsilon)
    if explore.size:
        actions[explore] = rng.integers(n_actions, size=explore.size)
    return actions


def greedy_one(values: np.ndarray, rng: np.random.Generator) -> int:
    """The best action for one row of values, ties broken uniformly."""
    best = values.max()
    ties = np.flatnonzero(values == best)
    if len(ties) == 1:
        return int(ties[0])
    return int(ties[rng.integers(len(ties))])


def epsilon_greedy_one(values: np.ndarray, epsilon: float, rng: np.random.Generator) -> int:
    """A random action with probability epsilon, else the greedy one."""
    if rng.random() < epsilon:
        return int(rng.integers(len(values)))
    return greedy_one(values, rng)


def policy_probabilities(values: np.ndarray, epsilon: float) -> np.ndarray:
    """Epsilon-greedy action probabilities per row of `values` (k, n_actions).

    Each action gets epsilon / n_actions; the greedy share 1 - epsilon is split
    evenly among the actions tied for the best value.
    """
    n_actions = values.shape[1]
    tied = values == row_max(values)[:, None]
    share = (1.0 - epsilon) / row_sum(tied)[:, None]
    return epsilon / n_actions + tied * share


def expected_values(values: np.ndarray, epsilon: float) -> np.ndarray:
    """Σ_a π(a|s) Q(s, a) per row of `values` under epsilon-greedy with uniform tie-breaking."""
    return row_sum(policy_probabilities(values, epsilon) * values)
