"""Exact answers for GridWorld: shortest paths, and how often a policy takes one."""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

__all__ = [
    "GRID_ACTION_DELTAS", "all_pairs", "mixed_pair_fraction", "mixed_steps_over_optimal",
    "optimal_actions", "optimal_pair_fraction", "policy_steps_over_optimal", "shortest_path_length",
    "shortest_path_policy",
]

GRID_ACTION_DELTAS = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]], dtype=np.int64)
"""Row ``a``: the (dx, dy) of action ``a`` (right, up, left, down)."""
GRID_ACTION_DELTAS.setflags(write=False)


def _xy(position: Sequence[int] | np.ndarray) -> tuple[int, int]:
    x, y = (int(v) for v in np.asarray(position).reshape(2))
    return x, y


def shortest_path_length(
    agent: Sequence[int] | np.ndarray, target: Sequence[int] | np.ndarray
) -> int:
    """The fewest steps from ``agent`` to ``target``: their Manhattan distance."""
    (ax, ay), (tx, ty) = _xy(agent), _xy(target)
    return abs(tx - ax) + abs(ty - ay)


def optimal_actions(
    agent: Sequence[int] | np.ndarray, target: Sequence[int] | np.ndarray
) -> tuple[int, ...]:
    """Every action that starts some shortest path, ascending; ``()`` at the target."""
    (ax, ay), (tx, ty) = _xy(agent), _xy(target)
    actions = []
    if tx > ax:
        actions.append(0)
    if ty > ay:
        actions.append(1)
    if tx < ax:
        actions.append(2)
    if ty < ay:
        actions.append(3)
    return tuple(actions)


def all_pairs(size: int) -> np.ndarray:
    """Every start placement: shape ``(size**2 * (size**2 - 1), 4)`` rows of
    ``[agent_x, agent_y, target_x, target_y]`` with agent != target."""
    _check_size(size)
    grid = np.indices((size, size, size, size)).reshape(4, -1).T
    distinct = (grid[:, 0] != grid[:, 2]) | (grid[:, 1] != grid[:, 3])
    return grid[distinct]


def shortest_path_policy(size: int) -> np.ndarray:
    """An optimal policy array (int8, ``(size,) * 4``): the lowest-numbered
    optimal action, so horizontal moves first; 0 where agent == target."""
    _check_size(size)
    ax, ay, tx, ty = np.indices((size, size, size, size))
    policy = np.zeros((size,) * 4, dtype=np.int8)
    # Fill in reverse preference order so the preferred action wins.
    policy[ty < ay] = 3
    policy[tx < ax] = 2
    policy[ty > ay] = 1
    policy[tx > ax] = 0
    return policy


def optimal_pair_fraction(size: int, policy: np.ndarray) -> float:
    """The fraction of start placements (agent != target) from which following
    ``policy`` deterministically reaches the target in exactly the Manhattan
    number of steps.

    All placements are simulated at once. Every step changes the distance by at
    most one, so standing on the target after exactly that many steps means
    every step was a shortest-path step and the target was not reached sooner.
    """
    _check_size(size)
    pol = np.asarray(policy)
    if pol.shape != (size,) * 4:
        raise ValueError(f"policy must have shape {(size,) * 4}, got {pol.shape}")
    pairs, distance, walking = _placements_by_distance(int(size))
    used = pol[pairs[:, 0], pairs[:, 1], pairs[:, 2], pairs[:, 3]]
    if not np.issubdtype(pol.dtype, np.integer) or used.min() < 0 or used.max() > 3:
        raise ValueError("policy actions must be integers in 0..3 wherever agent != target")
    agent = pairs[:, :2].copy()
    target = pairs[:, 2:]
    reached = np.zeros(len(pairs), dtype=bool)
    for step in range(1, int(distance[0]) + 1):
        n, done = walking[step], walking[step + 1]  # rows [done, n) arrive now if ever
        here = agent[:n]
        actions = pol[here[:, 0], here[:, 1], target[:n, 0], target[:n, 1]]
        np.clip(here + GRID_ACTION_DELTAS[actions], 0, size - 1, out=here)
        reached[done:n] = (here[done:n] == target[done:n]).all(axis=1)
    return float(reached.mean())


