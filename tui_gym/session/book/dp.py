"""The dynamic-programming figures (Chapters 3 and 4), exact on each game's model: the
gridworlds' values (3.2, 3.5, 4.1), Jack's car rental (4.2) and the gambler (4.3)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import optimal_actions, solve
from tui_gym.core.mdp.planning import Planner, greedy
from tui_gym.envs.car_rental import MOVES, SIDE
from tui_gym.games import game_named
from tui_gym.games.planning import PlanModel
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
    book_figure,
)
from tui_gym.session.plan.panels import number_text, plan_panels

__all__ = ["FIGURES", "grid_check", "number_grid", "planner_on", "value_check"]

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


# --- Figures 3.2 and 3.5: Example 3.5's grid, γ = 0.9 -------------------------------------

RANDOM_VALUES = np.array([
    [3.3, 8.8, 4.4, 5.3, 1.5], [1.5, 3.0, 2.3, 1.9, 0.5], [0.1, 0.7, 0.7, 0.4, -0.4],
    [-1.0, -0.4, -0.4, -0.6, -1.2], [-1.9, -1.3, -1.2, -1.4, -2.0],
])
OPTIMAL_VALUES = np.array([
    [22.0, 24.4, 22.0, 19.4, 17.5], [19.8, 22.0, 19.8, 17.8, 16.0], [17.8, 19.8, 17.8, 16.0, 14.4],
    [16.0, 17.8, 16.0, 14.4, 13.0], [14.4, 16.0, 14.4, 13.0, 11.7],
])
UP, LEFT, RIGHT = 0, 2, 3


def _ab_grid(method: str, what: str, progress: Progress) -> tuple[PlanModel, Planner, np.ndarray]:
    """Example 3.5's grid solved by `method` (told as `what`) to a largest change below 1e-12."""
    progress(0, 1, what)
    plan, planner = planner_on("ab-grid", 0.9, 1e-12)
    planner.run(method)
    progress(1, 1, f"converged in {planner.sweeps} sweeps")
    return plan, planner, planner.v.reshape(5, 5)


@book_figure(
    "3.2", "ab-grid", aliases=("example 3.5",),
    title="Gridworld (Example 3.5): the equiprobable random policy's state values",
    about="The grid of Example 3.5 under the random policy, discounted by 0.9: A's value "
          "is below its reward of 10, because A′ sits by the edge where the random policy "
          "often bumps, and B's above its 5.")
