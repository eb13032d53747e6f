"""Sutton & Barto's mazes of chapter 8: the Dyna maze, the blocking and the shortcut maze."""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Sequence
from typing import Any

from tui_gym.envs.dp_grid import Cell, Grid, GridEnv

__all__ = ["MAZES", "BlockingMazeEnv", "DynaMazeEnv", "MazeEnv", "ShortcutMazeEnv", "maze_phases"]

ROWS, COLS = 6, 9
GOAL = (0, 8)


def _maze(start: Cell, walls: Sequence[Cell], scale: int = 1) -> Grid:
    """The maze with each cell made `scale` x `scale` cells (the start and the goal stay
    single cells in their blocks' outer corners: the left edge, the top right corner)."""
    goal = (0, COLS * scale - 1)
    cells = frozenset((r * scale + i, c * scale + j) for r, c in walls
                      for i in range(scale) for j in range(scale))
    return Grid(ROWS * scale, COLS * scale, terminals=(goal,), walls=cells, pays={goal: 1.0},
                start=(start[0] * scale, start[1] * scale))


# name -> the walls of each phase, and the start
MAZES: dict[str, tuple[Cell, tuple[tuple[Cell, ...], ...]]] = {
    "dyna": ((2, 0), (((1, 2), (2, 2), (3, 2), (4, 5), (0, 7), (1, 7), (2, 7)),)),
    "blocking": ((5, 3), (tuple((3, c) for c in range(0, 8)), tuple((3, c) for c in range(1, 9)))),
    "shortcut": ((5, 3), (tuple((3, c) for c in range(1, 9)), tuple((3, c) for c in range(1, 8)))),
}


def maze_phases(name: str, change_at: int | None = None, scale: int = 1) -> list[tuple[int, Grid]]:
    """The book's maze `name` as (first step, grid) phases: one phase for the Dyna maze,
    two for the blocking and shortcut mazes, the second from step `change_at` on; with
    `scale` > 1, each cell made a `scale` x `scale` block (Example 8.4's mazes)."""
    if isinstance(scale, bool) or int(scale) < 1:
        raise ValueError(f"a maze's scale is a whole number >= 1, not {scale!r}")
    start, walls = MAZES[name]
    grids = [_maze(start, w, int(scale)) for w in walls]
    if len(grids) == 1:
        return [(0, grids[0])]
    if change_at is None or isinstance(change_at, bool) or int(change_at) < 1:
        raise ValueError(f"the {name} maze changes after a number of steps >= 1, "
                         f"not {change_at!r}")
    return [(0, grids[0]), (int(change_at), grids[1])]


class MazeEnv(GridEnv):
    """A maze of the book's chapter 8, whose wall may move after a number of steps.

    ## Action Space
    up (0), down (1), left (2), right (3); walls and the edge block.

    ## Observation Space
    The cell, `row * cols + col`, on a 6 x 9 grid (`scale` times finer), row 0 on top.

    ## Rewards
    +1 on reaching the goal (the top right cell); every other move 0.

    ## Starting State
    The maze's start.

    ## Episode End
    Terminated at the goal.

    ## A world that changes
    Steps are counted over episodes (`world_steps`; a reset with a seed starts over,
    `reset(options={"world_steps": n})` sets it); from step `change_at` on the second
    phase plays. `info` tells `world_steps`, `phase` and `changes_in` (while ahead).

    ## Arguments
    `change_at` (the changing mazes); `render_mode`: "ansi" draws the maze.
    """

    def __init__(self, phases: Sequence[tuple[int, Grid]], render_mode: str | None = None) -> None:
        self.phases = list(phases)
        super().__init__(self.phases[0][1], render_mode)
        self.world_steps = 0
        self.phase = 0

    def _enter_phase(self) -> None:
        phase = max(0, bisect_right([start for start, _ in self.phases], self.world_steps) - 1)
        if phase != self.phase:
            self.grid = self.phases[phase][1]
            self.model, self.phase, self._P = self.grid.model, phase, None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        if seed is not None:
            self.world_steps = 0
        if options is not None and "world_steps" in options:
            steps = options["world_steps"]
            if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0:
                raise ValueError(f"world_steps must be an integer >= 0, not {steps!r}")
            self.world_steps = steps
        self._enter_phase()
        obs, info = super().reset(seed=seed, options=options)
        return obs, {**info, **self._clock()}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = super().step(action)
        self.world_steps += 1
        self._enter_phase()
        return obs, reward, terminated, truncated, {**info, **self._clock()}

    def _clock(self) -> dict[str, int]:
        clock = {"world_steps": self.world_steps, "phase": self.phase}
        if self.phase + 1 < len(self.phases):
            clock["changes_in"] = self.phases[self.phase + 1][0] - self.world_steps
        return clock


class DynaMazeEnv(MazeEnv):
    """Figure 8.2's maze (see `MazeEnv`): it never changes; `scale` makes each cell a
    `scale` x `scale` block (Example 8.4's finer mazes of the same structure)."""

    def __init__(self, scale: int = 1, render_mode: str | None = None) -> None:
        super().__init__(maze_phases("dyna", scale=scale), render_mode)
        self.scale = scale


class BlockingMazeEnv(MazeEnv):
    """Figure 8.4's maze (see `MazeEnv`): after `change_at` steps the way round the right of
    the wall closes and one round its left opens."""

    def __init__(self, change_at: int = 1000, render_mode: str | None = None) -> None:
        super().__init__(maze_phases("blocking", change_at), render_mode)
        self.change_at = change_at


class ShortcutMazeEnv(MazeEnv):
    """Figure 8.5's maze (see `MazeEnv`): after `change_at` steps a shorter way opens round
    the right of the wall, the long way round its left staying open."""

    def __init__(self, change_at: int = 3000, render_mode: str | None = None) -> None:
        super().__init__(maze_phases("shortcut", change_at), render_mode)
        self.change_at = change_at
