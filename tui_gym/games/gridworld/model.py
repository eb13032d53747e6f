"""GridWorld's exact model, so a greedy policy gets an exact expected return."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from tui_gym.core.mdp import FiniteMDP, Solution, solve
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.envs.walls import Walls, cell_distances, cell_moves, free_cells

__all__ = ["gridworld_model", "gridworld_optimum", "shortest_path_optimum"]


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
    """`(q, value)` of `gridworld_optimum` with no wrappers but a time limit of `limit`
    steps, where a shortest path pays (a positive `reward_scale`, no negative
    penalty): an episode that walks the fewest steps d returns
    `reward_scale - step_penalty * (d - 1)`, and one the walls part from its target
    `-step_penalty * limit`. None where that does not hold."""
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