def policy_steps_over_optimal(
    size: int, policy: np.ndarray, max_steps: int | None = None
) -> tuple[float, float]:
    """``(mean extra steps, fraction solved)`` of a deterministic ``policy`` over
    every start placement (agent != target).

    A placement is solved when following ``policy`` reaches the target (within
    ``max_steps`` steps, if given); the mean counts the steps taken beyond the
    Manhattan distance over the solved placements only (NaN when none is
    solved).

    For a fixed target the policy sends each cell to one next cell, so the
    steps to arrive satisfy ``steps[cell] = 1 + steps[next(cell)]``. They are
    filled backwards from the target, one step a round, for every target at
    once; cells caught in a loop are never reached and stay unsolved. Each
    round costs one pass over ``size**4`` entries, and the rounds stop at the
    longest solved walk, so even a poor policy on a 12 x 12 grid takes
    milliseconds.
    """
    _check_size(size)
    size = int(size)
    pol = np.asarray(policy)
    if pol.shape != (size,) * 4:
        raise ValueError(f"policy must have shape {(size,) * 4}, got {pol.shape}")
    cells = size * size
    off_target = ~np.eye(cells, dtype=bool)  # [agent cell, target cell]
    actions = pol.reshape(cells, cells)  # rows: agent x * size + y; columns: target
    used = actions[off_target]
    if not np.issubdtype(pol.dtype, np.integer) or used.min() < 0 or used.max() > 3:
        raise ValueError("policy actions must be integers in 0..3 wherever agent != target")
    x, y = np.divmod(np.arange(cells), size)
    moves = GRID_ACTION_DELTAS[np.where(off_target, actions, 0)]  # (cells, cells, 2)
    nx = np.clip(x[:, None] + moves[..., 0], 0, size - 1)
    ny = np.clip(y[:, None] + moves[..., 1], 0, size - 1)
    following = nx * size + ny  # the cell each (cell, target) moves to
    targets = np.arange(cells)[None, :]
    steps = np.where(off_target, -1, 0)
    frontier = ~off_target  # cells whose steps were set last round
    limit = cells - 1 if max_steps is None else min(cells - 1, int(max_steps))
    for step in range(1, limit + 1):
        frontier = (steps < 0) & frontier[following, targets]
        if not frontier.any():
            break
        steps[frontier] = step
    solved = steps[off_target] >= 0
    if not solved.any():
        return float("nan"), 0.0
    distance = np.abs(x[:, None] - x[None, :]) + np.abs(y[:, None] - y[None, :])
    extra = (steps - distance)[off_target][solved]
    return float(extra.mean()), float(solved.mean())


def mixed_pair_fraction(size: int, probabilities: np.ndarray) -> float:
    """The chance that following a random policy takes a shortest path, averaged
    over every start placement (agent != target): `optimal_pair_fraction` for a
    policy given as action probabilities, shape ``(size,) * 4 + (4,)``.

    Filled in by distance: from a cell at distance d the chance is the sum, over
    the moves that shorten the distance, of the move's probability times the
    chance from where it leads (at distance d - 1).
    """
    size = int(size)
    probs = _check_probabilities(size, probabilities)
    following, shortens, distance = _moves(size)
    cells = size * size
    chance = np.eye(cells)  # rows: the agent's cell; columns: the target's
    weights = [probs[..., a] * shortens[a] for a in range(4)]
    for d in range(1, int(distance.max()) + 1):
        at = distance == d
        step = np.zeros((cells, cells))
        for a in range(4):
            step += weights[a] * chance[following[a]]
        chance[at] = step[at]
    return float(chance[~np.eye(cells, dtype=bool)].mean())


