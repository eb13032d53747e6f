"""How far a policy is from the optimum: `exact_gap` and the `Gap` it returns, `gap_of`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy.typing as npt

from tui_gym.core.mdp.evaluation import evaluate
from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.core.mdp.optimum import Solution, solve

__all__ = ["ROUND_OFF", "Gap", "exact_gap", "gap_of"]


@dataclass(frozen=True)
class Gap:
    """A policy's exact value beside the optimum.

    `gap = optimal_value - exact_value`, at least 0: plus infinity for a
    policy that never ends against an optimum that does, 0 when both are the
    same infinity. `never_ends`: see `PolicyValue.never_ends`.
    """

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
    model: FiniteMDP, policy: npt.ArrayLike, gamma: float = 1.0, optimum: Solution | None = None,
) -> Gap:
    """The exact value of `policy`, the optimum, and the gap between them.

    Pass `optimum` (from `solve(model, gamma)`) to reuse it across calls; it
    must be for the same gamma and for the start of an episode.
    """
    if optimum is None:
        optimum = solve(model, gamma)
    elif optimum.gamma != float(gamma) or optimum.steps_left != model.horizon:
        raise ValueError(
            f"the optimum given is for gamma={optimum.gamma}, {optimum.steps_left} steps left; "
            f"this needs gamma={gamma}, {model.horizon} steps left"
        )
    value = evaluate(model, policy, gamma)
    return Gap(
        exact_value=value.value, optimal_value=optimum.value,
        gap=gap_of(optimum.value, value.value), never_ends=value.never_ends,
    )
