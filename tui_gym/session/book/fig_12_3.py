"""Figure 12.3: the offline λ-return algorithm on the 19-state random walk, the mean RMS error
of the first 10 episodes against α, one curve per λ."""

from __future__ import annotations

from tui_gym.session.book.figure import BookFigure, FigureOptions, FigureResult, Progress
from tui_gym.session.book.sweeps import lambda_figure


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    return lambda_figure(FIGURE, "offline-lambda-return", "updates at each episode's end",
                         options, progress)


FIGURE = BookFigure(
    name="12.3",
    title="Offline λ-return on the 19-state random walk (Figure 12.3): error against α per λ",
    about="Each state moves toward its λ-return at the episode's end, a blend of every "
          "n-step return: an intermediate λ does best, much as an intermediate n does for "
          "n-step TD (Figure 7.2).",
    world="random-walk",
    run=run,
    runs=100,
    episodes=10,
)