def mixed_steps_over_optimal(
    size: int, probabilities: np.ndarray, max_steps: int | None = None
) -> tuple[float, float]:
    """``(mean extra steps, fraction solved)`` of a random policy, exactly:
    `policy_steps_over_optimal` for a policy given as action probabilities,
    shape ``(size,) * 4 + (4,)``.

    The fraction solved is the chance of reaching the target (within
    ``max_steps`` steps, if given) averaged over every start placement; the
    mean counts the steps beyond the Manhattan distance over the episodes that
    reach it. With ``h_k`` the chance of arriving within k steps (``h_k =
    sum_a p(a) h_{k-1}(next)``, 1 at the target), the expected steps of those
    that arrive within L are ``L h_L - sum_{k<L} h_k``. The walk stops early
    once ``h`` no longer moves (the rest adds nothing); NaN when no placement
    can be solved.
    """
    size = int(size)
    probs = _check_probabilities(size, probabilities)
    following, _, distance = _moves(size)
    cells = size * size
    on_target = np.eye(cells, dtype=bool)
    reach = on_target.astype(np.float64)  # h_0; rows: the agent's cell, columns: the target's
    earlier = np.zeros((cells, cells))  # sum of h_k for k below the current step
    weights = [np.ascontiguousarray(probs[..., a]) for a in range(4)]
    moves = [a for a in range(4) if weights[a].any()]
    nxt, term = np.empty((cells, cells)), np.empty((cells, cells))
    limit = _NO_LIMIT if max_steps is None else int(max_steps)
    k = 0
    while k < limit:
        nxt.fill(0.0)
        for a in moves:  # a row gather: where action a leads, for every target at once
            np.multiply(weights[a], np.take(reach, following[a], axis=0), out=term)
            nxt += term
        nxt[on_target] = 1.0
        earlier += reach
        k += 1
        np.subtract(nxt, reach, out=term)
        moved = float(np.abs(term).max())
        reach, nxt = nxt, reach
        if moved <= _SETTLED:
            break
    steps = k * reach - earlier
    off = ~on_target
    solved = reach[off]
    total = float(solved.sum())
    fraction = float(solved.mean())
    if total <= _SETTLED:
        return float("nan"), 0.0
    extra = float((steps[off] - distance[off] * solved).sum()) / total
    return extra, fraction


_NO_LIMIT = 1_000_000  # steps: far past where any chance left to arrive still counts
_SETTLED = 1e-13  # a change in the chance of arriving smaller than this is no change


def _check_probabilities(size: int, probabilities: np.ndarray) -> np.ndarray:
    """The probabilities as (agent cell, target cell, action), after checks."""
    _check_size(size)
    probs = np.asarray(probabilities, dtype=np.float64)
    if probs.shape != (size,) * 4 + (4,):
        raise ValueError(f"probabilities must have shape {(size,) * 4 + (4,)}, got {probs.shape}")
    if (probs < 0).any() or not np.allclose(probs.sum(axis=-1), 1.0):
        raise ValueError("each state's action probabilities must be >= 0 and sum to 1")
    cells = size * size
    return probs.reshape(cells, cells, 4)


@lru_cache(maxsize=16)
def _moves(size: int) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...], np.ndarray]:
    """Per action, the cell each cell moves to (cells as x * size + y), and whether
    the move shortens the way to each target; and the distance of every
    (agent cell, target cell)."""
    cells = size * size
    x, y = np.divmod(np.arange(cells), size)
    distance = np.abs(x[:, None] - x[None, :]) + np.abs(y[:, None] - y[None, :])
    following, shortens = [], []
    for dx, dy in GRID_ACTION_DELTAS.tolist():
        to = np.clip(x + dx, 0, size - 1) * size + np.clip(y + dy, 0, size - 1)
        following.append(to)
        shortens.append(distance[to, :] < distance)
    for arr in (distance, *following, *shortens):
        arr.setflags(write=False)
    return tuple(following), tuple(shortens), distance


@lru_cache(maxsize=16)
def _placements_by_distance(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`all_pairs` sorted farthest first, their distances, and ``walking[k]``: how
    many placements are at distance >= k (a prefix, so the ones still walking at
    step k are the first ``walking[k]`` rows)."""
    pairs = all_pairs(size)
    distance = np.abs(pairs[:, 2:] - pairs[:, :2]).sum(axis=1)
    order = np.argsort(-distance, kind="stable")
    pairs, distance = pairs[order], distance[order]
    walking = np.searchsorted(-distance, -np.arange(distance.max() + 2), side="right")
    for arr in (pairs, distance, walking):
        arr.setflags(write=False)
    return pairs, distance, walking


def _check_size(size: int) -> None:
    if int(size) != size or size < 2:
        raise ValueError(f"size must be an integer >= 2, got {size!r}")
