"""Figure 8.5: Dyna-Q against Dyna-Q+ on the shortcut maze, cumulative reward over time steps."""

from __future__ import annotations

from tui_gym.session.book.changing_mazes import (
    NOTE,
    episodes_after,
    fewest_steps,
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
from tui_gym.session.book.runs import above, near, per_step

STEPS = 6000  # the figure's time steps
CHANGE = 3000  # the shortcut opens after this many
LATE = 1500  # the last steps: each agent's way after the change


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    dyna, plus = play_maze(FIGURE, "shortcut-maze", options, progress, STEPS, CHANGE)
    long_way, shortcut = fewest_steps("shortcut-maze", CHANGE)
    # An episode shorter than the long way's fewest steps went through the shortcut.
    through = [[100.0 * (lengths < long_way).mean() if lengths.size else 0.0
                for lengths in episodes_after(p, STEPS - LATE)] for p in (dyna, plus)]
    checks = (
        Check("the long way round the wall's left end takes 16 steps; the shortcut, 10",
              "16, then 10", f"{long_way}, then {shortcut}", (long_way, shortcut) == (16, 10)),
        near(f"Dyna-Q never finds the shortcut: % of its episodes in the last {LATE} steps "
             f"shorter than the long way's {long_way}", 0.0, through[0], unit="%"),
        above(f"Dyna-Q+ finds it: % of its episodes in the last {LATE} steps through the "
              "shortcut, against Dyna-Q's", "Dyna-Q+ takes it", through[1], through[0],
              unit="%"),
        above(f"after the change Dyna-Q+'s curve is steeper: reward over the last {LATE} "
              "steps", "steeper", reward_between(plus, STEPS - LATE, STEPS),
              reward_between(dyna, STEPS - LATE, STEPS)),
        above(f"Dyna-Q+'s cumulative reward after {STEPS} steps is above Dyna-Q's",
              "above", plus.values[:, -1], dyna.values[:, -1]),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=dyna.runs,
        charts=(Chart("cumulative reward", "time steps", (per_step(dyna), per_step(plus))),),
        checks=checks,
        notes=(NOTE,
               f"the shortcut opens after {CHANGE} steps; the maze pays +1 at the goal only, "
               "so the cumulative reward counts the episodes that reached it",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="8.5",
    title="Dyna-Q against Dyna-Q+ on the shortcut maze (Figure 8.5): cumulative reward",
    about="After 3000 steps a shorter way opens round the wall's right end, the long way "
          "staying open. Dyna-Q's model says the long way works, so it never tries the "
          "shortcut; Dyna-Q+'s bonus for what it has not tried for long sends it there, and "
          "its curve climbs faster.",
    world="shortcut-maze",
    run=run,
    runs=30,
    episodes=None,
    aliases=("example 8.3",),
)
