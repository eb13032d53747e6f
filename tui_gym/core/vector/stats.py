"""Pushing many values at once into the trainer's bounded statistics.

The batched engine finishes hundreds of episodes per step; pushing them one
at a time into `RollingWindow` and `Series` would cost more than the
episodes. `push_window_many` and `push_series_many` leave those objects in the
state the same values pushed one by one would (up to float rounding), in a
few numpy operations. They work on the classes in `tui_gym.core.stats` from
outside, so `tests/test_vector_trainer.py` checks them against one-by-one
pushes; they would sit best as `push_many` methods on the classes themselves.
"""

from __future__ import annotations

import numpy as np

from tui_gym.core.stats import RollingWindow, Series

__all__ = ["push_series_many", "push_window_many", "window_means"]


def window_means(window: RollingWindow, values: np.ndarray) -> np.ndarray:
    """The window's mean after each of `values` would be pushed (the window is unchanged)."""
    old = window.values()
    history = np.concatenate([[0.0], old, values]).cumsum()
    totals = len(old) + np.arange(1, len(values) + 1)  # values seen after each push
    lengths = np.minimum(totals, window.size)
    return (history[totals] - history[totals - lengths]) / lengths


def push_window_many(window: RollingWindow, values: np.ndarray) -> np.ndarray:
    """Push `values` in order; returns the window's mean after each push."""
    values = np.asarray(values, dtype=np.float64)
    k = len(values)
    if k == 0:
        return values
    means = window_means(window, values)
    size = window.size
    buffer = window._values
    start = window._next
    last = values[-size:]  # only the newest `size` values can still be in the window
    slots = (start + np.arange(k - len(last), k)) % size
    buffer[slots] = last
    window._next = (start + k) % size
    window.count += k
    window._sum = float(buffer.sum())  # the slots not yet filled hold zeros
    return means


def push_series_many(series: Series, values: np.ndarray) -> None:
    """Push `values` in order, merging points as `Series.push` does when full."""
    values = np.asarray(values, dtype=np.float64)
    i, k = 0, len(values)
    while i < k:
        need = series.span - series._acc_n
        if k - i < need:  # not enough to close a point
            series._acc += float(values[i:].sum())
            series._acc_n += k - i
            return
        # Close the open point, then as many whole points as fit before a merge.
        series._points.append((series._acc + float(values[i : i + need].sum())) / series.span)
        series._acc, series._acc_n = 0.0, 0
        i += need
        room = series.capacity - len(series._points)
        whole = min((k - i) // series.span, max(room, 0))
        if whole:
            block = values[i : i + whole * series.span].reshape(whole, series.span)
            series._points.extend(block.mean(axis=1).tolist())
            i += whole * series.span
        if len(series._points) >= series.capacity:
            pts = series._points
            series._points = [(pts[j] + pts[j + 1]) / 2 for j in range(0, len(pts), 2)]
            series.span *= 2
