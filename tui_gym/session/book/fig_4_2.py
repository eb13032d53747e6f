"""Figure 4.2: policy iteration on Jack's car rental (Example 4.2): π0 … π4 and v_π4."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tui_gym.envs.car_rental import MOVES, SIDE
from tui_gym.games import game_named
from tui_gym.session.book.dp import EXACT_NOTE, planner_on
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
)

THETA = 1e-4
NOTHING = MOVES.index(0)
ROUNDS = 5  # the book's π0 to π4, and the check that π4 is stable


def _moves(policy: np.ndarray) -> np.ndarray:
    """`[S]`: the cars a policy moves, the fewest where it takes several equal moves."""
    return np.array([min((MOVES[a] for a in np.flatnonzero(row > 0)), key=abs)
                     for row in policy], dtype=np.float64)


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    game = game_named("car-rental")
    plan, planner = planner_on("car-rental", 0.9, THETA)
    start = np.zeros((plan.model.n_states, len(MOVES)))
    start[:, NOTHING] = 1.0
    planner.restart(start)
    policies = [planner.policy.copy()]
    progress(0, ROUNDS, "π0: move nothing")
    while not planner.stable:
        while planner.delta >= planner.theta:
            planner.evaluation_sweep()
        if not planner.improvement().stable:
            policies.append(planner.policy.copy())
        progress(min(len(policies), ROUNDS), ROUNDS, f"π{len(policies) - 1}")
    v = planner.v.copy()
    layout, panels, series = game.layout, [], []
    for k, policy in enumerate(policies):
        q = np.where(policy > 0, 1.0, 0.0)
        panel = layout.heatmaps(q, {})[0]
        panels.append(replace(panel, title=f"π{k}: cars moved"))
        series.append(Series(f"π{k}", np.arange(float(SIDE * SIDE)), _moves(policy)))
    assert plan.value_panel is not None
    panels.append(plan.value_panel(v))
    series.append(Series(f"v_π{len(policies) - 1}", np.arange(float(SIDE * SIDE)), v))
    last = _moves(policies[-1]).reshape(SIDE, SIDE)
    grid = v.reshape(SIDE, SIDE)
    checks = (
        Check("policy iteration ends after four improvements: π4 is stable", 4,
              planner.iterations, planner.iterations == 4),
        Check("π4 moves five cars to the second site when the first has 20 and it none", 5,
              int(last[20, 0]), int(last[20, 0]) == 5),
        Check("π4 moves cars back when the first site has none and the second 20", "< 0",
              int(last[0, 20]), last[0, 20] < 0),
        Check("v_π4 is lowest with no cars at either site, about 420", 420,
              round(float(grid[0, 0]), 1),
              abs(grid[0, 0] - 420) <= 5 and grid[0, 0] == grid.min()),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=1,
        charts=(Chart("cars moved by each policy", "state (first * 21 + second)",
                      tuple(series[:-1])),
                Chart("v_π4", "state (first * 21 + second)", (series[-1],))),
        panels=tuple(panels), checks=checks,
        notes=(f"policy iteration from π0 (move nothing), evaluation to θ = {THETA:g} from the "
               f"last values, {planner.sweeps} sweeps in all",
               f"the book's plot of v_π4 tops out near 612; exactly it reaches "
               f"{grid.max():.1f} at 20 cars at each site", EXACT_NOTE),
    )


FIGURE = BookFigure(
    name="4.2",
    title="Jack's car rental (Example 4.2): the policies found by policy iteration",
    about="From moving nothing, four improvements reach the optimal policy: move cars to "
          "the second site, whose requests outrun its returns, unless it is the fuller one.",
    world="car-rental",
    run=run,
    aliases=("example 4.2",),
)
