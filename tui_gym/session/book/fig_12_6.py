"""Figure 12.6: TD(λ) on the 19-state random walk, the mean RMS error of the first 10 episodes
against α, one curve per λ."""

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

LAMBDAS = (0.0, 0.4, 0.8, 0.9, 0.95, 0.975, 0.99, 1.0)
MIDDLE = (0.4, 0.8, 0.9, 0.95)  # the intermediate λ


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    curves = dict(zip(LAMBDAS, sweep(FIGURE, "td-lambda", "lambda", LAMBDAS, options,
                                     progress), strict=True))
    best = min(LAMBDAS, key=lambda lam: curves[lam].means.min())
    middle = curves[0.8]
    checks = (
        Check("The best λ is an intermediate one (the lowest point of every curve)",
              "λ about 0.8 to 0.9", f"λ = {best:g} (α = {curves[best].best_alpha:g}, "
              f"{curves[best].means.min():.3f})", best in MIDDLE),
        above("λ = 0.8 below TD(0) (λ = 0), each at its best α", "lower",
              curves[0.0].best, middle.best, digits=3),
        above("λ = 0.8 below λ = 1, each at its best α", "lower", curves[1.0].best,
              middle.best, digits=3),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=len(middle.best),
        charts=(Chart(f"mean RMS error over the first {middle.episodes} episodes "
                      f"(points above {SHOWN:g} left out)", "α",
                      tuple(c.series() for c in curves.values())),),
        checks=checks,
        notes=("accumulating traces; the random policy's values -0.9 … 0.9, from policy "
               "evaluation on the model; V starts at 0, undiscounted",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


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
