"""Figure 3.2: the equiprobable random policy's values on Example 3.5's grid (γ = 0.9)."""

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

BOOK = np.array([
    [3.3, 8.8, 4.4, 5.3, 1.5], [1.5, 3.0, 2.3, 1.9, 0.5], [0.1, 0.7, 0.7, 0.4, -0.4],
    [-1.0, -0.4, -0.4, -0.6, -1.2], [-1.9, -1.3, -1.2, -1.4, -2.0],
])


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    progress(0, 1, "evaluating the random policy")
    _, planner = planner_on("ab-grid", 0.9, 1e-12)
    planner.run("evaluate")
    v = planner.v.reshape(5, 5)
    progress(1, 1, f"converged in {planner.sweeps} sweeps")
    checks = (
        value_check("V(A): below its +10, for A′ lies by the edge, where moves cost", 8.8, v[0, 1]),
        value_check("V(B): above its +5, for B′ is central", 5.3, v[0, 3]),
        Check("the values near the lower edge are negative: moves off the grid cost 1",
              "negative", round(float(v[4].max()), 3), bool((v[4] < 0).all())),
        grid_check("every value of the figure", BOOK, v),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=1,
        charts=(Chart("state values of the random policy", "state (row * 5 + col)",
                      (Series("v_random", np.arange(25.0), planner.v.copy()),)),),
        panels=(number_grid("state values of the random policy (γ = 0.9)", v,
                            "A is row 0, col 1; B row 0, col 3"),),
        checks=checks,
        notes=(f"iterative policy evaluation, {planner.sweeps} synchronous sweeps to a "
               "largest change below 1e-12", EXACT_NOTE),
    )


FIGURE = BookFigure(
    name="3.2",
    title="Gridworld (Example 3.5): the equiprobable random policy's state values",
    about="The grid of Example 3.5 under the random policy, discounted by 0.9: A's value "
          "is below its reward of 10, because A′ sits by the edge where the random policy "
          "often bumps, and B's above its 5.",
    world="ab-grid",
    run=run,
    aliases=("example 3.5",),
)
