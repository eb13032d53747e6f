"""A generator's `random` and `integers` draws, read from blocks of its raw output.

`block_draws(rng, high)` gives an object whose `doubles(k)` gives what
`rng.random(k)` gives and `integers(k)` what `rng.integers(high, size=k)`
gives, in any order; `close()` leaves `rng` exactly where those calls would
have left it. For the hottest loops, `reserve(k)` makes `k` doubles ready at
`dbl[p:p + k]` (the caller moves `p` on past those it takes).

For numpy's default generator (PCG64) on a little-endian machine the draws
come from blocks of `random_raw`, worked out as numpy works them out: a double
is the top 53 bits of one 64-bit output; an integer below 2**32 takes one
32-bit half (the low half of an output first, the high half kept for the next
integer) by Lemire's method, drawing again when it rejects. That saves the
call overhead of many small draws. Any other generator is called directly.
"""

from __future__ import annotations

import sys
from typing import Any, Protocol

import numpy as np

__all__ = ["Draws", "block_draws"]

_DOUBLE = 1.0 / 9007199254740992.0  # 2**-53
_HALF_MASK = np.uint64(0xFFFFFFFF)


class Draws(Protocol):
    dbl: np.ndarray
    p: int
    size: int

    def reserve(self, k: int) -> None:
        """Make `dbl[p:p + k]` the next `k` doubles."""

    def doubles(self, k: int) -> np.ndarray:
        """`rng.random(k)`."""

    def integers(self, k: int) -> np.ndarray:
        """`rng.integers(high, size=k)`."""

    def integers_into(self, target: np.ndarray, at: np.ndarray) -> None:
        """`target[at] = rng.integers(high, size=len(at))`."""

    def close(self) -> None:
        """Leave the generator where the draws so far would have left it."""


class _Direct:
    """Draws straight from the generator, exactly as many as are asked for."""

    def __init__(self, rng: np.random.Generator, high: int) -> None:
        self.rng = rng
        self.high = high
        self.dbl = np.zeros(0)
        self.p = self.size = 0

    def reserve(self, k: int) -> None:
        self.dbl = np.concatenate((self.dbl[self.p:], self.rng.random(k - (self.size - self.p))))
        self.p, self.size = 0, len(self.dbl)

    def doubles(self, k: int) -> np.ndarray:
        if self.p + k > self.size:
            self.reserve(k)
        p = self.p
        self.p = p + k
        return self.dbl[p:p + k]

    def integers(self, k: int) -> np.ndarray:
        return self.rng.integers(self.high, size=k)

    def integers_into(self, target: np.ndarray, at: np.ndarray) -> None:
        target[at] = self.rng.integers(self.high, size=len(at))

    def close(self) -> None:
        return None