def fig_3_2(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    _, planner, v = _ab_grid("evaluate", "evaluating the random policy", progress)
    checks = (
        value_check("V(A): below its +10, for A′ lies by the edge, where moves cost", 8.8, v[0, 1]),
        value_check("V(B): above its +5, for B′ is central", 5.3, v[0, 3]),
        Check("the values near the lower edge are negative: moves off the grid cost 1",
              "negative", round(float(v[4].max()), 3), bool((v[4] < 0).all())),
        grid_check("every value of the figure", RANDOM_VALUES, v),
    )
    return FigureResult(
        charts=(Chart("state values of the random policy", "state (row * 5 + col)",
                      (Series("v_random", np.arange(25.0), planner.v.copy()),)),),
        panels=(number_grid("state values of the random policy (γ = 0.9)", v,
                            "A is row 0, col 1; B row 0, col 3"),),
        checks=checks,
        notes=(f"iterative policy evaluation, {planner.sweeps} synchronous sweeps to a "
               "largest change below 1e-12", EXACT_NOTE),
    )


@book_figure(
    "3.5", "ab-grid",
    title="Gridworld (Example 3.5): the optimal state values and policies",
    about="Solved: every optimal policy runs to A and takes its +10, from B′ too; the "
          "values fall by a factor 0.9 a move away from A.")
def fig_3_5(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    plan, planner, v = _ab_grid("value-iteration", "value iteration", progress)
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
        grid_check("every value of the figure", OPTIMAL_VALUES, v),
    )
    arrows = plan_panels(game_named("ab-grid"), {}, plan, planner.v, planner.policy,
                         np.zeros(plan.model.n_states, dtype=bool))
    return FigureResult(
        charts=(Chart("optimal state values", "state (row * 5 + col)",
                      (Series("v*", np.arange(25.0), planner.v.copy()),)),),
        panels=(number_grid("v*, the optimal state values (γ = 0.9)", v), *arrows),
        checks=checks,
        notes=(f"value iteration, {planner.sweeps} sweeps to a largest change below 1e-12",
               EXACT_NOTE),
    )


# --- Figure 4.1: Example 4.1's grid, the random policy sweep by sweep ----------------------

THETA = 1e-4  # Figures 4.1 and 4.2
SHOWN = (1, 2, 3, 10)  # the sweeps the figure shows, before the converged values
SWEPT_VALUES = {
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


@book_figure(
    "4.1", "corner-grid", aliases=("example 4.1",),
    title="Iterative policy evaluation on the small gridworld (Example 4.1)",
    about="The random policy's values after 1, 2, 3 and 10 sweeps and at convergence, each "
          "with the greedy policy it suggests (already optimal after three sweeps); in place, "
          "the evaluation takes fewer sweeps than with two arrays.")
def fig_4_1(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
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
        checks.append(grid_check(f"the values after {k} sweep{'s' * (k > 1)}", SWEPT_VALUES[k],
                                 v.reshape(4, 4)))
        if k == 3:
            best = greedy(plan.model, v, 1.0, 1e-9)
            panels.extend(plan_panels(game_named("corner-grid"), {}, plan, v,
                                      best / best.sum(axis=1, keepdims=True),
                                      np.zeros(16, dtype=bool)))
            checks.append(Check("the greedy policy on v_3 is already optimal",
                                "optimal", "optimal" if (best <= optimal).all() else "not",
                                bool((best <= optimal).all())))
    planner.run("evaluate")
    progress(total, total, f"converged in {planner.sweeps} sweeps")
    final = planner.v.reshape(4, 4)
    series.append(Series("v_random", np.arange(16.0), planner.v.copy()))
    panels.append(number_grid(f"v_random: converged (largest change below {THETA:g})", final,
                              blank=CORNERS))
    checks.append(grid_check("the random policy's values", SWEPT_VALUES[0], final))
    _, in_place = planner_on("corner-grid", 1.0, THETA, in_place=True)
    in_place.run("evaluate")
    checks.append(Check(f"in-place evaluation converges in fewer sweeps (θ = {THETA:g})",
                        "fewer", f"{in_place.sweeps} in place, {planner.sweeps} synchronous",
                        in_place.sweeps < planner.sweeps))
    return FigureResult(
        charts=(Chart("the random policy's values, sweep by sweep", "state (row * 4 + col)",
                      tuple(series)),),
        panels=tuple(panels), checks=tuple(checks),
        notes=("synchronous sweeps from values 0; the book prints −1.75 as −1.7", EXACT_NOTE),
    )


# --- Figure 4.2: policy iteration on Jack's car rental -------------------------------------

NOTHING = MOVES.index(0)
ROUNDS = 5  # the book's π0 to π4, and the check that π4 is stable


def _moves(policy: np.ndarray) -> np.ndarray:
    """`[S]`: the cars a policy moves, the fewest where it takes several equal moves."""
    return np.array([min((MOVES[a] for a in np.flatnonzero(row > 0)), key=abs)
                     for row in policy], dtype=np.float64)


@book_figure(
    "4.2", "car-rental", aliases=("example 4.2",),
    title="Jack's car rental (Example 4.2): the policies found by policy iteration",
    about="From moving nothing, four improvements reach the optimal policy: move cars to "
          "the second site, whose requests outrun its returns, unless it is the fuller one.")
def fig_4_2(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
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
    layout, panels, series = game_named("car-rental").layout, [], []
    for k, policy in enumerate(policies):
        panel = layout.heatmaps(np.where(policy > 0, 1.0, 0.0), {})[0]
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
        charts=(Chart("cars moved by each policy", "state (first * 21 + second)",
                      tuple(series[:-1])),
                Chart("v_π4", "state (first * 21 + second)", (series[-1],))),
        panels=tuple(panels), checks=checks,
        notes=(f"policy iteration from π0 (move nothing), evaluation to θ = {THETA:g} from the "
               f"last values, {planner.sweeps} sweeps in all",
               f"the book's plot of v_π4 tops out near 612; exactly it reaches "
               f"{grid.max():.1f} at 20 cars at each site", EXACT_NOTE),
    )


# --- Figure 4.3: value iteration on the gambler's problem ----------------------------------

GAMBLER_THETA = 1e-9
TIES = 1e-9  # stakes whose values are this close count as equally good
GAMBLER_SHOWN = (1, 2, 3)


@book_figure(
    "4.3", "gambler", aliases=("example 4.3",),
    title="The gambler's problem (Example 4.3, p_h = 0.4): value iteration",
    about="The chance of reaching $100 from each capital, sweep by sweep, and the final "
          "stakes: bold play at 25, 50 and 75, and one of many optimal policies between.")
def fig_4_3(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    plan, planner = planner_on("gambler", 1.0, GAMBLER_THETA)
    line = plan.line
    assert line is not None
    capital = line.x
    series = []
    while not planner.done("value-iteration"):
        planner.value_sweep()
        if planner.sweeps in GAMBLER_SHOWN:
            series.append(Series(f"sweep {planner.sweeps}", capital, planner.v[line.states].copy()))
        progress(min(planner.sweeps, 32), 32, f"sweep {planner.sweeps}")
    progress(planner.sweeps, planner.sweeps, f"converged in {planner.sweeps} sweeps")
    v = planner.v
    series.append(Series(f"sweep {planner.sweeps} (final)", capital, v[line.states].copy()))
    best = greedy(plan.model, v, 1.0, TIES)
    stakes = line.policy_numbers(best / best.sum(axis=1, keepdims=True))
    stake = dict(zip(capital.astype(int).tolist(), stakes.tolist(), strict=True))
    rising = all(bool((a.y <= b.y + 1e-12).all()) for a, b in zip(series, series[1:], strict=False))
    checks = (
        Check("V(50) = p_h: bet everything once", 0.4, round(float(v[50]), 6),
              abs(v[50] - 0.4) < 1e-6),
        Check("V(25) = p_h², V(75) = p_h + (1 − p_h) p_h", "0.16, 0.64",
              f"{v[25]:.6f}, {v[75]:.6f}", abs(v[25] - 0.16) < 1e-6 and abs(v[75] - 0.64) < 1e-6),
        Check("the final policy stakes everything at 50", 50, int(stake[50]), stake[50] == 50),
        Check("it stakes 25 at 25 and at 75", "25, 25", f"{stake[25]:g}, {stake[75]:g}",
              stake[25] == stake[75] == 25),
        Check("the values rise sweep by sweep towards the final ones", "rising",
              "rising" if rising else "not", rising),
    )
    return FigureResult(
        charts=(Chart("value estimates by sweep", "capital", tuple(series)),
                Chart("final policy (stake)", "capital", (Series("stake", capital, stakes),))),
        checks=checks,
        notes=(f"value iteration to a largest change below {GAMBLER_THETA:g}",
               f"many policies are optimal: the stakes drawn are the smallest of those within "
               f"{TIES:g} of the best at each capital, the tie-breaking the book's figure shows "
               "(Exercise 4.8)", EXACT_NOTE),
    )


FIGURES = (fig_3_2, fig_3_5, fig_4_1, fig_4_2, fig_4_3)
