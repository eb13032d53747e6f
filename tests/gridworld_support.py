"""Shared by the GridWorld tests: open-grid references written out on their own (Manhattan
distances, the actions that start a shortest path, every placement) and the share of
placements a policy solves in the fewest steps, through `fewest_share`."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tui_gym.games.gridworld.paths import _check_probabilities, _check_size, _one_hot, fewest_share


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