class _Blocks:
    """A PCG64 generator's draws from blocks of its raw output (see the module docstring)."""

    def __init__(self, rng: np.random.Generator, high: int, block: int) -> None:
        self.bits = rng.bit_generator
        self.start: dict[str, Any] = dict(self.bits.state)
        self.high = high
        self.threshold = (1 << 32) % high  # Lemire's method rejects products below it
        self.shift = 33 - high.bit_length()  # for a power of two: 32 - log2(high)
        self.block = block
        # numpy keeps one 32-bit half between integer draws: the last high half kept, and
        # whether it is still unused (-1 when not).
        self.register = int(self.start["uinteger"])
        self.held = self.register if self.start["has_uint32"] else -1
        self.used = 0  # outputs before the block
        self.p = 0  # outputs of the block taken
        self.raw = np.zeros(0, dtype=np.uint64)
        self._refill(block)
        if high > 1 and not self.threshold:  # a power of two: no rejections, no products
            self.integers_into = self._into_power_of_two  # type: ignore[method-assign]

    def _refill(self, need: int) -> None:
        raw = np.concatenate((self.raw[self.p:], self.bits.random_raw(max(self.block, need))))
        self.used += self.p
        self.p = 0
        self.raw = raw
        self.size = len(raw)
        self.dbl = (raw >> 11) * _DOUBLE
        self.halves = raw.view(np.uint32)  # low half first on a little-endian machine

    def reserve(self, k: int) -> None:
        if self.p + k > self.size:
            self._refill(k)

    def doubles(self, k: int) -> np.ndarray:
        if self.p + k > self.size:
            self._refill(k)
        p = self.p
        self.p = p + k
        return self.dbl[p:p + k]

    def integers(self, k: int) -> np.ndarray:
        out = np.zeros(max(k, 0), dtype=np.int64)
        self.integers_into(out, np.arange(len(out)))
        return out

    def integers_into(self, target: np.ndarray, at: np.ndarray) -> None:
        """`target[at] = rng.integers(high, size=len(at))`."""
        k = len(at)
        high = self.high
        if k < 1 or high == 1:  # nothing to draw
            target[at] = 0
            return
        held = self.held
        m = k if held < 0 else k - 1  # halves to take from the outputs not yet taken
        outputs = (m + 1) // 2
        if self.p + outputs > self.size:
            self._refill(outputs)
        start = 2 * self.p
        halves = self.halves[start:start + m]
        threshold = self.threshold
        if threshold:
            products = halves.astype(np.uint64) * np.uint64(high)
            if ((products & _HALF_MASK) < threshold).any() or (
                held >= 0 and held * high & 0xFFFFFFFF < threshold
            ):
                target[at] = self._integers_one_by_one(k)
                return
            drawn = products >> 32
        else:  # a power of two: the top bits of each half
            drawn = halves >> self.shift
        if held >= 0:
            target[at[0]] = held * high >> 32
            at = at[1:]
        target[at] = drawn
        self.p += outputs
        self.held = -1
        if m % 2:  # the last output's high half is kept for the next integer
            self.held = self.register = int(self.halves[start + m])
        elif m:  # it was kept and used
            self.register = int(self.halves[start + m - 1])

    def _into_power_of_two(self, target: np.ndarray, at: np.ndarray) -> None:
        """`integers_into` for `high` a power of two: each integer is a half's top bits."""
        held, shift = self.held, self.shift
        if held >= 0 and len(at):
            target[at[0]] = held >> shift
            at = at[1:]
            self.held = -1
        m = len(at)
        if not m:
            return
        outputs = (m + 1) // 2
        if self.p + outputs > self.size:
            self._refill(outputs)
        start = 2 * self.p
        halves = self.halves
        target[at] = halves[start:start + m] >> shift
        self.p += outputs
        if m % 2:  # the last output's high half is kept for the next integer
            self.held = self.register = int(halves[start + m])
        else:  # it was kept and used
            self.register = int(halves[start + m - 1])

    def _half(self) -> int:
        if self.held >= 0:
            half, self.held = self.held, -1
            return half
        if self.p + 1 > self.size:
            self._refill(1)
        low = 2 * self.p
        self.p += 1
        self.held = self.register = int(self.halves[low + 1])
        return int(self.halves[low])

    def _integers_one_by_one(self, k: int) -> np.ndarray:
        out = np.empty(k, dtype=np.int64)
        for i in range(k):
            product = self._half() * self.high
            while product & 0xFFFFFFFF < self.threshold:  # rejected: draw again
                product = self._half() * self.high
            out[i] = product >> 32
        return out

    def close(self) -> None:
        bits: Any = self.bits  # a PCG64, as `block_draws` checked
        bits.state = self.start
        bits.advance(self.used + self.p)
        state = dict(bits.state)
        state["has_uint32"] = int(self.held >= 0)
        state["uinteger"] = self.register
        bits.state = state


def block_draws(rng: np.random.Generator, high: int, block: int = 1 << 14) -> Draws:
    """Draws of `rng`, integers below `high` (1 to 2**32; see the module docstring);
    `block` outputs are read at a time."""
    if not 1 <= high <= 1 << 32:
        raise ValueError(f"integers below {high} are not drawn from 32-bit halves")
    if type(rng.bit_generator) is np.random.PCG64 and sys.byteorder == "little":
        return _Blocks(rng, high, block)
    return _Direct(rng, high)
