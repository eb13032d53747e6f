"""`return_range`: the lowest and the highest return one episode of a finite MDP can have."""

from __future__ import annotations

import math

import numpy as np

from tui_gym.core.mdp.model import FiniteMDP

__all__ = ["MAX_SWEEPS", "return_range"]

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
