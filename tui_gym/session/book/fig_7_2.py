"""Figure 7.2: n-step TD on the 19-state random walk, the mean RMS error of the first 10
episodes against α, one curve per n."""

from __future__ import annotations

from tui_gym.session.book.figure import BookFigure, FigureOptions, FigureResult, Progress
from tui_gym.session.book.sweeps import swept_figure

NS = (1, 2, 4, 8, 16, 32, 64, 128, 256, 512)
MIDDLE = (2, 4, 8, 16)  # the intermediate n


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    return swept_figure(FIGURE, "n-step-td", "n", NS, MIDDLE, 4, "n = 4",
                        ((1, "one-step TD (n = 1)"), (512, "n = 512 (Monte Carlo on this walk)")),
                        "", options, progress)


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
