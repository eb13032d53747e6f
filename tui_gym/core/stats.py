"""Bounded statistics for runs of any length.

`RollingWindow` keeps the last `size` values of a quantity in a ring buffer
with a running sum (moving average in O(1)). `Series` keeps a whole run's
history as at most `capacity` points: when full it merges neighbouring points
pairwise and doubles the span each point covers, so memory stays fixed and
the picture still covers episode 0 to now. `EpisodeStats` bundles the four
per-episode quantities the trainer tracks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class RollingWindow:
    """The last `size` values of one quantity, with their mean."""

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"window size must be >= 1, got {size}")
        self.size = size
        self._values = np.zeros(size, dtype=np.float64)
        self._next = 0
        self.count = 0  # values pushed in total
        self._sum = 0.0

    def push(self, value: float) -> None:
        slot = self._next
        if self.count >= self.size:
            self._sum -= self._values[slot]
        self._values[slot] = value
        self._sum += value
        self._next = (slot + 1) % self.size
        self.count += 1
        if self._next == 0:
            # Re-sum once per lap so floating-point drift cannot build up.
            self._sum = float(self._values.sum())

    @property
    def filled(self) -> int:
        return min(self.count, self.size)

    @property
    def mean(self) -> float:
        n = self.filled
        return self._sum / n if n else 0.0

    def values(self) -> np.ndarray:
        """The window's values, oldest first (a copy)."""
        if self.count < self.size:
            return self._values[: self.count].copy()
        return np.concatenate([self._values[self._next :], self._values[: self._next]])

    @property
    def std(self) -> float:
        vals = self.values()
        return float(vals.std()) if len(vals) else 0.0


class Series:
    """A run's history of one quantity in at most `capacity` evenly spaced points."""

    def __init__(self, capacity: int = 256) -> None:
        if capacity < 2 or capacity % 2:
            raise ValueError(f"capacity must be an even number >= 2, got {capacity}")
        self.capacity = capacity
        self.span = 1  # values averaged into each point
        self._points: list[float] = []
        self._acc = 0.0
        self._acc_n = 0

    def push(self, value: float) -> None:
        self._acc += value
        self._acc_n += 1
        if self._acc_n < self.span:
            return
        self._points.append(self._acc / self._acc_n)
        self._acc = 0.0
        self._acc_n = 0
        if len(self._points) >= self.capacity:
            pts = self._points
            self._points = [(pts[i] + pts[i + 1]) / 2 for i in range(0, len(pts), 2)]
            self.span *= 2

    def points(self) -> tuple[float, ...]:
        return tuple(self._points)


@dataclass(frozen=True)
class EpisodeStats:
    """What one finished episode looked like."""

    episode_return: float
    length: int
    mean_abs_td: float
    epsilon: float
