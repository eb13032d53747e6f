"""Draws read from blocks of a generator's raw output are the generator's own draws."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.experiments.block_draws import block_draws


@pytest.mark.parametrize("high", [4, 3, 2**31 + 1, 1])  # 2**31 + 1: Lemire rejects half the time
@pytest.mark.parametrize("bits", [np.random.PCG64, np.random.MT19937])
def test_the_same_numbers_in_any_order_and_the_generator_left_where_they_leave_it(
    high: int, bits: type[np.random.BitGenerator]
) -> None:
    plan = np.random.default_rng(high).integers(0, 40, size=(200, 2))
    expected, mine = np.random.Generator(bits(7)), np.random.Generator(bits(7))
    expected.integers(5), mine.integers(5)  # numpy keeps half an output between integers
    draws = block_draws(mine, high, block=64)
    for kind, k in plan.tolist():
        if kind % 2:
            theirs, ours = expected.random(k), draws.doubles(k)
        else:
            theirs, ours = expected.integers(high, size=k), draws.integers(k)
        assert theirs.tobytes() == ours.tobytes()
    draws.close()
    assert expected.random(3).tobytes() == mine.random(3).tobytes()
    assert expected.integers(high, size=3).tobytes() == mine.integers(high, size=3).tobytes()


def test_a_block_holds_no_more_than_it_needs_when_no_integer_is_drawn() -> None:
    draws = block_draws(np.random.default_rng(0), 4, block=64)
    draws.integers(1)  # a kept half from the first output
    for _ in range(100):
        draws.doubles(40)
    assert draws.size <= 64 + 40
