"""Figure 8.2: Dyna-Q with 0, 5 and 50 planning steps on the Dyna maze, steps per episode."""

from __future__ import annotations

import numpy as np

from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
)
from tui_gym.session.book.runs import LENGTH, Learner, Played, above, margin, per_episode, play

# The book's settings: ε = 0.1, α = 0.1, γ = 0.95, Q and the model starting empty.
SETTINGS = {"learning_rate": 0.1, "learning_rate_schedule": "constant", "discount": 0.95,
            "epsilon_start": 0.1, "epsilon_final": 0.1}
PLANNING = (0, 5, 50)
LEARNERS = tuple(Learner(f"{n} planning steps", "dyna-q", {**SETTINGS, "planning_steps": n})
                 for n in PLANNING)
SETTLED = {0: 25, 5: 5, 50: 3}  # the book: the episodes each takes to reach its final level
READING = 10  # steps: how closely a curve is read off the figure's 800-step axis
LAST = 10  # episodes that make a run's final level
EARLY = (2, 10)  # the episodes compared at the start (the book's axis begins at 2)


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    played = play(FIGURE, "dyna-maze", LEARNERS, options, progress, measure=LENGTH)
    episodes = played[0].values.shape[1]
    first, last = EARLY[0] - 1, min(EARLY[1], episodes)
    early = [p.values[:, first:last].mean(axis=1) for p in played]
    checks = [
        above(f"more planning, fewer steps: {a.label} against {b.label} (episodes "
              f"{EARLY[0]} to {last})", "fewer", x, y)
        for a, b, x, y in zip(played, played[1:], early, early[1:], strict=False)
    ]
    checks += [_settled(p, SETTLED[n]) for n, p in zip(PLANNING, played, strict=True)
               if SETTLED[n] + LAST <= episodes]
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=played[0].runs,
        charts=(Chart("steps per episode", "episodes",
                      tuple(per_episode(p) for p in played), skip_start=True),),
        checks=tuple(checks),
        notes=("ε = 0.1, α = 0.1, γ = 0.95; the shortest path takes 14 steps, and exploring "
               "with ε = 0.1 lengthens it",
               f"a run's final level: its mean over the last {LAST} episodes; curves are read "
               f"off the book's figure to ±{READING} steps",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


def _settled(played: Played, episode: int) -> Check:
    """The episode no longer than the run's final level, beyond the reading and the margin."""
    at = played.values[:, episode - 1]
    final = played.values[:, -LAST:].mean(axis=1)
    excess = at - final
    return Check(f"{played.label}: at its final level by episode {episode}",
                 f"about {episode} episodes",
                 f"{at.mean():.1f} steps at episode {episode}, {final.mean():.1f} at the end",
                 float(np.mean(excess)) <= READING + margin(excess))


FIGURE = BookFigure(
    name="8.2",
    title="Dyna-Q on the Dyna maze (Figure 8.2): steps per episode",
    about="The first episode is a long random walk for every agent; after it, an agent that "
          "plans 50 updates a step has a path back nearly to the start by the second episode, "
          "one without planning needs about 25 episodes.",
    world="dyna-maze",
    run=run,
    runs=30,
    episodes=50,
    aliases=("example 8.1",),
)
