"""Figure 4.1: iterative policy evaluation of the random policy on Example 4.1's grid."""

from __future__ import annotations

import numpy as np

from tui_gym.core.mdp import optimal_actions, solve
from tui_gym.core.mdp.planning import greedy
from tui_gym.games import game_named
from tui_gym.session.book.dp import EXACT_NOTE, grid_check, number_grid, planner_on
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

THETA = 1e-4
SHOWN = (1, 2, 3, 10)  # the sweeps the figure shows, before the converged values
BOOK = {
    1: [[0.0, -1.0, -1.0, -1.0], [-1.0, -1.0, -1.0, -1.0], [-1.0, -1.0, -1.0, -1.0],
        [-1.0, -1.0, -1.0, 0.0]],
    2: [[0.0, -1.7, -2.0, -2.0], [-1.7, -2.0, -2.0, -2.0], [-2.0, -2.0, -2.0, -1.7],
        [-2.0, -2.0, -1.7, 0.0]],
    3: [[0.0, -2.4, -2.9, -3.0], [-2.4, -2.9, -3.0, -2.9], [-2.9, -3.0, -2.9, -2.4],
        [-3.0, -2.9, -2.4, 0.0]],
    10: [[0.0, -6.1, -8.4, -9.0], [-6.1, -7.7, -8.4, -8.4], [-8.4, -8.4, -7.7, -6.1],
         [-9.0, -8.4, -6.1, 0.0]],
    0: [[0.0, -14.0, -20.0, -22.0], [-14.0, -18.0, -20.0, -20.0],
        [-20.0, -20.0, -18.0, -14.0], [-22.0, -20.0, -14.0, 0.0]],  # 0: converged
}
CORNERS = np.zeros((4, 4), dtype=bool)
CORNERS[0, 0] = CORNERS[3, 3] = True


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    game = game_named("corner-grid")
    plan, planner = planner_on("corner-grid", 1.0, THETA)
    optimal = optimal_actions(solve(plan.model).q)
    panels, series, checks = [], [], []
    total = max(SHOWN) + 1
    for k in SHOWN:
        while planner.sweeps < k:
            planner.evaluation_sweep()
        progress(k, total, f"sweep {k}")
        v = planner.v.copy()
        series.append(Series(f"v_{k}", np.arange(16.0), v))
        panels.append(number_grid(f"v_{k}: after {k} sweep{'s' * (k > 1)}", v.reshape(4, 4),
                                  blank=CORNERS))
        checks.append(grid_check(f"the values after {k} sweep{'s' * (k > 1)}", BOOK[k],
                                 v.reshape(4, 4)))
        if k == 3:
            best = greedy(plan.model, v, 1.0, 1e-9)
            gready = plan_panels(game, {}, plan, v, best / best.sum(axis=1, keepdims=True),
                                 np.zeros(16, dtype=bool))
            panels.extend(gready)
            checks.append(Check("the greedy policy on v_3 is already optimal",
                                "optimal", "optimal" if (best <= optimal).all() else "not",
                                bool((best <= optimal).all())))
    planner.run("evaluate")
    progress(total, total, f"converged in {planner.sweeps} sweeps")
    final = planner.v.reshape(4, 4)
    series.append(Series("v_random", np.arange(16.0), planner.v.copy()))
    panels.append(number_grid(f"v_random: converged (largest change below {THETA:g})", final,
                              blank=CORNERS))
    checks.append(grid_check("the random policy's values", BOOK[0], final))
    _, in_place = planner_on("corner-grid", 1.0, THETA, in_place=True)
    in_place.run("evaluate")
    checks.append(Check(f"in-place evaluation converges in fewer sweeps (θ = {THETA:g})",
                        "fewer", f"{in_place.sweeps} in place, {planner.sweeps} synchronous",
                        in_place.sweeps < planner.sweeps))
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=1,
        charts=(Chart("the random policy's values, sweep by sweep", "state (row * 4 + col)",
                      tuple(series)),),
        panels=tuple(panels), checks=tuple(checks),
        notes=("synchronous sweeps from values 0; the book prints −1.75 as −1.7", EXACT_NOTE),
    )


FIGURE = BookFigure(
    name="4.1",
    title="Iterative policy evaluation on the small gridworld (Example 4.1)",
    about="The random policy's values after 1, 2, 3 and 10 sweeps and at convergence, each "
          "with the greedy policy it suggests (already optimal after three sweeps); in place, "
          "the evaluation takes fewer sweeps than with two arrays.",
    world="corner-grid",
    run=run,
    aliases=("example 4.1",),
)
