"""Exact answers for GridWorld, with walls or without: its model and optimum, shortest paths,
and how often a policy takes one."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp import FiniteMDP, Solution, solve
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.envs.gridworld import Walls, cell_distances, cell_moves, free_cells

__all__ = [
    "fewest_share", "gridworld_model", "gridworld_optimum", "path_figures",
    "placements", "shortest_marks", "shortest_path_optimum",
]

_SETTLED = 1e-13  # a change in the chance of arriving smaller than this is no change
_NO_LIMIT = 1_000_000  # steps: far past where any chance left to arrive still counts


@lru_cache(maxsize=8)
def gridworld_model(
    size: int, reward_scale: float, step_penalty: float, changes: GameChanges, walls: Walls = (),
) -> FiniteMDP:
    """The model of a `size` x `size` GridWorld with `walls` as the wrappers in `changes`
    make it."""
    cells = size * size
    agent, target = np.divmod(np.arange(cells * cells), cells)  # [S]: cell numbers x*size+y
    moved = cell_moves(size, walls)[:, agent].T  # [S, A]: the agent's cell after each move
    next_state = moved * cells + target[:, None]
    distance = cell_distances(size, walls)[moved, target[:, None]]
    terminal = moved == target[:, None]
    # Each distinct (bare reward, distance) passes once through the wrappers' own code.
    miss = 0.0 - float(step_penalty)
    reward = np.empty(distance.shape)
    for d in np.unique(distance):
        base = float(reward_scale) if d == 0 else miss
        reward[distance == d] = changes.reward(base, float(d))
    free = free_cells(size, walls)
    start = free[agent] & free[target] & (agent != target)
    return FiniteMDP(
        next_state=next_state[..., None], prob=np.ones(next_state.shape + (1,)),
        reward=reward[..., None], terminal=terminal[..., None], initial=start / start.sum(),
        horizon=changes.time_limit,
    )


@lru_cache(maxsize=8)
def gridworld_optimum(
    size: int, reward_scale: float, step_penalty: float, changes: GameChanges, walls: Walls = (),
) -> Solution:
    """The optimum of `gridworld_model` with the same arguments (kept)."""
    return solve(gridworld_model(size, reward_scale, step_penalty, changes, walls))


def shortest_path_optimum(
    size: int, reward_scale: float, step_penalty: float, limit: int, walls: Walls = ()
) -> tuple[np.ndarray, float] | None:
    """`(q, value)` of `gridworld_optimum` with no wrappers but a `limit`, where a shortest
    path pays (`reward_scale` > 0, `step_penalty` >= 0; None elsewhere): a walk of d steps
    returns `reward_scale - step_penalty * (d - 1)`, one walled off `-step_penalty * limit`."""
    cells = size * size
    distance = cell_distances(size, walls)
    if reward_scale <= 0.0 or step_penalty < 0.0 or distance.max() >= limit:
        return None
    agent, target = np.divmod(np.arange(cells * cells), cells)
    after = distance[cell_moves(size, walls)[:, agent].T, target[:, None]]  # [S, A]
    parted = -float(step_penalty) * limit
    q = np.where(after >= 0, float(reward_scale) - float(step_penalty) * after, parted)
    free = free_cells(size, walls)
    start = free[agent] & free[target] & (agent != target)
    return q, float(q.max(axis=1)[start].mean())


@lru_cache(maxsize=8)
def placements(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells, cells]`: the (agent, target) pairs an episode can start from and end."""
    out = cell_distances(size, walls) > 0
    out.setflags(write=False)
    return out


@lru_cache(maxsize=8)
def shortest_marks(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells * cells, 4]`: whether each action starts a shortest path."""
    distance = cell_distances(size, walls)
    moves = cell_moves(size, walls)
    marks = np.stack([(distance[moves[a]] >= 0) & (distance[moves[a]] == distance - 1)
                      & (distance > 0) for a in range(4)], axis=-1)
    marks = marks.reshape(-1, 4)
    marks.setflags(write=False)
    return marks


def _walk_arrays(size: int, walls: Walls, probabilities: np.ndarray) -> tuple[
        np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """The cells' distances, moves and placements, and each move's probability array."""
    cells = size * size
    probs = np.asarray(probabilities, dtype=np.float64).reshape(cells, cells, 4)
    return (cell_distances(size, walls), cell_moves(size, walls), placements(size, walls),
            [np.ascontiguousarray(probs[..., a]) for a in range(4)])


def fewest_share(size: int, walls: Walls, probabilities: np.ndarray) -> float:
    """The share of placements a policy (action probabilities per (agent cell, target
    cell)) solves in the fewest steps, exactly, filled in by distance (NaN: no placements)."""
    distance, moves, valid, weights = _walk_arrays(size, walls, probabilities)
    if not valid.any():
        return float("nan")
    cells = size * size
    marks = shortest_marks(size, walls).reshape(cells, cells, 4)
    chance = np.eye(cells, dtype=np.float64)
    for d in range(1, int(distance.max()) + 1):
        at = distance == d
        step = np.zeros((cells, cells))
        for a in range(4):
            step += weights[a] * marks[..., a] * chance[moves[a]]
        chance[at] = step[at]
    return float(chance[valid].mean())


def path_figures(
    size: int, walls: Walls, probabilities: np.ndarray, max_steps: int | None = None
) -> tuple[float, float, float]:
    """`(fewest_share, mean steps over the fewest of the walks that arrive, share that
    arrives)` of a policy, exactly: with `h_k` the chance to arrive within k steps (at most
    `max_steps`), walks arriving within L take `L h_L - sum_{k<L} h_k` steps."""
    distance, moves, valid, weights = _walk_arrays(size, walls, probabilities)
    if not valid.any():
        return float("nan"), float("nan"), 0.0
    fewest = fewest_share(size, walls, probabilities)
    cells = size * size
    on_target = np.eye(cells, dtype=bool)
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
