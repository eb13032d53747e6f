"""Observation keys: turning any observation our envs produce into a table key."""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Iterable, Iterator
from typing import Any

import numpy as np
from gymnasium import spaces

# Above this many states a dense table is not worth it: keys go sparse.
DENSE_STATE_LIMIT = 2_000_000
# Float leaves are rounded to this many decimals to form keys.
FLOAT_DECIMALS = 6
# A float Box wider than this is not a table (e.g. an image).
MAX_SPARSE_WIDTH = 4096


class NotTabularError(ValueError):
    """The observation space cannot be used as the keys of a table."""


Range = tuple[np.ndarray, np.ndarray]  # an integer leaf's lowest values and counts, int64 flat


def _parts(space: spaces.Tuple | spaces.Dict) -> Iterable[tuple[Any, spaces.Space]]:
    """A Tuple's (index, space) or a Dict's (name, space) pairs, in order."""
    return space.spaces.items() if isinstance(space, spaces.Dict) else enumerate(space.spaces)


def _leaves(space: spaces.Space, path: str = "observation") -> list[tuple[spaces.Space, str]]:
    if isinstance(space, spaces.Tuple | spaces.Dict):
        return [leaf for key, sub in _parts(space) for leaf in _leaves(sub, f"{path}[{key!r}]")]
    if isinstance(space, spaces.Discrete | spaces.MultiDiscrete | spaces.MultiBinary | spaces.Box):
        return [(space, path)]
    raise NotTabularError(
        f"{path} is a {type(space).__name__} space; a Q-table needs Discrete, "
        "MultiDiscrete, MultiBinary, Box, or Tuple/Dict of those"
    )


def _dense_leaf(space: spaces.Space) -> Range | None:
    """The integer range of a leaf, or None when it is not bounded integers."""
    if isinstance(space, spaces.Discrete):
        return np.array([int(space.start)]), np.array([int(space.n)])
    if isinstance(space, spaces.MultiDiscrete):
        starts = np.asarray(space.start, dtype=np.int64).ravel()
        return starts, np.asarray(space.nvec, dtype=np.int64).ravel()
    if isinstance(space, spaces.MultiBinary):
        n = int(np.prod(space.shape))
        return np.zeros(n, dtype=np.int64), np.full(n, 2, dtype=np.int64)
    if isinstance(space, spaces.Box) and space.dtype.kind in "iub":  # integers or bools
        if not space.is_bounded("both"):
            return None
        # Python ints (int64 overflows near the dtype's limits); a radix capped just past the
        # dense limit keeps such spaces sparse without changing any dense key.
        lows = np.asarray(space.low).ravel().tolist()
        highs = np.asarray(space.high).ravel().tolist()
        radix = [min(h - lo + 1, DENSE_STATE_LIMIT + 1) for lo, h in zip(lows, highs, strict=True)]
        return np.array(lows, dtype=np.int64), np.array(radix, dtype=np.int64)
    return None


def _leaf_flattener(space: spaces.Space) -> Callable[[Any], list[Hashable]]:
    if isinstance(space, spaces.Discrete):
        return lambda x: [int(x)]
    if isinstance(space, spaces.Box) and space.dtype.kind == "f":

        def floats(x: Any) -> list[Hashable]:
            arr = np.round(np.asarray(x, dtype=np.float64).ravel(), FLOAT_DECIMALS)
            return [round(v, FLOAT_DECIMALS) + 0.0 for v in arr.tolist()]  # -0.0 is 0.0

        return floats
    return lambda x: [int(v) for v in np.asarray(x).ravel().tolist()]


def _shaped(space: spaces.Space, values: Iterator[int]) -> Any:
    """An observation of `space` from its flat values (`_flattener`'s order)."""
    if isinstance(space, spaces.Tuple):
        return tuple(_shaped(sub, values) for sub in space.spaces)
    if isinstance(space, spaces.Dict):
        return {name: _shaped(sub, values) for name, sub in space.spaces.items()}
    if isinstance(space, spaces.Discrete):
        return next(values)
    shape = space.shape or ()
    flat = [next(values) for _ in range(int(np.prod(shape)))]
    return np.array(flat, dtype=space.dtype).reshape(shape)


