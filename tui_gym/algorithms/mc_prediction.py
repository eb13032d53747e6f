"""Constant-α Monte Carlo prediction (Sutton & Barto, 2nd ed., section 6.1): V of a fixed
policy from whole-episode returns.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms.base import Extra, filled, restart
from tui_gym.algorithms.prediction import Predictor, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule

__all__ = ["EpisodePredictor", "MonteCarloPrediction"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    v, visits, states, rewards, length = tables[3], tables[2], tables[4], tables[5], tables[6]
    steps = length[0] + 1
    states[steps - 1] = s
    rewards[steps - 1] = r
    length[0] = steps
    log[0, 4] = 0.0  # nothing learned yet
    if not (terminated or truncated):
        return 0.0
    g = 0.0 if terminated else v[s2]
    total = 0.0
    for t in range(steps - 1, -1, -1):
        g = rewards[t] + hp.discount * g
        total += v_update(v, visits, hp, states[t], g, log, steps - 1 - t)
    length[0] = 0
    return total


class EpisodePredictor(Predictor):
    """A predictor that keeps each episode's states and rewards until its end (`restart`
    and `filled`, tables 4 to 6)."""

    extras = (*Predictor.extras, Extra("_states", "episode", np.int64),
              Extra("_rewards", "episode"), Extra("_length", 1, np.int64))
    _length: np.ndarray

    def log_rows(self) -> int:
        return int(self._length[0]) + 1


class MonteCarloPrediction(EpisodePredictor):
    """Constant-α MC: V of the policy followed, from each episode's returns at its end."""

    name = "mc-prediction"
    title = "Constant-α MC"
    summary = "prediction: V of a fixed policy, toward whole-episode returns at their end"
    formula = "G = r + γ·G'"
    rule = Rule(update, begin=restart, full=filled)
