"""Curves: several seeds' as one (the mean per episode and its 95% Student-t band, with the
t distribution computed here, without scipy), and a long curve bounded to fewer points."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from statistics import NormalDist
from typing import Any

import numpy as np

from tui_gym.core.engine.stats import Series
from tui_gym.core.experiments.figures import FieldsJson, Figure
from tui_gym.core.experiments.records import Curve

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
class CurvePoint(FieldsJson):
    """One point of an aggregated curve (lo and hi None without a band)."""

    episode: int
    mean: float
    lo: float | None
    hi: float | None


@dataclass(frozen=True, eq=False)
class AggregateCurve:
    """The mean over `seeds` curves per episode, and the band's half-width (None for 1 seed)."""

    episodes: np.ndarray
    mean: np.ndarray
    half_width: np.ndarray | None
    seeds: int

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
            half_width=None if self.half_width is None else self.half_width[keep], seeds=self.seeds)

    def points(self) -> list[CurvePoint]:
        lo, hi = self.lo, self.hi
        return [CurvePoint(int(self.episodes[i]), float(self.mean[i]),
                           None if lo is None else float(lo[i]),
                           None if hi is None else float(hi[i])) for i in range(len(self.mean))]

    def as_curves(self, name: str) -> tuple[Curve, ...]:
        """The mean as curve `name`, and the band's edges as `name.lo` and `name.hi` if any."""
        curves = [Curve(name, self.episodes, self.mean)]
        if self.half_width is not None:
            curves += [Curve(f"{name}.lo", self.episodes, self.mean - self.half_width),
                       Curve(f"{name}.hi", self.episodes, self.mean + self.half_width)]
        return tuple(curves)


def aggregate(
    curves: np.ndarray | list[Any], *, episodes: np.ndarray | None = None, window: int = 1,
    max_points: int | None = None,
) -> AggregateCurve:
    """Mean and confidence band per episode of `curves` [seeds, episodes] numbered `episodes`,
    each seed's first smoothed over a trailing `window`; at most `max_points` kept."""
    data = rolling_mean(_as_seed_rows(curves), window)
    n, length = data.shape
    if episodes is None:
        xs = np.arange(1, length + 1, dtype=np.int64)
    else:
        xs = np.asarray(episodes, dtype=np.int64)
        if xs.shape != (length,):
            raise ValueError(f"{length} episodes per curve but {len(xs)} episode numbers")
    half = t_half_width(data.std(axis=0, ddof=1), n) if n > 1 else None
    result = AggregateCurve(episodes=xs, mean=data.mean(axis=0), half_width=half, seeds=n)
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


def mean_return_last(curves: np.ndarray | list[Any]) -> Estimate:
    """Each seed's mean over its last 10% of episodes (at least one), then over the seeds."""
    data = _as_seed_rows(curves)
    last = max(1, math.ceil(data.shape[1] * LAST_FRACTION - 1e-9))
    return mean_with_ci(data[:, -last:].mean(axis=1))


_MAX_ITERATIONS = 500
_EPS = 1e-15
_TINY = 1e-300
# Beyond this many degrees of freedom the Cornish-Fisher series (error of order
# df**-5) is exact to rounding, and the continued fraction converges slowly.
_SERIES_DF = 1000.0


def _beta_continued_fraction(a: float, b: float, x: float) -> float:
    # Lentz's method for the continued fraction of the incomplete beta function.
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = 1.0
    d = 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > _TINY else _TINY)
    h = d
    for m in range(1, _MAX_ITERATIONS + 1):
        m2 = 2 * m
        even = m * (b - m) * x / ((qam + m2) * (a + m2))
        for aa in (even, -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) > _TINY else _TINY)
            c = 1.0 + aa / c
            c = c if abs(c) > _TINY else _TINY
            h *= d * c
        if abs(d * c - 1.0) < _EPS:
            break
    return h


def regularized_beta(a: float, b: float, x: float) -> float:
    """I_x(a, b), the regularized incomplete beta function, for a, b > 0 and 0 <= x <= 1."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    log_front = (
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    )
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_continued_fraction(a, b, x) / a
    return 1.0 - math.exp(log_front) * _beta_continued_fraction(b, a, 1.0 - x) / b


def _check_df(df: float) -> None:
    if not df > 0 or math.isnan(df):
        raise ValueError(f"degrees of freedom must be > 0, got {df}")


def t_cdf(t: float, df: float) -> float:
    """P(T <= t) for Student's t with `df` degrees of freedom."""
    _check_df(df)
    if math.isinf(t):
        return 1.0 if t > 0 else 0.0
    tail = 0.5 * regularized_beta(df / 2.0, 0.5, df / (df + t * t))  # P(T > |t|)
    return 1.0 - tail if t >= 0 else tail


