"""The bytes of stored curves: float16 scaled by a power of two, episodes as gaps."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.experiments.codec import (
    CurveFormatError,
    decode_curve,
    encode_curve,
    pack_curves,
    unpack_curves,
)


@pytest.mark.parametrize("scale", [1e-9, 1e-3, 1.0, 250.0, 1e6, 1e12])
def test_values_keep_float16_precision_at_any_scale(scale: float) -> None:
    rng = np.random.default_rng(1)
    values = scale * rng.uniform(-1, 1, size=100)
    episodes = np.arange(1, 101) * 7
    xs, ys = decode_curve(encode_curve(episodes, values))
    assert xs.tolist() == episodes.tolist()
    top = np.abs(values).max()
    # Relative error 2**-11 for values near the top, absolute 2**-11 * top below.
    assert np.all(np.abs(ys - values) <= 2**-11 * np.maximum(np.abs(values), top * 2**-14))


def test_a_learning_curve_with_a_wide_range_keeps_its_tail() -> None:
    # A cliff-walking-like curve: early returns near -2000, late near -17 and -25.
    values = np.array([-2000.0, -500.0, -60.0, -25.0, -17.0, -17.25])
    _, ys = decode_curve(encode_curve(np.arange(6), values))
    assert ys[3:].tolist() == pytest.approx([-25.0, -17.0, -17.25], abs=0.01)


def test_nan_zero_and_uneven_episodes_survive() -> None:
    episodes = np.array([0, 1, 5, 6, 100, 10_000, 10_001])
    values = np.array([0.0, np.nan, 0.5, -0.25, 0.0, 3.0, np.nan])
    xs, ys = decode_curve(encode_curve(episodes, values))
    assert xs.tolist() == episodes.tolist()
    assert np.array_equal(ys, values, equal_nan=True)
    xs, ys = decode_curve(encode_curve(np.array([], dtype=np.int64), np.array([])))
    assert len(xs) == len(ys) == 0
    xs, ys = decode_curve(encode_curve(np.array([-3]), np.array([np.nan])))
    assert xs.tolist() == [-3] and np.isnan(ys[0])


def test_even_episodes_cost_a_few_bytes() -> None:
    data = encode_curve(np.arange(1, 101) * 1000, np.zeros(100))
    assert len(data) <= 2 * 100 + 12


def test_several_curves_in_one_blob() -> None:
    curves = {"return": b"\x01abc", "length": b"", "é": bytes(300)}
    assert unpack_curves(pack_curves(curves)) == curves
    assert unpack_curves(pack_curves({})) == {}


@pytest.mark.parametrize(
    "data", [b"", b"\x07", b"\x01\x05", b"\x01\x02\x09\x00", b"\x01\x01\x00\x01\x02\x00\x00"]
)
def test_damaged_bytes_are_refused(data: bytes) -> None:
    with pytest.raises(CurveFormatError):
        decode_curve(data)


def test_damaged_blob_is_refused() -> None:
    blob = pack_curves({"return": bytes(10)})
    with pytest.raises(CurveFormatError):
        unpack_curves(blob[:-1])
    with pytest.raises(CurveFormatError):
        unpack_curves(blob + b"x")
