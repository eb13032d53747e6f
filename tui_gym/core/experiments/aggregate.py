"""Curves from several seeds, as one: the mean per episode and its 95% confidence band."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.core.experiments.downsample import pick_indices
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.records import Curve
from tui_gym.core.experiments.student_t import t_quantile

CONFIDENCE = 0.95
LAST_FRACTION = 0.1


def _as_seed_rows(curves: np.ndarray | list[Any]) -> np.ndarray:
    data = np.asarray(curves, dtype=np.float64)
    if data.ndim == 1:
        data = data[np.newaxis, :]
    if data.ndim != 2 or data.shape[0] < 1 or data.shape[1] < 1:
        raise ValueError(f"curves must be an array [seeds, episodes], got shape {data.shape}")
    if not np.isfinite(data).all():
        raise ValueError("curves must be finite (every seed needs a value at every episode)")
    return data


def t_half_width(std: np.ndarray | float, n: int, confidence: float = CONFIDENCE) -> Any:
    """The half-width of the Student-t interval of a mean of n samples with sample std `std`."""
    if n < 2:
        raise ValueError("an interval needs at least 2 samples")
    return t_quantile(0.5 + confidence / 2, n - 1) * np.asarray(std) / math.sqrt(n)


def rolling_mean(values: np.ndarray, window: int) -> np.ndarray:
    """The trailing mean over `window` episodes along the last axis (fewer at the start)."""
    if window < 1:
        raise ValueError(f"the smoothing window must be >= 1, got {window}")
    values = np.asarray(values, dtype=np.float64)
    if window == 1:
        return values.copy()
    n = values.shape[-1]
    sums = np.cumsum(values, axis=-1)
    out = sums.copy()
    if n > window:
        out[..., window:] = sums[..., window:] - sums[..., :-window]
    counts = np.minimum(np.arange(1, n + 1), window)
    return out / counts


@dataclass(frozen=True)
class CurvePoint:
    """One point of an aggregated curve (lo and hi None without a band)."""

    episode: int
    mean: float
    lo: float | None
    hi: float | None

    def to_json(self) -> dict[str, Any]:
        return {"episode": self.episode, "mean": self.mean, "lo": self.lo, "hi": self.hi}


@dataclass(frozen=True, eq=False)
class AggregateCurve:
    """The mean over `seeds` curves per episode, and the band's half-width (None for 1 seed)."""

    episodes: np.ndarray
    mean: np.ndarray
    half_width: np.ndarray | None
    seeds: int
    confidence: float = CONFIDENCE

    @property
    def lo(self) -> np.ndarray | None:
        return None if self.half_width is None else self.mean - self.half_width

    @property
    def hi(self) -> np.ndarray | None:
        return None if self.half_width is None else self.mean + self.half_width

    def __len__(self) -> int:
        return len(self.mean)

    def downsample(self, max_points: int) -> AggregateCurve:
        """At most `max_points` evenly spaced points, the first and last episode kept."""
        keep = pick_indices(len(self.mean), max_points)
        return AggregateCurve(
            episodes=self.episodes[keep], mean=self.mean[keep],
            half_width=None if self.half_width is None else self.half_width[keep], seeds=self.seeds,
            confidence=self.confidence,
        )

    def points(self) -> list[CurvePoint]:
        lo, hi = self.lo, self.hi
        return [
            CurvePoint(
                episode=int(self.episodes[i]), mean=float(self.mean[i]),
                lo=None if lo is None else float(lo[i]), hi=None if hi is None else float(hi[i]),
            )
            for i in range(len(self.mean))
        ]

    def as_curves(self, name: str) -> tuple[Curve, ...]:
        """The mean as curve `name`, and the band's edges as `name.lo` and `name.hi` if any."""
        curves = [Curve(name, self.episodes, self.mean)]
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            curves.append(Curve(f"{name}.lo", self.episodes, lo))
            curves.append(Curve(f"{name}.hi", self.episodes, hi))
        return tuple(curves)


def aggregate(
    curves: np.ndarray | list[Any], *, episodes: np.ndarray | None = None, window: int = 1,
    max_points: int | None = None, confidence: float = CONFIDENCE,
) -> AggregateCurve:
    """Mean and confidence band per episode of `curves` [seeds, episodes].

    `episodes` numbers the columns (1, 2, ... by default); `window` > 1 smooths
    each seed's curve with a trailing rolling mean first (so the band is that of
    the smoothed quantity); `max_points` then keeps at most that many points.
    """
    data = rolling_mean(_as_seed_rows(curves), window)
    n, length = data.shape
    if episodes is None:
        xs = np.arange(1, length + 1, dtype=np.int64)
    else:
        xs = np.asarray(episodes, dtype=np.int64)
        if xs.shape != (length,):
            raise ValueError(f"{length} episodes per curve but {len(xs)} episode numbers")
    half = t_half_width(data.std(axis=0, ddof=1), n, confidence) if n > 1 else None
    result = AggregateCurve(
        episodes=xs, mean=data.mean(axis=0), half_width=half, seeds=n, confidence=confidence
    )
    return result if max_points is None else result.downsample(max_points)


@dataclass(frozen=True)
class Estimate:
    """A mean over seeds with its interval's half-width (None for 1 seed)."""

    mean: float
    ci95: float | None
    seeds: int

    def figure(self, name: str, unit: str = "") -> Figure:
        return Figure(name=name, value=self.mean, unit=unit, ci95=self.ci95)


def mean_with_ci(samples: np.ndarray | list[float]) -> Estimate:
    """The mean of one value per seed, with its 95% Student-t interval."""
    values = np.asarray(samples, dtype=np.float64).ravel()
    if len(values) == 0 or not np.isfinite(values).all():
        raise ValueError("a mean needs at least one value, all finite")
    n = len(values)
    half = float(t_half_width(values.std(ddof=1), n)) if n > 1 else None
    return Estimate(mean=float(values.mean()), ci95=half, seeds=n)


def mean_return_last(curves: np.ndarray | list[Any], fraction: float = LAST_FRACTION) -> Estimate:
    """Each seed's mean over its last `fraction` of episodes (at least one), then the mean
    over seeds with its interval."""
    if not 0 < fraction <= 1:
        raise ValueError(f"fraction must be in (0, 1], got {fraction}")
    data = _as_seed_rows(curves)
    last = max(1, math.ceil(data.shape[1] * fraction - 1e-9))
    return mean_with_ci(data[:, -last:].mean(axis=1))
