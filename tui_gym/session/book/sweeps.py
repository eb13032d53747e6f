"""The swept prediction figures (7.2, 12.3, 12.6): on the 19-state walk, one curve per
setting (n, or λ) over α, each point the mean RMS error of the first episodes, and the
book's claims about the best point of each curve."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
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
    book_figure,
)
from tui_gym.session.book.runs import BANDS, Played, below, play_prediction, swept
from tui_gym.session.experiments.compare import Arm

__all__ = ["ALPHAS", "FIGURES", "LAMBDAS", "SHOWN", "Sweep", "WalkSweep", "walk_figure"]

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
            return swept(self.label, ALPHAS, self.played, lambda v: v.mean(axis=1),
                         shown=(-np.inf, SHOWN))


@dataclass(frozen=True)
class WalkSweep:
    """A swept figure: `algorithm`, one curve over α per value of `name` in `settings`; the
    claims: the best value is in `middle`, `chosen` lies below each of `ends`."""

    algorithm: str
    name: str
    settings: Sequence[Any]
    middle: Sequence[Any]
    chosen: Any
    book_best: str
    ends: Sequence[tuple[Any, str]]
    how: str = ""

    @property
    def symbol(self) -> str:
        return "λ" if self.name == "lambda" else self.name

    def sweeps(self, figure: BookFigure, options: FigureOptions,
               progress: Progress) -> dict[Any, Sweep]:
        """One `Sweep` a value of the hyperparameter, each over `ALPHAS`."""
        learners = [Arm(self.algorithm, {"learning_rate": alpha, self.name: value},
                        f"{self.name}={value}|{alpha}")
                    for value in self.settings for alpha in ALPHAS]
        played = play_prediction(figure, 19, learners, options, progress)
        size = len(ALPHAS)
        return {value: Sweep(f"{self.symbol} = {value:g}", played[i * size: (i + 1) * size])
                for i, value in enumerate(self.settings)}

    def run(self, figure: BookFigure, options: FigureOptions,
            progress: Progress) -> FigureResult:
        """The figure measured, its claims checked."""
        curves, symbol, chosen = self.sweeps(figure, options, progress), self.symbol, self.chosen
        best = min(self.settings, key=lambda value: curves[value].means.min())
        picked = curves[chosen]
        checks = (
            Check(f"The best {symbol} is an intermediate one (the lowest point of every curve)",
                  self.book_best, f"{symbol} = {best:g} (α = {curves[best].best_alpha:g}, "
                  f"{curves[best].means.min():.3f})", best in self.middle),
            *(below(f"{symbol} = {chosen:g} below {words}, each at its best α", "lower",
                    picked.best, curves[end].best, digits=3) for end, words in self.ends),
        )
        return FigureResult(
            charts=(Chart(f"mean RMS error over the first {picked.episodes} episodes "
                          f"(points above {SHOWN:g} left out)", "α",
                          tuple(c.series() for c in curves.values())),),
            runs=len(picked.best), checks=checks,
            notes=(f"{self.how}the random policy's values -0.9 … 0.9, from policy evaluation "
                   "on the model; V starts at 0, undiscounted", BANDS),
        )


def walk_figure(name: str, title: str, about: str, sweep: WalkSweep) -> BookFigure:
    """A swept figure on the 19-state walk, at the book's 100 runs of 10 episodes."""
    return book_figure(name, "random-walk", title=title, about=about, runs=100,
                       episodes=10)(sweep.run)


LAMBDA_ENDS = ((0.0, "λ = 0 (one-step TD)"), (1.0, "λ = 1 (Monte Carlo)"))
fig_7_2 = walk_figure(
    "7.2", "n-step TD on the 19-state random walk (Figure 7.2): error against α per n",
    "Between one-step TD (n = 1) and Monte Carlo (large n), an intermediate n learns the "
    "random policy's values fastest: the book's best is n = 4. Large n needs a small step.",
    WalkSweep("n-step-td", "n", (1, 2, 4, 8, 16, 32, 64, 128, 256, 512), (2, 4, 8, 16), 4,
              "n = 4", ((1, "one-step TD (n = 1)"),
                        (512, "n = 512 (Monte Carlo on this walk)"))),
)
fig_12_3 = walk_figure(
    "12.3", "Offline λ-return on the 19-state random walk (Figure 12.3): error against α per λ",
    "Each state moves toward its λ-return at the episode's end, a blend of every n-step "
    "return: an intermediate λ does best, much as an intermediate n does for n-step TD "
    "(Figure 7.2).",
    WalkSweep("offline-lambda-return", "lambda", LAMBDAS, MIDDLE_LAMBDAS, 0.8,
              "λ about 0.8 to 0.9", LAMBDA_ENDS, "updates at each episode's end; "),
)
fig_12_6 = walk_figure(
    "12.6", "TD(λ) on the 19-state random walk (Figure 12.6): error against α per λ",
    "Traces spread each TD error back over the states just left: an intermediate λ learns "
    "the random policy's values fastest, between TD(0) (λ = 0) and Monte Carlo (λ = 1). "
    "With λ near 1 a large step makes the estimates diverge.",
    WalkSweep("td-lambda", "lambda", LAMBDAS, MIDDLE_LAMBDAS, 0.8, "λ about 0.8 to 0.9",
              LAMBDA_ENDS, "accumulating traces; "),
)
FIGURES = (fig_7_2, fig_12_3, fig_12_6)