def _flattener(space: spaces.Space) -> Callable[[Any], list[Hashable]]:
    """A function giving every scalar of an observation, in space order, as Python numbers."""
    if isinstance(space, spaces.Tuple) and all(
        isinstance(sub, spaces.Discrete) for sub in space.spaces
    ):
        return lambda obs: [int(v) for v in obs]
    if isinstance(space, spaces.Tuple | spaces.Dict):
        parts = [(key, _flattener(sub)) for key, sub in _parts(space)]
        return lambda obs: [v for key, part in parts for v in part(obs[key])]
    return _leaf_flattener(space)


class ObservationKeyer:
    """Turns observations of one space into hashable table keys (an `int` in `range(n_states)`
    for dense spaces); `signature` is the same for keyers whose keys mean the same."""

    def __init__(self, space: spaces.Space) -> None:
        self.space = space
        leaves = _leaves(space)
        self._flat = _flattener(space)
        dense = [_dense_leaf(leaf) for leaf, _ in leaves]
        self.signature = repr(space)
        self.n_states: int | None = None
        self._low = np.zeros(0, dtype=np.int64)
        self._strides = np.zeros(0, dtype=np.int64)
        if all(d is not None for d in dense):
            low = np.concatenate([d[0] for d in dense])  # type: ignore[index]
            radix = np.concatenate([d[1] for d in dense])  # type: ignore[index]
            total = math.prod(int(r) for r in radix.tolist())
            if total <= DENSE_STATE_LIMIT:
                self.n_states = total
                self._low = low
                # Row-major: the last element varies fastest.
                self._strides = np.append(np.cumprod(radix[:0:-1])[::-1], 1).astype(np.int64)
                self._low_list = low.tolist()
                self._stride_list = self._strides.tolist()
                return
        for (leaf, path), d in zip(leaves, dense, strict=True):
            if d is None and isinstance(leaf, spaces.Box) and leaf.dtype.kind == "f":
                width = int(np.prod(leaf.shape))
                if width > MAX_SPARSE_WIDTH:
                    raise NotTabularError(
                        f"{path} is a Box of {width} floats; too many for a "
                        f"Q-table (at most {MAX_SPARSE_WIDTH})"
                    )
            elif d is None:
                raise NotTabularError(f"{path} ({leaf}) has no finite range of values")

    @property
    def dense(self) -> bool:
        """True when keys are integers in `range(n_states)`."""
        return self.n_states is not None

    def key(self, obs: Any) -> Hashable:
        """The table key of one observation."""
        values = self._flat(obs)
        if self.n_states is None:
            return tuple(values)
        index = 0
        for v, lo, stride in zip(values, self._low_list, self._stride_list, strict=True):
            index += (v - lo) * stride
        return index

    def keys(self, observations: np.ndarray) -> np.ndarray:
        """Dense keys for a batch: `observations` is (batch, n_elements) integers."""
        if self.n_states is None:
            raise NotTabularError("batched keys need a dense (all-integer) observation space")
        obs = np.asarray(observations, dtype=np.int64)
        return (obs - self._low) @ self._strides

    def decode(self, index: int) -> tuple[int, ...]:
        """The flat observation values behind a dense key."""
        if self.n_states is None:
            raise NotTabularError("only dense keys can be decoded")
        rest = int(index)
        out = []
        for stride, lo in zip(self._stride_list, self._low_list, strict=True):
            digit, rest = divmod(rest, stride)
            out.append(digit + lo)
        return tuple(out)

    def observation(self, index: int) -> Any:
        """The observation behind a dense key, shaped as its space gives one."""
        return _shaped(self.space, iter(self.decode(index)))

    def __repr__(self) -> str:
        kind = f"dense, {self.n_states} states" if self.dense else "sparse"
        return f"ObservationKeyer({kind}, {self.signature})"
