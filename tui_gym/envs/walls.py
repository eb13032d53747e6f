"""Moves and shortest distances on GridWorld's square grid, with walls."""

from __future__ import annotations

from collections.abc import Iterable
from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt

__all__ = ["DELTAS", "Walls", "cell_distances", "cell_moves", "check_walls", "free_cells"]

Walls = tuple[tuple[int, int], ...]
IntArray = npt.NDArray[np.int64]

DELTAS = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)  # right, up, left, down
DELTAS.setflags(write=False)


def check_walls(size: int, walls: Iterable[Any] | None) -> Walls:
    """The walls as sorted `(x, y)` pairs without repeats; `ValueError` for a cell off the
    grid, a pair that is not two integers, or walls that leave fewer than two free cells."""
    out: set[tuple[int, int]] = set()
    for wall in walls or ():
        array = np.asarray(wall)
        if array.shape != (2,) or not np.issubdtype(array.dtype, np.integer):
            raise ValueError(f"a GridWorld wall must be two integers (x, y), got {wall!r}")
        x, y = int(array[0]), int(array[1])
        if not (0 <= x < size and 0 <= y < size):
            raise ValueError(f"wall ({x}, {y}) is off the {size}x{size} grid")
        out.add((x, y))
    if size * size - len(out) < 2:
        raise ValueError(f"walls leave {size * size - len(out)} free cell(s); the agent and "
                         "the target need two")
    return tuple(sorted(out))


def free_cells(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells]`: whether each cell is free (not a wall)."""
    free = np.ones(size * size, dtype=bool)
    for x, y in walls:
        free[x * size + y] = False
    return free


@lru_cache(maxsize=16)
def cell_moves(size: int, walls: Walls = ()) -> IntArray:
    """`[4, cells]`: where each action leads from each cell (blocked moves stay put)."""
    cells = size * size
    x, y = np.divmod(np.arange(cells), size)
    free = free_cells(size, walls)
    moves = np.empty((4, cells), dtype=np.int64)
    for a, (dx, dy) in enumerate(DELTAS.tolist()):
        to = np.clip(x + dx, 0, size - 1) * size + np.clip(y + dy, 0, size - 1)
        moves[a] = np.where(free[to], to, np.arange(cells))
    moves.setflags(write=False)
    return moves


@lru_cache(maxsize=16)
def cell_distances(size: int, walls: Walls = ()) -> IntArray:
    """`[cells, cells]`: the fewest moves from a cell (row) to a cell (column); -1 where
    there is no way (either is a wall, or walls part them)."""
    cells = size * size
    free = free_cells(size, walls)
    if not walls:
        x, y = np.divmod(np.arange(cells), size)
        manhattan = np.abs(x[:, None] - x[None, :]) + np.abs(y[:, None] - y[None, :])
        manhattan = manhattan.astype(np.int64)
        manhattan.setflags(write=False)
        return manhattan
    moves = cell_moves(size, walls)
    distance = np.full((cells, cells), -1, dtype=np.int64)
    frontier = np.diag(free)  # [cell, target]: at the distance of the last round
    distance[frontier] = 0
    step = 0
    while frontier.any():
        step += 1
        reached = frontier[moves[0]] | frontier[moves[1]] | frontier[moves[2]] | frontier[moves[3]]
        frontier = reached & (distance < 0) & free[:, None]
        distance[frontier] = step
    distance.setflags(write=False)
    return distance
