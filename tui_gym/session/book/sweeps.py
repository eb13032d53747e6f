"""What the swept prediction figures (7.2, 12.3, 12.6) share: one curve per setting over α,
each point the mean RMS error of the first episodes, and the best point of each curve;
`swept_figure` is the whole of such a figure, `lambda_figure` one with a curve per λ
(12.3, 12.6)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
)
from tui_gym.session.book.prediction_runs import play_prediction
from tui_gym.session.book.runs import Learner, Played, below, swept

__all__ = ["ALPHAS", "LAMBDAS", "SHOWN", "Sweep", "lambda_figure", "sweep", "swept_figure"]

ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
SHOWN = 0.55  # the book's axis ends here: points above it are off the chart
LAMBDAS = (0.0, 0.4, 0.8, 0.9, 0.95, 0.975, 0.99, 1.0)
MIDDLE_LAMBDAS = (0.4, 0.8, 0.9, 0.95)  # the intermediate λ


class Sweep:
    """Per setting, its `Played` runs over `ALPHAS` and their per-run means."""

    def __init__(self, label: str, played: Sequence[Played]) -> None:
        self.label = label
        self.played = tuple(played)
        self.per_run = [p.values.mean(axis=1) for p in played]  # one number a run, per α
        with np.errstate(invalid="ignore", over="ignore"):
            means = np.array([v.mean() for v in self.per_run])
        self.means = np.where(np.isfinite(means), means, np.inf)

    @property
    def episodes(self) -> int:
        return int(self.played[0].values.shape[1])

    @property
    def best(self) -> np.ndarray:
        """The per-run figures at the α with the lowest mean."""
        return self.per_run[int(np.argmin(self.means))]

    @property
    def best_alpha(self) -> float:
        return ALPHAS[int(np.argmin(self.means))]

    def series(self) -> Series:
        """The curve over α, without the points off the book's chart (diverging ones)."""
        with np.errstate(invalid="ignore", over="ignore"):  # diverged runs: inf, NaN
            full = swept(self.label, ALPHAS, self.played, lambda v: v.mean(axis=1))
        assert full.lo is not None and full.hi is not None  # a sweep has bands
        keep = np.isfinite(full.hi) & (full.y <= SHOWN)
        return Series(full.label, full.x[keep], full.y[keep], full.lo[keep], full.hi[keep])


def sweep(figure: BookFigure, algorithm: str, name: str, settings: Sequence[Any],
          options: FigureOptions, progress: Progress) -> list[Sweep]:
    """One `Sweep` a value of hyperparameter `name`, each over `ALPHAS`, on the 19-state
    walk."""
    learners = [Learner(f"{name}={value}|{alpha}", algorithm, {"learning_rate": alpha, name: value})
                for value in settings for alpha in ALPHAS]
    played = play_prediction(figure, 19, learners, options, progress)
    size = len(ALPHAS)
    return [Sweep(f"{'λ' if name == 'lambda' else name} = {value:g}",
                  played[i * size: (i + 1) * size]) for i, value in enumerate(settings)]


def swept_figure(figure: BookFigure, algorithm: str, name: str, settings: Sequence[Any],
                 middle: Sequence[Any], chosen: Any, book_best: str,
                 ends: Sequence[tuple[Any, str]], how: str, options: FigureOptions,
                 progress: Progress) -> FigureResult:
    """A figure of `algorithm` with one curve over α per value of `name` on the 19-state
    walk, and the book's claims: the best value is an intermediate one (in `middle`), and
    `chosen` lies below each of `ends` (a value and how the claim names it)."""
    curves = dict(zip(settings, sweep(figure, algorithm, name, settings, options, progress),
                      strict=True))
    symbol = "λ" if name == "lambda" else name
    best = min(settings, key=lambda value: curves[value].means.min())
    picked = curves[chosen]
    checks = (
        Check(f"The best {symbol} is an intermediate one (the lowest point of every curve)",
              book_best, f"{symbol} = {best:g} (α = {curves[best].best_alpha:g}, "
              f"{curves[best].means.min():.3f})", best in middle),
        *(below(f"{symbol} = {chosen:g} below {words}, each at its best α", "lower",
                picked.best, curves[end].best, digits=3) for end, words in ends),
    )
    return FigureResult(
        figure=figure.name, title=figure.title, runs=len(picked.best),
        charts=(Chart(f"mean RMS error over the first {picked.episodes} episodes "
                      f"(points above {SHOWN:g} left out)", "α",
                      tuple(c.series() for c in curves.values())),),
        checks=checks,
        notes=(f"{how}the random policy's values -0.9 … 0.9, from policy evaluation on "
               "the model; V starts at 0, undiscounted",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


def lambda_figure(figure: BookFigure, algorithm: str, how: str, options: FigureOptions,
                  progress: Progress) -> FigureResult:
    """A figure of `algorithm` with one curve per λ over α on the 19-state walk, and the
    book's claims: an intermediate λ does best, below λ = 0 and λ = 1."""
    return swept_figure(figure, algorithm, "lambda", LAMBDAS, MIDDLE_LAMBDAS, 0.8,
                        "λ about 0.8 to 0.9",
                        ((0.0, "λ = 0 (one-step TD)"), (1.0, "λ = 1 (Monte Carlo)")),
                        f"{how}; ", options, progress)
