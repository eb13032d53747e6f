"""Tests for `tui_gym.games.gridworld.paths`: shortest paths and policy checks against
open-grid references."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tui_gym  # noqa: F401  (registers the GridWorld ids)
from tests.gridworld_support import (
    all_pairs,
    optimal_actions,
    optimal_pair_fraction,
    shortest_path_length,
    shortest_path_policy,
)

RIGHT, UP, LEFT, DOWN = 0, 1, 2, 3
# The tutorial's moves, written out independently of the module under test.
MOVES = {RIGHT: (1, 0), UP: (0, 1), LEFT: (-1, 0), DOWN: (0, -1)}


def constant_policy(size: int, action: int) -> np.ndarray:
    return np.full((size,) * 4, action, dtype=np.int64)


def brute_force_fraction(size: int, policy: np.ndarray) -> float:
    """One placement at a time, step by step, stopping on arrival."""
    hits = total = 0
    for ax in range(size):
        for ay in range(size):
            for tx in range(size):
                for ty in range(size):
                    if (ax, ay) == (tx, ty):
                        continue
                    total += 1
                    x, y, steps = ax, ay, 0
                    while (x, y) != (tx, ty) and steps < 4 * size:
                        dx, dy = MOVES[int(policy[x, y, tx, ty])]
                        x, y = min(max(x + dx, 0), size - 1), min(max(y + dy, 0), size - 1)
                        steps += 1
                    hits += (x, y) == (tx, ty) and steps == abs(tx - ax) + abs(ty - ay)
    return hits / total


# -- shortest paths -----------------------------------------------------------


def test_shortest_path_length_is_manhattan() -> None:
    assert shortest_path_length((0, 0), (2, 3)) == 5
    assert shortest_path_length(np.array([4, 1]), np.array([1, 4])) == 6
    assert shortest_path_length([2, 2], [2, 2]) == 0


@pytest.mark.parametrize(
    ("agent", "target", "expected"),
    [
        ((0, 0), (2, 3), (RIGHT, UP)),
        ((3, 3), (1, 3), (LEFT,)),
        ((2, 2), (0, 0), (LEFT, DOWN)),
        ((1, 4), (1, 0), (DOWN,)),
        ((4, 0), (0, 4), (UP, LEFT)),
        ((2, 2), (2, 2), ()),
    ],
)
def test_optimal_actions_by_hand(
    agent: tuple[int, int], target: tuple[int, int], expected: tuple[int, ...]
) -> None:
    assert optimal_actions(agent, target) == expected
    assert optimal_actions(np.array(agent), np.array(target)) == expected


def test_every_optimal_action_shortens_the_path_and_no_other_does() -> None:
    size = 4
    for ax, ay, tx, ty in all_pairs(size):
        d = shortest_path_length((ax, ay), (tx, ty))
        for action, (dx, dy) in MOVES.items():
            moved = (min(max(ax + dx, 0), size - 1), min(max(ay + dy, 0), size - 1))
            shorter = shortest_path_length(moved, (tx, ty)) == d - 1
            assert shorter == (action in optimal_actions((ax, ay), (tx, ty)))


def test_all_pairs() -> None:
    pairs = all_pairs(3)
    assert pairs.shape == (9 * 8, 4)
    assert len({tuple(row) for row in pairs}) == 72
    assert ((pairs[:, :2] != pairs[:, 2:]).any(axis=1)).all()
    assert pairs.min() == 0 and pairs.max() == 2


# -- optimal_pair_fraction ----------------------------------------------------


@pytest.mark.parametrize("size", [2, 3, 5, 10])
def test_the_shortest_path_policy_is_optimal_everywhere(size: int) -> None:
    policy = shortest_path_policy(size)
    assert optimal_pair_fraction(size, policy) == 1.0
    for ax, ay, tx, ty in all_pairs(size)[:: max(1, size**3 // 50)]:
        assert policy[ax, ay, tx, ty] in optimal_actions((ax, ay), (tx, ty))


def test_always_right_on_a_3x3_grid() -> None:
    # Only a target straight to the right on the agent's row: 3 per row
    # ((0,1), (0,2), (1,2) as x pairs), 3 rows, out of 9 * 8 placements.
    assert optimal_pair_fraction(3, constant_policy(3, RIGHT)) == 9 / 72


def test_bouncing_between_two_cells() -> None:
    # Left unless at x = 0, then right: a target straight to the left on the row
    # is met on a shortest path (3 per row), and from x = 0 a target at x = 1 on
    # the row (1 per row); every other placement bounces forever.
    size = 3
    ax = np.indices((size,) * 4)[0]
    policy = np.where(ax > 0, LEFT, RIGHT)
    assert optimal_pair_fraction(size, policy) == (9 + 3) / 72


def test_a_loop_and_a_detour_fail_only_their_own_placements() -> None:
    size = 3
    policy = shortest_path_policy(size)
    # Towards (2, 2): (0, 0) steps right to (1, 0), which steps back left.
    policy[1, 0, 2, 2] = LEFT
    # Towards (1, 0): from (0, 0) go up, right, down: arrives, but in 3 steps, not 1.
    policy[0, 0, 1, 0] = UP
    assert policy[0, 1, 1, 0] == RIGHT and policy[1, 1, 1, 0] == DOWN
    # Failing: (0,0)->(2,2), (1,0)->(2,2), (0,0)->(1,0).
    assert optimal_pair_fraction(size, policy) == (72 - 3) / 72
    assert brute_force_fraction(size, policy) == (72 - 3) / 72


def test_walking_into_a_wall_fails() -> None:
    size = 3
    policy = shortest_path_policy(size)
    policy[0, 0, 2, 0] = LEFT  # clipped: stays on (0, 0)
    assert optimal_pair_fraction(size, policy) == 71 / 72


@pytest.mark.parametrize("size", [2, 4, 5])
def test_matches_a_step_by_step_simulation_of_random_policies(size: int) -> None:
    rng = np.random.default_rng(size)
    optimal = shortest_path_policy(size)
    for noise in (1.0, 0.3, 0.05):
        random_actions = rng.integers(0, 4, (size,) * 4)
        policy = np.where(rng.random((size,) * 4) < noise, random_actions, optimal)
        assert optimal_pair_fraction(size, policy) == pytest.approx(
            brute_force_fraction(size, policy), abs=1e-15
        )


def test_validation() -> None:
    policy = shortest_path_policy(3)
    with pytest.raises(ValueError):
        optimal_pair_fraction(3, policy[..., :2])
    with pytest.raises(ValueError):
        optimal_pair_fraction(1, np.zeros((1, 1, 1, 1), dtype=np.int64))
    for bad in (4, -1):
        broken = policy.copy()
        broken[0, 0, 2, 2] = bad
        with pytest.raises(ValueError):
            optimal_pair_fraction(3, broken)
    with pytest.raises(ValueError):
        optimal_pair_fraction(3, policy.astype(np.float64))
    # Entries where the agent stands on the target are never read.
    unused = policy.copy()
    for x in range(3):
        for y in range(3):
            unused[x, y, x, y] = 99
    assert optimal_pair_fraction(3, unused) == 1.0


# -- against the real environment ---------------------------------------------


def test_the_env_takes_the_manhattan_number_of_steps() -> None:
    size = 5
    policy = shortest_path_policy(size)
    env = gym.make("tui_gym/GridWorld-v0", size=size)
    for seed in range(30):
        obs, _ = env.reset(seed=seed)
        expected = shortest_path_length(obs["agent"], obs["target"])
        steps, terminated = 0, False
        while not terminated:
            ax, ay = obs["agent"]
            tx, ty = obs["target"]
            obs, _, terminated, truncated, _ = env.step(int(policy[ax, ay, tx, ty]))
            steps += 1
            assert not truncated and steps <= expected
        assert steps == expected
    env.close()
