"""Shared by the GridWorld tests: open-grid references written out on their own (Manhattan
distances, the actions that start a shortest path, every placement) and the share of
placements a policy solves in the fewest steps, through `fewest_share`; a policy's steps
over the fewest, through `path_figures`."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tui_gym.games.gridworld.paths import fewest_share, path_figures


def _xy(position: Sequence[int] | np.ndarray) -> tuple[int, int]:
    x, y = (int(v) for v in np.asarray(position).reshape(2))
    return x, y


def shortest_path_length(
    agent: Sequence[int] | np.ndarray, target: Sequence[int] | np.ndarray
) -> int:
    """The fewest steps from ``agent`` to ``target`` on an open grid: their Manhattan
    distance."""
    (ax, ay), (tx, ty) = _xy(agent), _xy(target)
    return abs(tx - ax) + abs(ty - ay)


def optimal_actions(
    agent: Sequence[int] | np.ndarray, target: Sequence[int] | np.ndarray
) -> tuple[int, ...]:
    """Every action that starts some shortest path on an open grid, ascending; ``()`` at
    the target."""
    (ax, ay), (tx, ty) = _xy(agent), _xy(target)
    return tuple(a for a, toward in enumerate((tx > ax, ty > ay, tx < ax, ty < ay)) if toward)


def all_pairs(size: int) -> np.ndarray:
    """Every start placement: shape ``(size**2 * (size**2 - 1), 4)`` rows of
    ``[agent_x, agent_y, target_x, target_y]`` with agent != target."""
    _check_size(size)
    grid = np.indices((size, size, size, size)).reshape(4, -1).T
    distinct = (grid[:, 0] != grid[:, 2]) | (grid[:, 1] != grid[:, 3])
    return grid[distinct]


def optimal_pair_fraction(size: int, policy: np.ndarray) -> float:
    """The fraction of start placements (agent != target) of an open grid from which
    following ``policy`` (an action per ``(ax, ay, tx, ty)``) reaches the target in the
    fewest steps."""
    return fewest_share(size, (), _one_hot(size, policy))


def mixed_pair_fraction(size: int, probabilities: np.ndarray) -> float:
    """`optimal_pair_fraction` of a policy given as action probabilities, shape
    ``(size,) * 4 + (4,)``: the chance of a shortest walk, averaged over the placements."""
    return fewest_share(size, (), _check_probabilities(size, probabilities))


def shortest_path_policy(size: int) -> np.ndarray:
    """An optimal policy array (int8, ``(size,) * 4``) on an open grid: the
    lowest-numbered optimal action, so horizontal moves first; 0 where agent == target."""
    _check_size(size)
    ax, ay, tx, ty = np.indices((size, size, size, size))
    policy = np.zeros((size,) * 4, dtype=np.int8)
    # Fill in reverse preference order so the preferred action wins.
    policy[ty < ay] = 3
    policy[tx < ax] = 2
    policy[ty > ay] = 1
    policy[tx > ax] = 0
    return policy


def policy_steps_over_optimal(
    size: int, policy: np.ndarray, max_steps: int | None = None
) -> tuple[float, float]:
    """``(mean extra steps, fraction solved)`` of a deterministic ``policy`` over every
    start placement of an open grid (see `path_figures`)."""
    return path_figures(size, (), _one_hot(size, policy), max_steps)[1:]


def mixed_steps_over_optimal(
    size: int, probabilities: np.ndarray, max_steps: int | None = None
) -> tuple[float, float]:
    """`policy_steps_over_optimal` of a policy given as action probabilities, shape
    ``(size,) * 4 + (4,)``."""
    return path_figures(size, (), _check_probabilities(size, probabilities), max_steps)[1:]


def _one_hot(size: int, policy: np.ndarray) -> np.ndarray:
    """A deterministic policy as action probabilities, after checks (entries where the
    agent stands on the target are never read)."""
    _check_size(size)
    pol = np.asarray(policy)
    if pol.shape != (size,) * 4:
        raise ValueError(f"policy must have shape {(size,) * 4}, got {pol.shape}")
    cells = size * size
    actions = np.where(np.eye(cells, dtype=bool), 0, pol.reshape(cells, cells))
    if not np.issubdtype(pol.dtype, np.integer) or actions.min() < 0 or actions.max() > 3:
        raise ValueError("policy actions must be integers in 0..3 wherever agent != target")
    return np.eye(4)[actions]


def _check_probabilities(size: int, probabilities: np.ndarray) -> np.ndarray:
    """The probabilities as (agent cell, target cell, action), after checks."""
    _check_size(size)
    probs = np.asarray(probabilities, dtype=np.float64)
    if probs.shape != (size,) * 4 + (4,):
        raise ValueError(f"probabilities must have shape {(size,) * 4 + (4,)}, got {probs.shape}")
    if (probs < 0).any() or not np.allclose(probs.sum(axis=-1), 1.0):
        raise ValueError("each state's action probabilities must be >= 0 and sum to 1")
    return probs


def _check_size(size: int) -> None:
    if int(size) != size or size < 2:
        raise ValueError(f"size must be an integer >= 2, got {size!r}")
