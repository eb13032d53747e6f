"""What the book's small grids share (`ab-grid`, `corner-grid`): a `ModelGame` on a grid.

A `DPGridGame` names its grid's size, its special cells and the transitions
(`arrays`, from `tui_gym.envs.dp_grid`); from them it gets:

- `DPGridStates`: a cell in words, and the tile board's scene (the grid as
  rows of tiles, the agent, the last move, a jump's words and rewards);
- `DPGridLayout`: one heatmap panel shaped like the grid, the greedy move's
  arrow in each cell, the special cells by their letters where every move is
  worth the same (A and B, from which every move jumps), terminal cells as ★;
- its exact model, built from the same arrays as the env.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP
from tui_gym.envs.dp_grid import GRID_ACTIONS
from tui_gym.envs.tile_map import TileArrays
from tui_gym.games.base import UNREADABLE, HeatmapLayout
from tui_gym.games.model import DiscreteStates, ModelGame

__all__ = ["DPGridGame", "DPGridLayout", "DPGridStates"]

Cell = tuple[int, int]
ARROWS = {"up": "↑", "down": "↓", "left": "←", "right": "→"}
TIED = "·"
END = "★"  # a terminal cell: the tile board's goal


class DPGridGame(ModelGame):
    """A grid world of the book's chapters 3 and 4 (see the module docstring)."""

    board = "tile"
    action_names = GRID_ACTIONS
    rows = cols = 0
    letters: Mapping[Cell, str] = {}  # cells drawn as a letter on board and heatmap
    primes: Mapping[Cell, str] = {}  # cells marked on the board (where a jump lands)
    terminals: tuple[Cell, ...] = ()
    jumps: Mapping[Cell, tuple[Cell, float]] = {}

    def __init__(self) -> None:
        super().__init__()
        self.states = DPGridStates(self)
        self.layout = DPGridLayout(self)
        self._model: FiniteMDP | None = None

    def arrays(self) -> TileArrays:
        """The grid's transitions."""
        raise NotImplementedError

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP:
        if self._model is None:
            arrays = self.arrays()
            self._model = FiniteMDP(arrays.next_state, arrays.prob, arrays.reward,
                                    arrays.terminal, arrays.initial,
                                    action_names=self.action_names)
        return self._model

    def cells(self) -> list[str]:
        """The grid as tile rows: F floor, G a terminal cell, a special cell's letter."""
        rows = [["F"] * self.cols for _ in range(self.rows)]
        for r, c in self.terminals:
            rows[r][c] = "G"
        for (r, c), letter in self.letters.items():
            rows[r][c] = letter
        return ["".join(row) for row in rows]


def _game(role: Any) -> DPGridGame:
    game = role.game
    assert isinstance(game, DPGridGame)
    return game


class DPGridStates(DiscreteStates):
    """Cells of the grid; the tile board's scene."""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        game = _game(self)
        row, col = divmod(int(observation), game.cols)
        name = game.letters.get((row, col)) or game.primes.get((row, col))
        if (row, col) in game.terminals:
            name = "terminal"
        return f"row {row}, col {col}" + (f" ({name})" if name else "")

    def json_observation(self, observation: Any) -> Any:
        """A cell as [row, col]."""
        return list(divmod(int(observation), _game(self).cols))

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        game = _game(self)
        state, last = game_env.s, game_env.lastaction
        agent = None if state is None else divmod(int(state), game.cols)
        scene: dict[str, Any] = {
            "rows": game.rows,
            "cols": game.cols,
            "cells": game.cells(),
            "theme": "plain",
            "agent": agent,
            "last_action": None if last is None else game.action_names[int(last)],
            "slipped": False,
            "rewards": {f"{r},{c}": pay for (r, c), (_, pay) in game.jumps.items()},
            "marks": {f"{r},{c}": text
                      for (r, c), text in {**game.letters, **game.primes}.items()},
        }
        was = before.get("agent")
        if was is not None and agent is not None and last is not None:
            jump = game.jumps.get((int(was[0]), int(was[1])))
            if jump is not None and tuple(agent) == jump[0]:
                name = game.letters[int(was[0]), int(was[1])]
                scene["event"] = f"{{who}} jumped from {name} to {name}′: +{jump[1]:g}"
        return scene


class DPGridLayout(HeatmapLayout):
    """One panel shaped like the grid: max Q colours each cell, the greedy move's arrow."""

    def heatmaps(
        self,
        q: np.ndarray,
        kwargs: Mapping[str, Any],
        focus: Any = None,
        marks: Any = None,
    ) -> list[Heatmap]:
        game = _game(self)
        rows, cols = game.rows, game.cols
        try:
            values = np.asarray(q, dtype=float).reshape(rows * cols, len(game.action_names))
        except UNREADABLE:
            return []
        has_marks = isinstance(marks, np.ndarray) and marks.shape == values.shape
        grid = np.full((rows, cols), np.nan)
        marked = np.zeros((rows, cols), dtype=bool)
        labels = []
        for r in range(rows):
            line = []
            for c in range(cols):
                if (r, c) in game.terminals:
                    line.append(END)
                    continue
                qs = values[r * cols + c]
                grid[r, c] = float(qs.max())
                if (qs == qs[0]).all():
                    line.append(game.letters.get((r, c), TIED))
                    continue
                action = int(np.argmax(qs))
                line.append(ARROWS[game.action_names[action]])
                marked[r, c] = has_marks and not marks[r * cols + c, action]
            labels.append(tuple(line))
        parts = ["arrow: greedy move", f"{TIED} tie",
                 *(f"{letter} jumps" for letter in game.letters.values()),
                 *([f"{END} terminal"] if game.terminals else []), "* not an optimal move"]
        return [
            Heatmap(
                title="max Q and the greedy move",
                row_labels=tuple(str(r) for r in range(rows)),
                col_labels=tuple(str(c) for c in range(cols)),
                values=grid,
                labels=tuple(labels),
                marked=marked,
                legend="  ".join(parts),
            )
        ]
