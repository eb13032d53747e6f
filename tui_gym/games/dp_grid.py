"""What the book's grid worlds share: a `ModelGame` on a `Grid` (`tui_gym.envs.dp_grid`)."""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP
from tui_gym.envs.dp_grid import GRID_ACTIONS, Cell, Grid
from tui_gym.games.base import TIED, UNREADABLE, HeatmapLayout, greedy_panel, numbered
from tui_gym.games.model import DiscreteStates, ModelGame, freeze

__all__ = ["ARROWS", "DPGridGame", "DPGridLayout", "DPGridStates", "Event"]

ARROWS = {"up": "↑", "down": "↓", "left": "←", "right": "→",
          "up-left": "↖", "up-right": "↗", "down-left": "↙", "down-right": "↘"}
END = "★"  # a terminal cell: the tile board's goal
WALL = "█"

Event = tuple[str, str]  # what a move did ('{who} ...'), and its tone on the board


class DPGridStates(DiscreteStates):
    """Cells of the grid; the tile board's scene."""

    game: DPGridGame

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        grid = self.game.grid(kwargs)
        cell = divmod(int(observation), grid.cols)
        if not 0 <= cell[0] < grid.rows:
            raise ValueError(f"no cell {observation}")
        name = grid.letters.get(cell) or grid.primes.get(cell)
        if cell in grid.terminals:
            name = "terminal"
        return f"row {cell[0]}, col {cell[1]}" + (f" ({name})" if name else "")

    def json_observation(self, observation: Any) -> Any:
        """A cell as [row, col]."""
        game = self.game
        return list(divmod(int(observation), game.grid(game.default_kwargs()).cols))

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        game = self.game
        grid: Grid = game_env.grid
        state, last = game_env.s, game_env.lastaction
        agent = None if state is None else divmod(int(state), grid.cols)
        move = None if last is None else grid.moves[int(last)]
        shown = {**grid.pays, **{cell: pay for cell, (_, pay) in grid.jumps.items()}}
        scene: dict[str, Any] = {
            "rows": grid.rows, "cols": grid.cols, "cells": grid.cells(), "theme": "plain",
            "agent": agent, "last_action": move, "slipped": False,
            "rewards": {f"{r},{c}": pay for (r, c), pay in shown.items()},
            "marks": {f"{r},{c}": text for (r, c), text in {**grid.letters, **grid.primes}.items()},
            "moves": list(grid.moves),
        }
        if not set(GRID_ACTIONS) <= set(grid.moves):
            scene["offered"] = list(grid.moves)
        if grid.wind:
            scene["wind"], scene["gusts"] = list(grid.wind), grid.gusts
        was = before.get("agent")
        if was is not None and agent is not None and move is not None:
            event = game.event(game_env, before, (int(was[0]), int(was[1])), agent, move)
            if event is not None:
                scene["event"], scene["event_tone"] = event
        return scene


class DPGridLayout(HeatmapLayout):
    """One panel shaped like the grid: max Q colours each cell, the greedy move's arrow."""

    game: DPGridGame

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        game = self.game
        try:
            grid = game.grid(kwargs)
            rows, cols = grid.rows, grid.cols
            values = np.asarray(q, dtype=float).reshape(rows * cols, len(grid.moves))
        except UNREADABLE:
            return []
        has_marks = isinstance(marks, np.ndarray) and marks.shape == values.shape
        parts = ["arrow: greedy move", f"{TIED} tie",
                 *(f"{grid.letters[cell]} jumps" for cell in grid.jumps),
                 *([f"{END} terminal"] if grid.terminals else []),
                 *([f"{WALL} wall"] if grid.walls else []), "* not an optimal move"]
        return [greedy_panel(
            "max Q and the greedy move", "  ".join(parts), numbered(rows), numbered(cols),
            lambda r, c: END if (r, c) in grid.terminals else WALL if (r, c) in grid.walls
            else None,
            lambda r, c: values[r * cols + c],
            lambda action: ARROWS.get(grid.moves[action], grid.moves[action]),
            lambda r, c, action: has_marks and not marks[r * cols + c, action],
            lambda r, c: grid.letters.get((r, c), TIED),
        )]


@lru_cache(maxsize=64)
def _grid_model(game: DPGridGame, frozen: Any) -> FiniteMDP:
    """The model of the grid a game's arguments (frozen) make, kept."""
    return game.grid(dict(frozen)).model


class DPGridGame(ModelGame):
    """A grid world of the book (see the module docstring)."""

    board = "tile"
    action_names: tuple[str, ...] = GRID_ACTIONS

    states_type = DPGridStates
    layout_type = DPGridLayout

    fixed_grid: Grid | None = None  # the grid of a game whose arguments change none

    def grid(self, kwargs: Mapping[str, Any]) -> Grid:
        """The grid these arguments make."""
        if self.fixed_grid is None:
            raise NotImplementedError
        return self.fixed_grid

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP:
        return _grid_model(self, freeze(kwargs))

    def event(self, game_env: Any, before: Mapping[str, Any], was: Cell, now: Cell,
              move: str) -> Event | None:
        """What the move `move` from `was` to `now` did, in the game's words (None: the
        board's own words); `before` is the scene before it."""
        grid: Grid = game_env.grid
        jump = grid.jumps.get(was)
        if jump is not None and now == jump[0]:
            name = grid.letters[was]
            return f"{{who}} jumped from {name} to {name}′: +{jump[1]:g}", "good"
        return None
