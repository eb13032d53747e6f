"""Figure 3.5: the optimal state values and policy on Example 3.5's grid (γ = 0.9)."""

from __future__ import annotations

import numpy as np

from tui_gym.session.book.dp import EXACT_NOTE, grid_check, number_grid, planner_on, value_check
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
)
from tui_gym.session.plan.panels import plan_panels

BOOK = np.array([
    [22.0, 24.4, 22.0, 19.4, 17.5], [19.8, 22.0, 19.8, 17.8, 16.0], [17.8, 19.8, 17.8, 16.0, 14.4],
    [16.0, 17.8, 16.0, 14.4, 13.0], [14.4, 16.0, 14.4, 13.0, 11.7],
])
UP, LEFT, RIGHT = 0, 2, 3


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    from tui_gym.games import game_named

    progress(0, 1, "value iteration")
    plan, planner = planner_on("ab-grid", 0.9, 1e-12)
    planner.run("value-iteration")
    v = planner.v.reshape(5, 5)
    progress(1, 1, f"converged in {planner.sweeps} sweeps")
    # From the bottom row every optimal move goes up, or along the row towards A's column.
    toward = np.zeros((5, 4), dtype=bool)
    toward[:, UP] = True
    toward[2:, LEFT] = toward[:1, RIGHT] = True
    bottom = planner.policy.reshape(5, 5, 4)[4] > 0
    heads = bool((bottom <= toward).all())
    checks = (
        value_check("V*(A): +10 and on from A′, five moves from A again", 24.4, v[0, 1]),
        value_check("V*(B)", 19.4, v[0, 3]),
        Check("every optimal move from the bottom row heads for A: up, or along the row to "
              "its column", "towards A", "towards A" if heads else "not", heads),
        grid_check("every value of the figure", BOOK, v),
    )
    game = game_named("ab-grid")
    arrows = plan_panels(game, {}, plan, planner.v, planner.policy,
                         np.zeros(plan.model.n_states, dtype=bool))
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=1,
        charts=(Chart("optimal state values", "state (row * 5 + col)",
                      (Series("v*", np.arange(25.0), planner.v.copy()),)),),
        panels=(number_grid("v*, the optimal state values (γ = 0.9)", v), *arrows),
        checks=checks,
        notes=(f"value iteration, {planner.sweeps} sweeps to a largest change below 1e-12",
               EXACT_NOTE),
    )


FIGURE = BookFigure(
    name="3.5",
    title="Gridworld (Example 3.5): the optimal state values and policies",
    about="Solved: every optimal policy runs to A and takes its +10, from B′ too; the "
          "values fall by a factor 0.9 a move away from A.",
    world="ab-grid",
    run=run,
)
