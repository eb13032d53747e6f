"""Policies for a `FiniteMDP`, in the two forms the package accepts."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import PROBABILITY_TOLERANCE, FiniteMDP

__all__ = ["PolicyError", "greedy_policy", "policy_matrix"]


class PolicyError(ValueError):
    """An array that is not a policy of the model it is used with."""


def policy_matrix(model: FiniteMDP, policy: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The `[S, A]` action probabilities of a deterministic (`[S]`) or stochastic policy."""
    array = np.asarray(policy)
    n_states, n_actions = model.n_states, model.n_actions
    if array.shape == (n_states,):
        if not np.issubdtype(array.dtype, np.integer):
            raise PolicyError(f"a deterministic policy holds integer actions, got {array.dtype}")
        if array.min() < 0 or array.max() >= n_actions:
            raise PolicyError(f"a policy's actions must be in [0, {n_actions - 1}]")
        matrix = np.zeros((n_states, n_actions))
        matrix[np.arange(n_states), array] = 1.0
        return matrix
    if array.shape == (n_states, n_actions):
        matrix = np.asarray(array, dtype=np.float64)
        if not np.isfinite(matrix).all() or (matrix < 0).any():
            raise PolicyError("a stochastic policy holds probabilities in [0, 1]")
        totals = matrix.sum(axis=1)
        bad = np.abs(totals - 1.0) > PROBABILITY_TOLERANCE
        if bad.any():
            state = int(np.argmax(bad))
            raise PolicyError(
                f"the action probabilities of state {state} sum to {totals[state]:.12g}, not 1"
            )
        return matrix
    raise PolicyError(
        f"a policy is an [S] array of actions or an [S, A] array of probabilities; "
        f"this model has S={n_states}, A={n_actions}, got shape {array.shape}"
    )


def greedy_policy(q: npt.ArrayLike, epsilon: float = 0.0) -> npt.NDArray[np.float64]:
    """`[S, A]`: the actions equal to each row's maximum of `q` shared equally, mixed with
    the uniform policy by `epsilon`."""
    values = np.asarray(q, dtype=np.float64)
    if values.ndim != 2 or 0 in values.shape:
        raise PolicyError(f"action values must be an [S, A] array, got shape {values.shape}")
    if np.isnan(values).any():
        raise PolicyError("action values must be numbers, not NaN")
    if not 0.0 <= epsilon <= 1.0:
        raise PolicyError(f"epsilon must be in [0, 1], got {epsilon!r}")
    best = values == values.max(axis=1, keepdims=True)
    greedy = best / best.sum(axis=1, keepdims=True)
    return (1.0 - epsilon) * greedy + epsilon / values.shape[1]
