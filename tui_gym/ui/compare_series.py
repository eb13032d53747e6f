"""What the Compare view draws: a run's return curve with its band, and its final figures."""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from tui_gym.core.experiments import Figure, RunRecord, RunSummary, rolling_mean
from tui_gym.core.text import visible
from tui_gym.games.words import plural

if TYPE_CHECKING:
    from tui_gym.session.experiments.compare import AlgorithmOutcome

CURVE = "return"
SMOOTH_FRACTION = 0.1  # a single run's curve: a trailing mean over this share of its points


def algorithm_title(name: str) -> str:
    """How a person reads an algorithm's registry name (the name itself when unknown)."""
    from tui_gym.algorithms import ALGORITHMS

    return next((cls.title for cls in ALGORITHMS if cls.name == name), name)


def run_label(run: RunSummary) -> str:
    """'#12 Q-learning': a run's id and its algorithm (as data: control characters shown)."""
    return f"#{run.id} {visible(algorithm_title(run.algorithm), 40)}"


@dataclass(frozen=True, eq=False)
class Series:
    """One curve of the chart: `mean` at `episodes`, the band `lo`..`hi` if any."""

    key: Hashable  # a run's id, or ("live", algorithm) while a comparison runs
    label: str
    episodes: np.ndarray
    mean: np.ndarray
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None
    seeds: int = 1
    smoothing: int = 1  # the trailing mean's window over points (1: as recorded)
    smoothing_episodes: int = 1  # about how many episodes that window spans
    bounds: tuple[float, float] | None = None  # the returns the game allows, when known

    @property
    def has_band(self) -> bool:
        return self.lo is not None and self.hi is not None

    def legend(self) -> str:
        """The legend's words: label, seeds, and what the band and the smoothing are."""
        words = [self.label, plural(self.seeds, "seed")]
        if self.has_band:
            words.append("95% band")
        if self.smoothing > 1:
            words.append(f"smoothed over {self.smoothing_episodes:,} episodes")
        return " · ".join(words)


def bounded(series: Series, bounds: tuple[float, float] | None) -> Series:
    """`series` within the returns its game allows (`bounds`, ±inf on a side without
    one): its band clipped to them, and the bounds kept for the chart's axis."""
    if bounds is None:
        return series
    low, high = bounds
    lo = None if series.lo is None else np.clip(series.lo, low, high)
    hi = None if series.hi is None else np.clip(series.hi, low, high)
    return replace(series, lo=lo, hi=hi, bounds=(low, high))


def _finite(episodes: np.ndarray, *columns: np.ndarray) -> tuple[np.ndarray, ...]:
    keep = np.isfinite(columns[0])
    for column in columns[1:]:
        keep &= np.isfinite(column)
    return (episodes[keep], *(c[keep] for c in columns))


def _curve(
    key: Hashable, label: str, episodes: np.ndarray, mean: np.ndarray,
    lo: np.ndarray | None, hi: np.ndarray | None, seeds: int, smooth: bool,
) -> Series | None:
    """The curve over its finite points, smoothed with `smooth`, with its band where the
    band has some; None without a point."""
    xs: np.ndarray = np.empty(0)
    if lo is not None and hi is not None:
        xs, ys, lo, hi = _finite(episodes, mean, lo, hi)
    if not len(xs):
        (xs, ys), lo, hi = _finite(episodes, mean), None, None
    if not len(xs):
        return None
    window = max(1, round(len(ys) * SMOOTH_FRACTION)) if smooth else 1
    if lo is not None and hi is not None:
        lo, hi = rolling_mean(lo, window), rolling_mean(hi, window)
    spacing = (xs[-1] - xs[0]) / (len(xs) - 1) if len(xs) > 1 else 1
    return Series(key, label, xs, rolling_mean(ys, window), lo, hi, seeds=seeds,
                  smoothing=window, smoothing_episodes=max(1, round(window * spacing)))


