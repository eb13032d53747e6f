"""Aggregation over seeds: t quantiles, means and bands by hand, smoothing, downsampling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tui_gym.core.experiments.aggregate import (
    aggregate,
    mean_return_last,
    mean_with_ci,
    rolling_mean,
    t_cdf,
    t_half_width,
    t_quantile,
)

# t(0.975, df) from the standard tables.
T_975 = {1: 12.706, 2: 4.303, 3: 3.182, 5: 2.571, 10: 2.228, 30: 2.042, 100: 1.984}


@pytest.mark.parametrize(("df", "expected"), sorted(T_975.items()))
def test_t_quantile_matches_the_tables(df: int, expected: float) -> None:
    assert t_quantile(0.975, df) == pytest.approx(expected, abs=1e-3)


def test_t_quantile_more_digits_and_other_levels() -> None:
    assert t_quantile(0.975, 1) == pytest.approx(12.7062047, abs=1e-6)
    assert t_quantile(0.975, 5) == pytest.approx(2.5705818, abs=1e-6)
    assert t_quantile(0.995, 10) == pytest.approx(3.1692727, abs=1e-6)
    assert t_quantile(0.95, 4) == pytest.approx(2.1318468, abs=1e-6)
    assert t_quantile(0.025, 10) == pytest.approx(-2.2281389, abs=1e-6)
    assert t_quantile(0.5, 7) == 0.0
    # Large df tends to the normal quantile.
    assert t_quantile(0.975, 1e7) == pytest.approx(1.959964, abs=1e-5)


@pytest.mark.parametrize("df", [1, 2, 3, 4, 7, 25, 250, 999, 1500])
@pytest.mark.parametrize("p", [0.6, 0.9, 0.975, 0.999, 1 - 1e-8])
def test_t_quantile_inverts_the_cdf(df: int, p: float) -> None:
    assert t_cdf(t_quantile(p, df), df) == pytest.approx(p, abs=1e-10)


def test_t_cdf_closed_forms() -> None:
    # df = 1 is the Cauchy distribution; df = 2 has F(t) = 1/2 + t / (2 sqrt(t^2 + 2)).
    for t in (-3.0, -0.5, 0.0, 0.7, 4.0):
        assert t_cdf(t, 1) == pytest.approx(0.5 + math.atan(t) / math.pi, abs=1e-12)
        assert t_cdf(t, 2) == pytest.approx(0.5 + t / (2 * math.sqrt(t * t + 2)), abs=1e-12)


def test_t_quantile_rejects_bad_input() -> None:
    with pytest.raises(ValueError):
        t_quantile(1.0, 3)
    with pytest.raises(ValueError):
        t_quantile(0.9, 0)


def test_two_seeds_by_hand() -> None:
    # Columns: (1, 3), (2, 6), (4, 4). Sample std (ddof 1): sqrt(2), 2 sqrt(2), 0.
    # Half-width t(0.975, 1) * s / sqrt(2) = 12.7062 * (1, 2, 0).
    result = aggregate([[1.0, 2.0, 4.0], [3.0, 6.0, 4.0]])
    assert result.seeds == 2
    assert result.episodes.tolist() == [1, 2, 3]
    assert result.mean.tolist() == [2.0, 4.0, 4.0]
    assert result.half_width is not None and result.lo is not None and result.hi is not None
    t = 12.706204736
    assert result.half_width == pytest.approx([t, 2 * t, 0.0], abs=1e-6)
    assert result.lo == pytest.approx([2 - t, 4 - 2 * t, 4.0], abs=1e-6)
    assert result.hi == pytest.approx([2 + t, 4 + 2 * t, 4.0], abs=1e-6)


def test_three_seeds_by_hand() -> None:
    # Values 1, 2, 6: mean 3, s^2 = (4 + 1 + 9) / 2 = 7, half = 4.302653 * sqrt(7) / sqrt(3).
    result = aggregate(np.array([[1.0], [2.0], [6.0]]), episodes=np.array([10]))
    assert result.episodes.tolist() == [10]
    assert result.mean.tolist() == [3.0]
    assert result.half_width is not None
    assert result.half_width[0] == pytest.approx(4.302653 * math.sqrt(7 / 3), abs=1e-5)
    assert result.points()[0].to_json() == {
        "episode": 10,
        "mean": 3.0,
        "lo": pytest.approx(3 - 6.5725, abs=1e-3),
        "hi": pytest.approx(3 + 6.5725, abs=1e-3),
    }


def test_one_seed_has_no_band() -> None:
    result = aggregate([[1.0, 2.0, 3.0]])
    assert result.seeds == 1
    assert result.half_width is None and result.lo is None and result.hi is None
    assert [p.to_json() for p in result.points()][0] == {
        "episode": 1,
        "mean": 1.0,
        "lo": None,
        "hi": None,
    }
    assert [c.name for c in result.as_curves("return")] == ["return"]
    estimate = mean_with_ci([0.25])
    assert estimate.mean == 0.25 and estimate.ci95 is None and estimate.seeds == 1


def test_band_curves_are_named_after_the_mean() -> None:
    result = aggregate([[0.0, 1.0], [2.0, 3.0]])
    curves = result.as_curves("return")
    assert [c.name for c in curves] == ["return", "return.lo", "return.hi"]
    assert curves[1].values.tolist() == pytest.approx((result.mean - result.half_width).tolist())


def test_rolling_mean_is_trailing_with_a_short_start() -> None:
    assert rolling_mean(np.array([1.0, 2.0, 3.0, 4.0, 5.0]), 3).tolist() == [
        1.0,
        1.5,
        2.0,
        3.0,
        4.0,
    ]
    assert rolling_mean(np.array([[2.0, 4.0], [0.0, 0.0]]), 5).tolist() == [[2.0, 3.0], [0.0, 0.0]]
    with pytest.raises(ValueError):
        rolling_mean(np.zeros(3), 0)


def test_smoothing_applies_to_each_seed_before_the_band() -> None:
    # Smoothed seeds: (1, 1.5, 2.5) and (3, 3, 3) -> the band is that of the smoothed values.
    result = aggregate([[1.0, 2.0, 3.0], [3.0, 3.0, 3.0]], window=2)
    assert result.mean.tolist() == [2.0, 2.25, 2.75]
    expected_std = np.array([math.sqrt(2), 1.5 / math.sqrt(2), 0.5 / math.sqrt(2)])
    assert result.half_width == pytest.approx(t_half_width(expected_std, 2), abs=1e-9)


def test_downsampling_keeps_first_and_last_episode() -> None:
    rng = np.random.default_rng(3)
    curves = rng.normal(size=(4, 1000))
    full = aggregate(curves)
    small = aggregate(curves, max_points=500)
    assert len(small) == 500
    assert small.episodes[0] == 1 and small.episodes[-1] == 1000
    assert np.all(np.diff(small.episodes) > 0)
    at = small.episodes - 1  # picked points carry the full curve's values
    assert small.mean.tolist() == full.mean[at].tolist()
    assert full.half_width is not None and small.half_width is not None
    assert small.half_width.tolist() == full.half_width[at].tolist()
    assert len(aggregate(curves[:, :300], max_points=500)) == 300


def test_mean_return_last_uses_the_last_tenth() -> None:
    # 20 episodes: the last 10% is the last 2. Seed means: 5.5, 7.5 -> 6.5;
    # s = sqrt(2), half = 12.7062 * sqrt(2) / sqrt(2).
    curves = np.zeros((2, 20))
    curves[0, -2:] = [5.0, 6.0]
    curves[1, -2:] = [7.0, 8.0]
    curves[:, :-2] = 100.0  # earlier episodes must not count
    estimate = mean_return_last(curves)
    assert estimate.mean == 6.5
    assert estimate.ci95 == pytest.approx(12.706204736, abs=1e-6)
    assert estimate.seeds == 2
    figure = estimate.figure("mean_return_last", "return")
    assert (figure.name, figure.value, figure.unit) == ("mean_return_last", 6.5, "return")
    # Fewer than 10 episodes still use one.
    assert mean_return_last([[1.0, 2.0, 3.0]]).mean == 3.0


def test_bad_curves_are_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        aggregate([[1.0, float("nan")]])
    with pytest.raises(ValueError, match="episode numbers"):
        aggregate([[1.0, 2.0]], episodes=np.array([1, 2, 3]))
    with pytest.raises(ValueError):
        aggregate(np.zeros((0, 3)))
