"""Bounded curves: picked points, bucket means, and a run's curve in fixed memory."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.experiments.aggregate import (
    CurveAccumulator,
    aggregate,
    bucket_means,
    pick_indices,
)


def test_pick_indices_are_even_and_keep_both_ends() -> None:
    assert pick_indices(5, 10).tolist() == [0, 1, 2, 3, 4]
    assert pick_indices(11, 3).tolist() == [0, 5, 10]
    picked = pick_indices(100_000, 500)
    assert len(picked) == 500 and picked[0] == 0 and picked[-1] == 99_999
    assert np.all(np.diff(picked) > 0)
    with pytest.raises(ValueError):
        pick_indices(10, 1)


def test_downsample_picks_the_same_points_of_every_series() -> None:
    values = np.arange(1, 11) * 10.0
    curve = aggregate([values, values + 2.0]).downsample(4)
    assert curve.episodes.tolist() == [1, 4, 7, 10]
    assert curve.mean.tolist() == [11.0, 41.0, 71.0, 101.0]
    assert curve.half_width is not None and len(curve.half_width) == 4


def test_bucket_means_by_hand() -> None:
    xs, ys = bucket_means(np.arange(1, 7), np.array([1.0, 3.0, 5.0, 7.0, 9.0, 11.0]), 3)
    assert xs.tolist() == [2, 4, 6]  # each bucket labelled with its last episode
    assert ys.tolist() == [2.0, 6.0, 10.0]
    # Weights: a point standing for 3 episodes counts three times.
    xs, ys = bucket_means(
        np.array([3, 4, 5, 6]), np.array([1.0, 5.0, 0.0, 2.0]), 2, np.array([3, 1, 1, 1])
    )
    assert ys.tolist() == [2.0, 1.0]
    # NaN is left out of its bucket; a bucket of NaN only stays NaN.
    xs, ys = bucket_means(np.arange(4), np.array([np.nan, 4.0, np.nan, np.nan]), 2)
    assert ys[0] == 4.0 and np.isnan(ys[1])


def test_accumulator_means_are_exact_and_memory_is_bounded() -> None:
    rng = np.random.default_rng(0)
    values = rng.normal(size=100_003)
    acc = CurveAccumulator(capacity=64)
    # Uneven chunks, single values included, must give what one big push gives.
    for chunk in np.array_split(values[:-3], 97):
        acc.extend(chunk)
    for value in values[-3:]:
        acc.append(float(value))
    assert acc.count == len(values)
    episodes, means = acc.curve()
    assert len(means) <= 64 + 1
    assert episodes[-1] == len(values)  # the unfinished bucket keeps the last episode
    edges = np.concatenate([[0], episodes])
    for lo, hi, mean in zip(edges[:-1], edges[1:], means, strict=True):
        assert mean == pytest.approx(values[lo:hi].mean(), abs=1e-9)
    # Re-bucketed, the means stay exact (buckets are weighted by their episodes).
    xs, ys = acc.curve(max_points=10)
    assert len(xs) == 10 and xs[-1] == len(values)
    edges = np.concatenate([[0], xs])
    for lo, hi, mean in zip(edges[:-1], edges[1:], ys, strict=True):
        assert mean == pytest.approx(values[lo:hi].mean(), abs=1e-9)


def test_accumulator_short_run_keeps_every_episode() -> None:
    acc = CurveAccumulator(capacity=8, first_episode=5)
    acc.extend(np.array([1.0, 2.0, 3.0]))
    episodes, values = acc.curve()
    assert episodes.tolist() == [5, 6, 7]
    assert values.tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError):
        CurveAccumulator(capacity=7)