def series_of_record(record: RunRecord, smooth: bool = True) -> Series | None:
    """The run's `return` curve (with `return.lo`/`return.hi` as its band), None without one."""
    curve = record.curve(CURVE)
    if curve is None or not len(curve):
        return None
    lo, hi = record.curve(f"{CURVE}.lo"), record.curve(f"{CURVE}.hi")
    band: tuple[np.ndarray | None, np.ndarray | None] = (None, None)
    if (lo is not None and hi is not None and np.array_equal(lo.episodes, curve.episodes)
            and np.array_equal(hi.episodes, curve.episodes)):
        band = (lo.values, hi.values)
    return _curve(record.id, run_label(record.summary), curve.episodes, curve.values, *band,
                  max(1, len(record.summary.seeds)), smooth)


def series_of_outcome(outcome: AlgorithmOutcome, label: str, smooth: bool = True) -> Series | None:
    """A running comparison's aggregate curve for one algorithm, None before any point.
    Smoothed, it is the comparison's own smoothed curve where it has one (each seed's
    returns smoothed before the band is formed)."""
    curve = outcome.curve
    if smooth and outcome.smoothed is not None and len(outcome.smoothed):
        own = outcome.smoothed
        if own.lo is not None and own.hi is not None:
            xs, ys, low, high = _finite(np.asarray(own.episodes), own.mean, own.lo, own.hi)
            if len(xs):
                return Series(("live", outcome.algorithm), label, xs, ys, low, high,
                              seeds=max(1, own.seeds), smoothing=outcome.smoothing,
                              smoothing_episodes=outcome.smoothing)
    lo, hi = curve.lo, curve.hi
    return _curve(("live", outcome.algorithm), label, np.asarray(curve.episodes),
                  np.asarray(curve.mean, dtype=np.float64),
                  None if lo is None else np.asarray(lo), None if hi is None else np.asarray(hi),
                  max(1, int(curve.seeds)), smooth)


@dataclass(frozen=True)
class FigureRow:
    """One row of the figures table."""

    key: Hashable
    label: str
    seeds: int
    episodes: int | None
    mean_return_last: Figure | None
    exact_value: Figure | None
    exact_gap: Figure | None
    note: str = ""  # "running", "interrupted", ...


def row_of_record(record: RunRecord) -> FigureRow:
    summary = record.summary
    curve = record.curve(CURVE)
    trained = summary.figure("episodes")  # what the run trained; a curve ends at its last bucket
    if trained is not None and trained.value == trained.value:
        episodes: int | None = int(trained.value)
    else:
        episodes = int(curve.episodes[-1]) if curve is not None and len(curve) else None
    status = str(summary.status)
    return FigureRow(
        key=record.id, label=run_label(summary), seeds=max(1, len(summary.seeds)),
        episodes=episodes, mean_return_last=summary.figure("mean_return_last"),
        exact_value=summary.figure("exact_value"), exact_gap=summary.figure("exact_gap"),
        note="" if status == "finished" else status,
    )


def _figure(name: str, value: float | None, ci95: float | None = None) -> Figure | None:
    return None if value is None else Figure(name, value, ci95=ci95)


def row_of_outcome(outcome: AlgorithmOutcome, label: str, note: str = "running") -> FigureRow:
    """The figures so far: over the episodes every seed has finished."""
    estimate = outcome.mean_return_last
    return FigureRow(
        key=("live", outcome.algorithm), label=label, seeds=int(outcome.curve.seeds),
        episodes=outcome.episodes or None,
        mean_return_last=Figure("mean_return_last", estimate.mean, ci95=estimate.ci95),
        exact_value=_figure("exact_value", outcome.exact_value, outcome.exact_ci95),
        exact_gap=_figure("exact_gap", outcome.exact_gap), note=note,
    )


__all__ = [
    "CURVE", "FigureRow", "Series", "algorithm_title", "bounded", "row_of_outcome", "row_of_record",
    "run_label", "series_of_outcome", "series_of_record",
]
