"""What the swept prediction figures (7.2, 12.6) share: one curve per setting over α, each
point the mean RMS error of the first episodes, and the best point of each curve."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tui_gym.session.book.figure import BookFigure, FigureOptions, Progress, Series
from tui_gym.session.book.prediction_runs import play_prediction
from tui_gym.session.book.runs import Learner, Played, swept

__all__ = ["ALPHAS", "SHOWN", "Sweep", "sweep"]

ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
SHOWN = 0.55  # the book's axis ends here: points above it are off the chart


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
    learners = [Learner(f"{name}={value}|{alpha}", algorithm,
                        {"learning_rate": alpha, name: value})
                for value in settings for alpha in ALPHAS]
    played = play_prediction(figure, 19, learners, options, progress)
    size = len(ALPHAS)
    return [Sweep(f"{'λ' if name == 'lambda' else name} = {value:g}",
                  played[i * size: (i + 1) * size]) for i, value in enumerate(settings)]
