"""A plan drawn as the game's heatmaps draw a Q-table: each state's value and its actions."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap
from tui_gym.games import Game
from tui_gym.games.planning import PlanModel

__all__ = ["number_text", "numbered", "plan_panels"]

_NOT_OPTIMAL = re.compile(r"not (?:an )?optimal(?: move| stake)?")
_TITLE = re.compile(r"max Q|Q-value")
_ABOUT_ACTIONS = re.compile(r"arrow|number|greedy|tie|\*|jumps")
_GREEDY = re.compile(r"\bthe greedy\b|\bgreedy\b")


def number_text(value: float, largest: float) -> str:
    """A value in a cell of a panel whose largest magnitude is `largest`: as the book
    prints them, one decimal (none from 100; two while every value is below one)."""
    if largest >= 99.95:
        return f"{value:.0f}"
    return f"{value:.1f}" if largest >= 0.995 else f"{value:.2f}"


def numbered(panel: Heatmap) -> Heatmap:
    """The panel with each cell that has a value showing it (`number_text`)."""
    finite = np.abs(panel.values[np.isfinite(panel.values)])
    largest = float(finite.max()) if finite.size else 0.0
    labels = tuple(
        tuple(number_text(float(value), largest) if np.isfinite(value) else label
              for value, label in zip(row, line, strict=True))
        for row, line in zip(panel.values, panel.labels, strict=True)
    )
    kept = [part.strip() for part in panel.legend.split("  ")
            if part.strip() and not _ABOUT_ACTIONS.search(part)]
    return replace(panel, labels=labels, title="values",
                   legend="  ".join(["number: the value", *kept]))


def plan_panels(
    game: Game, kwargs: Mapping[str, Any], plan: PlanModel, v: npt.ArrayLike, policy: npt.ArrayLike,
    changed: npt.ArrayLike, focus: Any = None, numbers: bool = False,
) -> list[Heatmap]:
    """The game's heatmap panels of the plan, the changed states marked."""
    # A table the heatmaps draw: the value where the policy acts, something lower elsewhere.
    values = plan.base_values(np.asarray(v, dtype=np.float64))[:, None]
    taken = plan.base_rows(np.asarray(policy)) > 0
    with np.errstate(invalid="ignore"):
        q = np.where(taken, values, values - np.maximum(1.0, np.abs(values)))
    moved = np.asarray(plan.base_rows(np.asarray(changed)), dtype=bool)
    marks = np.broadcast_to(~moved[:, None], q.shape)
    panels = game.layout.heatmaps(q, kwargs, focus, marks)
    if numbers:
        panels = [numbered(panel) for panel in panels]
    return [replace(panel, title=_GREEDY.sub("the policy's", _TITLE.sub("value", panel.title)),
                    legend=_GREEDY.sub("the policy's", _NOT_OPTIMAL.sub(
                        "changed by the last step", panel.legend)))
            for panel in panels]
