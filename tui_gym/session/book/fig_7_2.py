"""Figure 7.2: n-step TD on the 19-state random walk, the mean RMS error of the first 10
episodes against α, one curve per n."""

from __future__ import annotations

from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
)
from tui_gym.session.book.runs import above
from tui_gym.session.book.sweeps import SHOWN, sweep

NS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)
MIDDLE = (2, 4, 8, 16)  # the intermediate n


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    curves = dict(zip(NS, sweep(FIGURE, "n-step-td", "n", NS, options, progress),
                      strict=True))
    best = min(NS, key=lambda n: curves[n].means.min())
    four = curves[4]
    checks = (
        Check("The best n is an intermediate one (the lowest point of every curve)", "n = 4",
              f"n = {best} (α = {curves[best].best_alpha:g}, "
              f"{curves[best].means.min():.3f})", best in MIDDLE),
        above("n = 4 below one-step TD (n = 1), each at its best α", "lower",
              curves[1].best, four.best, digits=3),
        above("n = 4 below n = 512 (Monte Carlo on this walk), each at its best α", "lower",
              curves[512].best, four.best, digits=3),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=len(four.best),
        charts=(Chart(f"mean RMS error over the first {four.episodes} episodes "
                      f"(points above {SHOWN:g} left out)", "α",
                      tuple(c.series() for c in curves.values())),),
        checks=checks,
        notes=("the random policy's values -0.9 … 0.9, from policy evaluation on the model; "
               "V starts at 0, undiscounted",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="7.2",
    title="n-step TD on the 19-state random walk (Figure 7.2): error against α per n",
    about="Between one-step TD (n = 1) and Monte Carlo (large n), an intermediate n learns "
          "the random policy's values fastest: the book's best is n = 4. Large n needs a "
          "small step.",
    world="random-walk",
    run=run,
    runs=100,
    episodes=10,
)
