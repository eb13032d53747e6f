"""Figure 8.4: Dyna-Q against Dyna-Q+ on the blocking maze, cumulative reward over time steps."""

from __future__ import annotations

import numpy as np

from tui_gym.session.book.changing_mazes import (
    NOTE,
    fewest_steps,
    found_after,
    play_maze,
    reward_between,
)
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
)
from tui_gym.session.book.runs import above, per_step

STEPS = 3000  # the figure's time steps
CHANGE = 1000  # the wall moves after this many
GLANCE = 100  # steps on each side of the change that show the curves go flat
LATE = 500  # the last steps, where the curves have risen again


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    dyna, plus = play_maze(FIGURE, "blocking-maze", options, progress, STEPS, CHANGE)
    before, after = fewest_steps("blocking-maze", CHANGE)
    flat = [above(f"{p.label}'s curve goes flat at the change: reward in the {GLANCE} steps "
                  f"before it against the {GLANCE} after", "flat after the change",
                  reward_between(p, CHANGE - GLANCE, CHANGE),
                  reward_between(p, CHANGE, CHANGE + GLANCE)) for p in (dyna, plus)]
    rises = [above(f"{p.label} finds the new way after a while: reward per {GLANCE} steps "
                   f"over the last {LATE} against the {GLANCE} after the change",
                   "the curve rises again",
                   reward_between(p, STEPS - LATE, STEPS) * GLANCE / LATE,
                   reward_between(p, CHANGE, CHANGE + GLANCE)) for p in (dyna, plus)]
    found_dyna, found_plus = found_after(dyna, CHANGE), found_after(plus, CHANGE)
    checks = (
        Check("the short way round the wall's right end takes 10 steps; after the change, "
              "the way round its left end 16", "10, then 16", f"{before}, then {after}",
              (before, after) == (10, 16)),
        *flat,
        *rises,
        above("Dyna-Q+ finds the new way sooner: time steps from the change until an episode "
              "begun after it reaches the goal (Dyna-Q against Dyna-Q+)", "sooner",
              found_dyna, found_plus, digits=0),
        above(f"Dyna-Q+'s cumulative reward after {STEPS} steps is above Dyna-Q's",
              "above", plus.values[:, -1], dyna.values[:, -1]),
    )
    stuck = int((found_dyna >= STEPS - CHANGE).sum())
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=dyna.runs,
        charts=(Chart("cumulative reward", "time steps", (per_step(dyna), per_step(plus))),),
        checks=checks,
        notes=(NOTE,
               f"the wall moves after {CHANGE} steps; the maze pays +1 at the goal only, so "
               "the cumulative reward counts the episodes that reached it",
               f"Dyna-Q had not found the new way by step {STEPS} in {stuck} of {dyna.runs} "
               f"runs (counted as {STEPS - CHANGE} steps); Dyna-Q+ took "
               f"{float(np.median(found_plus)):.0f} steps (median)",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="8.4",
    title="Dyna-Q against Dyna-Q+ on the blocking maze (Figure 8.4): cumulative reward",
    about="After 1000 steps the short way round the wall closes and a longer one opens at "
          "its other end. Both agents' curves go flat while they search behind the wall; "
          "Dyna-Q+, whose planning rewards trying what it has not tried for long, finds "
          "the new way sooner and ends ahead.",
    world="blocking-maze",
    run=run,
    runs=30,
    episodes=None,
    aliases=("example 8.2",),
)
