"""Figure 12.6: TD(λ) on the 19-state random walk, the mean RMS error of the first 10 episodes
against α, one curve per λ."""

from __future__ import annotations

from tui_gym.session.book.figure import BookFigure, FigureOptions, FigureResult, Progress
from tui_gym.session.book.sweeps import lambda_figure


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    return lambda_figure(FIGURE, "td-lambda", "accumulating traces", options, progress)


FIGURE = BookFigure(
    name="12.6",
    title="TD(λ) on the 19-state random walk (Figure 12.6): error against α per λ",
    about="Traces spread each TD error back over the states just left: an intermediate λ "
          "learns the random policy's values fastest, between TD(0) (λ = 0) and Monte "
          "Carlo (λ = 1). With λ near 1 a large step makes the estimates diverge.",
    world="random-walk",
    run=run,
    runs=100,
    episodes=10,
)
