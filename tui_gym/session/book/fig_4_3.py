"""Figure 4.3: value iteration on the gambler's problem (Example 4.3, p_h = 0.4)."""

from __future__ import annotations

from tui_gym.core.mdp.planning import greedy
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

THETA = 1e-9
TIES = 1e-9  # stakes whose values are this close count as equally good
SHOWN = (1, 2, 3)


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    plan, planner = planner_on("gambler", 1.0, THETA)
    line = plan.line
    assert line is not None
    capital = line.x
    series = []
    while not planner.done("value-iteration"):
        planner.value_sweep()
        if planner.sweeps in SHOWN:
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
        figure=FIGURE.name, title=FIGURE.title, runs=1,
        charts=(Chart("value estimates by sweep", "capital", tuple(series)),
                Chart("final policy (stake)", "capital", (Series("stake", capital, stakes),))),
        checks=checks,
        notes=(f"value iteration to a largest change below {THETA:g}",
               f"many policies are optimal: the stakes drawn are the smallest of those within "
               f"{TIES:g} of the best at each capital, the tie-breaking the book's figure shows "
               "(Exercise 4.8)", EXACT_NOTE),
    )


FIGURE = BookFigure(
    name="4.3",
    title="The gambler's problem (Example 4.3, p_h = 0.4): value iteration",
    about="The chance of reaching $100 from each capital, sweep by sweep, and the final "
          "stakes: bold play at 25, 50 and 75, and one of many optimal policies between.",
    world="gambler",
    run=run,
    aliases=("example 4.3",),
)
