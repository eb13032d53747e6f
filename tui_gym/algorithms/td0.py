"""TD(0) prediction (Sutton & Barto, 2nd ed., section 6.1): V of a fixed policy."""

from __future__ import annotations

from typing import Any

from tui_gym.algorithms.prediction import Predictor, v_update
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.rules import Rule

__all__ = ["TD0"]


@kernel
def update(tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int, r: float, s2: int,
           terminated: bool, truncated: bool, a2: int, epsilon: float, log: Any) -> float:
    v, visits = tables[3], tables[2]
    future = 0.0 if terminated else v[s2]
    return v_update(v, visits, hp, s, r + hp.discount * future, log, 0)


class TD0(Predictor):
    """TD(0): V of the policy followed, bootstrapping from the next state each step."""

    name = "td0"
    title = "TD(0)"
    summary = "prediction: V of a fixed policy, each step toward r + γ·V(s')"
    formula = "r + γ·V(s')"
    rule = Rule(update)
