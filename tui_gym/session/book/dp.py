"""What the dynamic-programming figures share: their grids of values and their checks."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp.planning import Planner
from tui_gym.games import game_named
from tui_gym.games.planning import PlanModel
from tui_gym.session.book.figure import Check
from tui_gym.session.plan.panels import number_text

__all__ = ["EXACT_NOTE", "grid_check", "number_grid", "planner_on", "value_check"]

PRINTED = 0.05 + 1e-9  # a value printed to one decimal is within this of the exact one
EXACT_NOTE = "exact (dynamic programming on the model): runs, episodes and seeds do not apply"


def number_grid(title: str, values: npt.ArrayLike, legend: str = "",
                blank: npt.ArrayLike | None = None) -> Heatmap:
    """A grid of values as a panel: rows and columns numbered from 0, each cell's value
    written in it (`blank` cells, e.g. terminal ones, show `·`)."""
    grid = np.asarray(values, dtype=np.float64)
    rows, cols = grid.shape
    empty = np.zeros(grid.shape, dtype=bool) if blank is None else np.asarray(blank, bool)
    largest = float(np.abs(grid).max(initial=0.0))
    labels = tuple(tuple("·" if empty[r, c] else number_text(float(grid[r, c]), largest)
                         for c in range(cols)) for r in range(rows))
    return Heatmap(title=title, row_labels=tuple(str(r) for r in range(rows)),
                   col_labels=tuple(str(c) for c in range(cols)), values=grid,
                   labels=labels, marked=np.zeros(grid.shape, dtype=bool), legend=legend)


def value_check(claim: str, book: float, measured: float) -> Check:
    """A value the book prints to one decimal, beside the exact one (rounded to 3)."""
    return Check(claim, book, round(float(measured), 3), abs(measured - book) <= PRINTED)


def grid_check(claim: str, book: npt.ArrayLike, measured: npt.ArrayLike) -> Check:
    """Every value of a grid the book prints to one decimal: the largest difference."""
    worst = float(np.max(np.abs(np.asarray(measured) - np.asarray(book))))
    return Check(claim, "as printed, to one decimal", f"largest difference {worst:.3f}",
                 worst <= PRINTED)


def planner_on(world: str, gamma: float, theta: float, **options: object) -> tuple[
        PlanModel, Planner]:
    """A game's plan model and a planner on it (the random policy, values 0)."""
    plan = game_named(world).plan_model({})
    if not isinstance(plan, PlanModel):
        raise ValueError(f"{world} has no model to plan on")
    return plan, Planner(plan.model, gamma=gamma, theta=theta, **options)  # type: ignore[arg-type]
