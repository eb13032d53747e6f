"""Bounded curves: fewer points for a long curve, and a run's curve kept in fixed memory."""

from __future__ import annotations

import numpy as np


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


def downsample(
    episodes: np.ndarray, *series: np.ndarray, max_points: int
) -> tuple[np.ndarray, ...]:
    """`episodes` and each of `series` at the same at most `max_points` picked points."""
    episodes = np.asarray(episodes)
    keep = pick_indices(len(episodes), max_points)
    return (episodes[keep], *(np.asarray(values)[..., keep] for values in series))


def bucket_means(
    episodes: np.ndarray, values: np.ndarray, max_points: int, weights: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive points averaged into at most `max_points` buckets of near-equal size.

    Each bucket is labelled with its last episode; `weights` (how many episodes
    each point already stands for) make the means exact for points that are
    themselves bucket means. NaN values are left out of a bucket's mean.
    """
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


class CurveAccumulator:
    """Per-episode values of a run of any length, as at most `capacity` bucket means."""

    def __init__(self, capacity: int = 512, first_episode: int = 1) -> None:
        if capacity < 2 or capacity % 2:
            raise ValueError(f"capacity must be an even number >= 2, got {capacity}")
        self.capacity = capacity
        self.first_episode = first_episode
        self.span = 1  # episodes in each full bucket
        self.count = 0  # episodes seen
        self._means: list[float] = []
        self._tail_sum = 0.0
        self._tail_n = 0

    def append(self, value: float) -> None:
        self.extend(np.array([value], dtype=np.float64))

    def extend(self, values: np.ndarray) -> None:
        """Add the values of the next episodes, in order."""
        values = np.asarray(values, dtype=np.float64).ravel()
        i, k = 0, len(values)
        self.count += k
        while i < k:
            need = self.span - self._tail_n
            take = min(need, k - i)
            if self._tail_n or take < self.span:
                self._tail_sum += float(values[i : i + take].sum())
                self._tail_n += take
                i += take
                if self._tail_n < self.span:
                    return
                self._close(self._tail_sum / self.span)
                self._tail_sum, self._tail_n = 0.0, 0
                continue
            whole = min((k - i) // self.span, self.capacity - len(self._means))
            block = values[i : i + whole * self.span].reshape(whole, self.span)
            self._means.extend(block.mean(axis=1).tolist())
            i += whole * self.span
            self._merge_if_full()

    def _close(self, mean: float) -> None:
        self._means.append(mean)
        self._merge_if_full()

    def _merge_if_full(self) -> None:
        if len(self._means) >= self.capacity:
            pairs = np.asarray(self._means).reshape(-1, 2)
            self._means = pairs.mean(axis=1).tolist()
            self.span *= 2

    def curve(self, max_points: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(episodes, values): the bucket means so far, the unfinished bucket last, each
        labelled with its last episode; re-bucketed to at most `max_points` if given."""
        full = len(self._means)
        episodes = self.first_episode - 1 + self.span * np.arange(1, full + 1, dtype=np.int64)
        values = np.asarray(self._means, dtype=np.float64)
        weights = np.full(full, float(self.span))
        if self._tail_n:
            episodes = np.append(episodes, self.first_episode + self.count - 1)
            values = np.append(values, self._tail_sum / self._tail_n)
            weights = np.append(weights, float(self._tail_n))
        if max_points is not None:
            return bucket_means(episodes, values, max_points, weights)
        return episodes, values
