"""GridWorld's exact model, so a greedy policy gets an exact expected return.

States are the (agent, target) placements in the row-major order of the
game's table (`ax, ay, tx, ty`), actions right, up, left, down; a move is
clipped at the walls and ends the episode on the target. Every move has one
outcome, so the model is `[S, 4, 1]`. Episodes start uniformly over the
placements with agent != target (the env's draw-until-different). Rewards are
the env's (`+reward_scale` on the target, `-step_penalty` otherwise) passed
through the wrappers' reward code with the distance after the move, so
`StepPenalty`, `ScaleReward` and `DistanceShaping` are followed exactly; the
episode limit is the tightest `TimeLimit`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from tui_gym.core.mdp import FiniteMDP, Solution, solve
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.envs.gridworld import ACTION_DELTAS

__all__ = ["gridworld_model", "gridworld_optimum"]


@lru_cache(maxsize=8)
def gridworld_model(
    size: int, reward_scale: float, step_penalty: float, changes: GameChanges
) -> FiniteMDP:
    """The model of a `size` x `size` GridWorld as the wrappers in `changes` make it."""
    grid = np.indices((size,) * 4).reshape(4, -1).T  # [S, 4]: ax, ay, tx, ty
    deltas = np.asarray(ACTION_DELTAS, dtype=np.int64)  # [A, 2]
    moved = np.clip(grid[:, None, :2] + deltas[None, :, :], 0, size - 1)  # [S, A, 2]
    target = np.broadcast_to(grid[:, None, 2:], moved.shape)
    next_state = ((moved[..., 0] * size + moved[..., 1]) * size + target[..., 0]) * size
    next_state = next_state + target[..., 1]
    distance = np.abs(moved - target).sum(axis=2)
    terminal = distance == 0
    # Each distinct (bare reward, distance) passes once through the wrappers' own code.
    miss = 0.0 - float(step_penalty)
    reward = np.empty(distance.shape)
    for d in np.unique(distance):
        base = float(reward_scale) if d == 0 else miss
        reward[distance == d] = changes.reward(base, float(d))
    distinct = (grid[:, 0] != grid[:, 2]) | (grid[:, 1] != grid[:, 3])
    initial = distinct / distinct.sum()
    return FiniteMDP(
        next_state=next_state[..., None],
        prob=np.ones(next_state.shape + (1,)),
        reward=reward[..., None],
        terminal=terminal[..., None],
        initial=initial,
        horizon=changes.time_limit,
    )


@lru_cache(maxsize=8)
def gridworld_optimum(
    size: int, reward_scale: float, step_penalty: float, changes: GameChanges
) -> Solution:
    """The optimum of `gridworld_model` with the same arguments (kept)."""
    return solve(gridworld_model(size, reward_scale, step_penalty, changes))