def _cornish_fisher(z: float, df: float) -> float:
    # Abramowitz & Stegun 26.7.5: the t quantile as a series in 1/df around z.
    z2 = z * z
    g1 = (z2 + 1) * z / 4
    g2 = ((5 * z2 + 16) * z2 + 3) * z / 96
    g3 = (((3 * z2 + 19) * z2 + 17) * z2 - 15) * z / 384
    g4 = ((((79 * z2 + 776) * z2 + 1482) * z2 - 1920) * z2 - 945) * z / 92160
    return z + g1 / df + g2 / df**2 + g3 / df**3 + g4 / df**4


@lru_cache(maxsize=256)  # the same few (p, df) come back for every curve point
def t_quantile(p: float, df: float) -> float:
    """The t with P(T <= t) = p, for Student's t with `df` degrees of freedom (0 < p < 1)."""
    _check_df(df)
    if not 0.0 < p < 1.0:
        raise ValueError(f"a quantile needs 0 < p < 1, got {p}")
    if p < 0.5:
        return -t_quantile(1.0 - p, df)
    if p == 0.5:
        return 0.0
    if df == 1:
        return math.tan(math.pi * (p - 0.5))
    if df == 2:
        return (2 * p - 1) / math.sqrt(2 * p * (1 - p))
    guess = _cornish_fisher(NormalDist().inv_cdf(p), df)
    if df > _SERIES_DF:
        return guess
    # Bracket the root in [lo, hi], then halve the bracket (the series can overshoot for
    # small df).
    lo, hi = 0.0, max(guess, 1.0)
    while t_cdf(hi, df) < p:
        lo, hi = hi, hi * 2.0
    while hi - lo > 1e-13 * hi:
        middle = (lo + hi) / 2.0
        lo, hi = (middle, hi) if t_cdf(middle, df) < p else (lo, middle)
    return (lo + hi) / 2.0


def _check_points(max_points: int) -> None:
    if max_points < 2:
        raise ValueError(f"a bounded curve keeps at least 2 points, got max_points={max_points}")


def pick_indices(n: int, max_points: int) -> np.ndarray:
    """At most `max_points` evenly spaced indices into n points, including 0 and n - 1."""
    _check_points(max_points)
    if n <= max_points:
        return np.arange(n)
    # The spacing is above 1, so the rounded positions are all distinct.
    return np.rint(np.linspace(0, n - 1, max_points)).astype(np.int64)


def bucket_means(
    episodes: np.ndarray, values: np.ndarray, max_points: int, weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive points averaged (NaN left out) in at most `max_points` near-equal buckets,
    each labelled with its last episode; `weights`: the episodes each point stands for."""
    _check_points(max_points)
    episodes = np.asarray(episodes, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    n = len(values)
    if n <= max_points:
        return episodes.copy(), values.copy()
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=np.float64)
    starts = (np.arange(max_points) * n) // max_points
    ends = np.append(starts[1:], n) - 1
    present = ~np.isnan(values)
    weighted = np.where(present, values * w, 0.0)
    totals = np.add.reduceat(weighted, starts)
    counts = np.add.reduceat(np.where(present, w, 0.0), starts)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(counts > 0, totals / counts, np.nan)
    return episodes[ends], means


class CurveAccumulator(Series):
    """Per-episode values of a run of any length, as at most `capacity` bucket means: a
    `Series` that numbers its points' episodes."""

    def __init__(self, capacity: int = 512, first_episode: int = 1) -> None:
        super().__init__(capacity)
        self.first_episode = first_episode
        self.count = 0  # episodes seen

    def append(self, value: float) -> None:
        self.extend(np.array([value], dtype=np.float64))

    def extend(self, values: np.ndarray) -> None:
        """Add the values of the next episodes, in order."""
        values = np.asarray(values, dtype=np.float64).ravel()
        self.count += len(values)
        self.push_many(values)

    def curve(self, max_points: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(episodes, values): the bucket means so far, the unfinished bucket last, each
        labelled with its last episode; re-bucketed to at most `max_points` if given."""
        full = len(self._points)
        episodes = self.first_episode - 1 + self.span * np.arange(1, full + 1, dtype=np.int64)
        values = np.asarray(self._points, dtype=np.float64)
        weights = np.full(full, float(self.span))
        if self._acc_n:
            episodes = np.append(episodes, self.first_episode + self.count - 1)
            values = np.append(values, self._acc / self._acc_n)
            weights = np.append(weights, float(self._acc_n))
        if max_points is not None:
            return bucket_means(episodes, values, max_points, weights)
        return episodes, values
