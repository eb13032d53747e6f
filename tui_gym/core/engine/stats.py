"""Bounded statistics for runs of any length (`RollingWindow`, `Series`), and the immutable
views of a run (`EpisodeStats`, `TrainingSnapshot`, `StepEvent`)."""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tui_gym.core.engine.kernel import kernel


@kernel
def push_all(ring: Any, values: Any, means: Any, at: int, count: int,
             total: float) -> tuple[int, int, float]:
    """`RollingWindow.push` of each of `values` in turn, the mean after each into `means`;
    the next slot, count and sum after them."""
    size = ring.shape[0]
    for i in range(values.shape[0]):
        if count >= size:
            total -= ring[at]
        ring[at] = values[i]
        total += values[i]
        at += 1
        count += 1
        if at == size:  # re-summed once per lap, so that no drift builds up
            at = 0
            total = 0.0
            for j in range(size):
                total += ring[j]
        means[i] = total / min(count, size)
    return at, count, total


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
        self.push_many(np.array([value], dtype=np.float64))

    def push_many(self, values: np.ndarray) -> np.ndarray:
        """Push `values` in order (compiled); the mean after each."""
        values = np.ascontiguousarray(values, dtype=np.float64)
        means = np.empty(len(values))
        at, count, total = push_all(self._values, values, means, self._next, self.count,
                                    self._sum)
        self._next, self.count, self._sum = int(at), int(count), float(total)
        return means

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
        self.push_many(np.array([value], dtype=np.float64))

    def push_many(self, values: np.ndarray) -> None:
        """Push `values` in order; when full, merge points pairwise and double the span."""
        values = np.asarray(values, dtype=np.float64)
        i, k = 0, len(values)
        while i < k:
            need = self.span - self._acc_n
            if k - i < need:  # not enough to close a point
                self._acc += float(values[i:].sum())
                self._acc_n += k - i
                return
            self._points.append((self._acc + float(values[i : i + need].sum())) / self.span)
            self._acc, self._acc_n = 0.0, 0
            i += need
            room = self.capacity - len(self._points)
            whole = min((k - i) // self.span, max(room, 0))
            if whole:
                block = values[i : i + whole * self.span].reshape(whole, self.span)
                self._points.extend(block.mean(axis=1).tolist())
                i += whole * self.span
            if len(self._points) >= self.capacity:
                pts = self._points
                self._points = [(pts[j] + pts[j + 1]) / 2 for j in range(0, len(pts), 2)]
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
    first_action: int = -1  # the action taken in the episode's first state


@dataclass(frozen=True)
class TrainingSnapshot:
    """What a viewer needs to draw one frame of training; never changes."""

    engine: str  # the loop that trained last: "model" or "env"
    episodes: int
    steps: int
    seconds: float  # time spent training
    episodes_per_second: float  # recent rate
    epsilon: float
    mean_return: float  # over the rolling window
    mean_length: float
    mean_abs_td: float
    window: int
    series: dict[str, tuple[float, ...]]  # whole-run history per quantity
    q: np.ndarray  # copy of the learner's action values (rows used)
    keys: list[Hashable] | None  # the key of each row for sparse tables, None when dense
    budget: int  # the episode budget from the hyperparameters
    last: EpisodeStats | None = None
    version: int = 0  # increases with every snapshot of a run
    recorded: int = 0  # episodes in the statistics (fewer than `episodes` after a load)
    status: str = ""  # what the engine is doing besides training, e.g. compiling
    traces: np.ndarray | None = None  # the episode's eligibility traces, shaped as `q`
    _lookup: dict[Hashable, int] | None = field(default=None, repr=False, compare=False)

    def values(self, keys: list[Hashable], traces: bool = False) -> np.ndarray:
        """Action values (with `traces`, the traces) for the given keys (zeros for unseen)."""
        table = self.traces if traces else self.q
        if table is None:
            raise ValueError("this learner keeps no eligibility traces")
        out = np.zeros((len(keys), table.shape[1]))
        if self.keys is None:
            if keys:
                out[:] = table[np.asarray(keys, dtype=np.int64)]
            return out
        lookup = self._lookup
        if lookup is None:
            lookup = {k: i for i, k in enumerate(self.keys)}
            object.__setattr__(self, "_lookup", lookup)
        for i, key in enumerate(keys):
            row = lookup.get(key)
            if row is not None:
                out[i] = table[row]
        return out

    @property
    def progress(self) -> float:
        return min(1.0, self.episodes / self.budget) if self.budget else 0.0


@dataclass(frozen=True)
class StepEvent:
    """One move of the agent, for animated training."""

    observation: Any
    action: int
    reward: float
    next_observation: Any
    terminated: bool
    truncated: bool
    episode_done: EpisodeStats | None
    episode: int = 0  # the 1-based number of the episode this step belongs to
    step: int = 0  # the 1-based number of this step within its episode
    last_update: Any = None  # the learner's record of the update, when asked to explain
