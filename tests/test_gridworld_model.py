"""GridWorld's exact model: the expected return of a policy, worked out by hand on a 2x2 grid."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.wrappers import parse_wrapper_spec
from tui_gym.session.session import Session

RIGHT = 0


def _always_right() -> np.ndarray:
    """A table whose greedy move is right in every placement (16 on a 2x2 grid)."""
    q = np.zeros((16, 4))
    q[:, RIGHT] = 1.0
    return q


@pytest.mark.parametrize(
    ("params", "wrappers", "value", "optimum", "note"),
    [
        # Of the 12 placements (agent != target) moving right reaches the target
        # only from the left cell of the target's row: 2 of 12, one step, +1.
        ({}, (), 2 / 12, 1.0, ""),
        # The other 10 walk into the wall for the whole 300-step limit at -0.1 a
        # step. The optimum: 8 placements one step away (+1), 4 diagonal (-0.1 + 1).
        ({"step_penalty": 0.1}, (), (2 * 1.0 + 10 * 300 * -0.1) / 12, (8 + 4 * 0.9) / 12, ""),
        # ScaleReward doubles every reward, TimeLimit cuts the walk at 20 steps.
        ({"step_penalty": 0.1}, ("ScaleReward:factor=2", "TimeLimit:max_episode_steps=20"),
         (2 * 2.0 + 10 * 20 * -0.2) / 12, 2 * (8 + 4 * 0.9) / 12, ""),
        # Negated, the target costs 1: the optimum stays off it (bumping into a wall),
        # and the shortest-path figures say they are the unwrapped game's.
        ({}, ("ScaleReward:factor=-1",), -2 / 12, 0.0,
         "; the exact value and gap are with ScaleReward(factor=-1)"),
    ],
)
def test_exact_value_of_always_right_on_a_2x2_grid(
    params: dict[str, float], wrappers: tuple[str, ...], value: float, optimum: float,
    note: str,
) -> None:
    session = Session(env_id="tui_gym/GridWorld-v0", env_kwargs={"size": 2, **params},
                      choices=tuple(parse_wrapper_spec(w) for w in wrappers), seed=0)
    reference = session.game.oracle.evaluation_reference(
        _always_right(), session.env_kwargs, session.changes
    )
    figures = reference.figures  # type: ignore[union-attr]
    assert figures["exact_value"] == pytest.approx(value, abs=1e-12)
    assert figures["optimal_value"] == pytest.approx(optimum, abs=1e-12)
    assert figures["gap"] == pytest.approx(optimum - value, abs=1e-12)
    assert reference.scope.exact == (not note)  # type: ignore[union-attr]
    assert reference.scope.note.endswith(note)  # type: ignore[union-attr]


def test_walls_block_moves_and_part_placements_in_the_exact_value() -> None:
    # A wall down the middle column of a 3x3 grid leaves two columns of three free
    # cells: 30 placements on different free cells, 12 of them in one column, where
    # the optimum reaches the target (+1); across the wall nothing ever does. Always
    # moving up reaches it only from below: 3 placements a column, 6 of 30.
    session = Session(env_id="tui_gym/GridWorld-v0",
                      env_kwargs={"size": 3, "walls": [[1, 0], [1, 1], [1, 2]]}, seed=0)
    always_up = np.zeros((81, 4))
    always_up[:, 1] = 1.0
    reference = session.game.oracle.evaluation_reference(
        always_up, session.env_kwargs, session.changes
    )
    figures = reference.figures  # type: ignore[union-attr]
    assert figures["optimal_value"] == pytest.approx(12 / 30, abs=1e-12)
    assert figures["exact_value"] == pytest.approx(6 / 30, abs=1e-12)


@pytest.mark.parametrize(
    ("size", "reward_scale", "step_penalty", "walls"),
    [
        (2, 1.0, 0.0, ()),
        (3, 2.5, 0.3, ()),
        (4, 1.0, 0.1, ((1, 1), (1, 2), (2, 1))),
        (4, 0.5, 0.2, ((0, 2), (1, 2), (2, 2), (3, 2))),  # a wall across: parted placements
    ],
)
def test_the_shortest_path_optimum_is_the_model_solved(
    size: int, reward_scale: float, step_penalty: float, walls: tuple
) -> None:
    from tui_gym.core.wrappers.changes import GameChanges
    from tui_gym.envs.gridworld import free_cells
    from tui_gym.games.gridworld.paths import gridworld_optimum, shortest_path_optimum

    found = shortest_path_optimum(size, reward_scale, step_penalty, 300, walls)
    assert found is not None
    q, value = found
    solved = gridworld_optimum(size, reward_scale, step_penalty, GameChanges(time_limit=300),
                               walls)
    assert value == pytest.approx(solved.value)
    free = free_cells(size, walls)
    agent, target = np.divmod(np.arange(size**4), size * size)
    played = free[agent] & free[target] & (agent != target)
    np.testing.assert_allclose(q[played], solved.q[played])
    # A target that costs to reach: no closed form, the model is solved instead.
    assert shortest_path_optimum(size, -1.0, step_penalty, 300, walls) is None


def test_the_optimum_of_gridworld_is_a_return_beside_its_mean_steps() -> None:
    from tui_gym.games import game_for

    game = game_for("gridworld")
    kwargs = game.normalize_kwargs({"size": 3, "reward_scale": -1.0})
    optimum = game.oracle.optimum(kwargs)  # the target costs: the optimum never goes there
    assert optimum.value == pytest.approx(0.0) and optimum.figures["optimal_mean_steps"] == 2.0
    session = Session("gridworld", env_kwargs=kwargs, seed=0)
    reference = session.evaluation_reference()
    assert reference is not None
    assert reference.figures["optimal_value"] == pytest.approx(optimum.value)
