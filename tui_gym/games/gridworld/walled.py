"""Exact answers for GridWorld with walls: shortest paths around them, and how often a
policy takes one.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import numpy.typing as npt

from tui_gym.envs.walls import Walls, cell_distances, cell_moves

__all__ = ["placements", "walled_figures", "walled_marks", "walled_mean_steps"]

_SETTLED = 1e-13  # a change in the chance of arriving smaller than this is no change
_NO_LIMIT = 100_000  # steps: far past where any chance left to arrive still counts


@lru_cache(maxsize=8)
def placements(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells, cells]`: the (agent, target) pairs an episode can start from and end."""
    distance = cell_distances(size, walls)
    out = distance > 0
    out.setflags(write=False)
    return out


@lru_cache(maxsize=8)
def walled_marks(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells * cells, 4]`: whether each action starts a shortest path."""
    distance = cell_distances(size, walls)
    moves = cell_moves(size, walls)
    marks = np.stack([(distance[moves[a]] >= 0) & (distance[moves[a]] == distance - 1)
                      & (distance > 0) for a in range(4)], axis=-1)
    marks = marks.reshape(-1, 4)
    marks.setflags(write=False)
    return marks


def walled_mean_steps(size: int, walls: Walls) -> float:
    """The mean fewest steps over the placements (NaN when there are none)."""
    valid = placements(size, walls)
    if not valid.any():
        return float("nan")
    return float(cell_distances(size, walls)[valid].mean())


def walled_figures(
    size: int, walls: Walls, probabilities: np.ndarray, max_steps: int | None = None
) -> tuple[float, float, float]:
    """`(share solved in the fewest steps, mean steps over the fewest, share solved)`.

    The first is filled in by distance (from a cell at distance d, the chance of
    a shortest walk is the sum over moves that bring the target one step nearer
    of the move's probability times the chance from where it leads); the others
    by the chance `h_k` of arriving within k steps, as `paths` does without walls.
    """
    cells = size * size
    probs = np.asarray(probabilities, dtype=np.float64).reshape(cells, cells, 4)
    distance = cell_distances(size, walls)
    moves = cell_moves(size, walls)
    valid = placements(size, walls)
    if not valid.any():
        return float("nan"), float("nan"), 0.0
    marks = walled_marks(size, walls).reshape(cells, cells, 4)
    weights = [np.ascontiguousarray(probs[..., a]) for a in range(4)]
    on_target = np.eye(cells, dtype=bool)

    chance = on_target.astype(np.float64)
    for d in range(1, int(distance.max()) + 1):
        at = distance == d
        step = np.zeros((cells, cells))
        for a in range(4):
            step += weights[a] * marks[..., a] * chance[moves[a]]
        chance[at] = step[at]
    fewest = float(chance[valid].mean())

    reach = on_target.astype(np.float64)
    earlier = np.zeros((cells, cells))
    limit = _NO_LIMIT if max_steps is None else int(max_steps)
    k = 0
    while k < limit:
        nxt = np.zeros((cells, cells))
        for a in range(4):
            nxt += weights[a] * reach[moves[a]]
        nxt[on_target] = 1.0
        earlier += reach
        k += 1
        moved = float(np.abs(nxt - reach).max())
        reach = nxt
        if moved <= _SETTLED:
            break
    steps = k * reach - earlier
    solved = reach[valid]
    total = float(solved.sum())
    if total <= _SETTLED:
        return fewest, float("nan"), 0.0
    extra = float((steps[valid] - distance[valid] * solved).sum()) / total
    return fewest, extra, float(solved.mean())
