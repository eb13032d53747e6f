"""`GridMap`: a map of tiles with its rewards and slip, and the edits a person makes."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from tui_gym.envs.tile_map import STANDING, TILE_NAMES, TILES, VALUED, cell_key, check_map

__all__ = ["MAX_SIDE", "TOOLS", "Cell", "GridMap", "Tool"]

MAX_SIDE = 16  # rows and columns of a map, at most
Cell = tuple[int, int]


@dataclass(frozen=True)
class Tool:
    """One thing a person paints: its name, the tile it leaves and what its value is."""

    name: str
    tile: str  # the tile it paints ("" for ice: the cell keeps its tile)
    value: str = ""  # what its number means: "reward", "slip" or "" (none)
    default: float | None = None  # the number it paints with when none is given


TOOLS: tuple[Tool, ...] = (
    Tool("floor", "F"), Tool("wall", "W"), Tool("hole", "H", "reward"), Tool("goal", "G", "reward"),
    Tool("start", "S"), Tool("reward", "R", "reward", 1.0), Tool("ice", "", "slip", 0.5),
    Tool("cliff", "C", "reward"),
)
TOOL_NAMED = {tool.name: tool for tool in TOOLS}


def _sorted(table: Mapping[Cell, float]) -> tuple[tuple[Cell, float], ...]:
    return tuple(sorted((cell, float(value)) for cell, value in table.items()))


@dataclass(frozen=True)
class GridMap:
    """A checked map: `cells` rows, `rewards` and `slip` as sorted ((row, col), value) pairs."""

    cells: tuple[str, ...]
    rewards: tuple[tuple[Cell, float], ...] = ()
    slip: tuple[tuple[Cell, float], ...] = ()

    def __post_init__(self) -> None:
        rows, rewards, slip = check_map(self.cells, dict(self.rewards), dict(self.slip),
                                        need_start=False)
        if len(rows) > MAX_SIDE or len(rows[0]) > MAX_SIDE:
            raise ValueError(f"a map is at most {MAX_SIDE}x{MAX_SIDE} tiles, this one is "
                             f"{len(rows)}x{len(rows[0])}")
        object.__setattr__(self, "cells", rows)
        object.__setattr__(self, "rewards", _sorted(rewards))
        object.__setattr__(self, "slip", _sorted(slip))

    @classmethod
    def of(
        cls, cells: Iterable[str], rewards: Mapping[Cell, float] | None = None,
        slip: Mapping[Cell, float] | None = None,
    ) -> GridMap:
        return cls(tuple(cells), _sorted(rewards or {}), _sorted(slip or {}))

    # --- reading ------------------------------------------------------------------
    @property
    def rows(self) -> int:
        return len(self.cells)

    @property
    def cols(self) -> int:
        return len(self.cells[0])

    @property
    def size_text(self) -> str:
        return f"{self.rows}x{self.cols}"

    def tile(self, cell: Cell) -> str:
        return self.cells[cell[0]][cell[1]]

    def reward_table(self) -> dict[Cell, float]:
        return dict(self.rewards)

    def slip_table(self) -> dict[Cell, float]:
        return dict(self.slip)

    def inside(self, cell: Cell) -> bool:
        return 0 <= cell[0] < self.rows and 0 <= cell[1] < self.cols

    @property
    def start(self) -> Cell | None:
        """The start cell (None on a map without one, as GridWorld's)."""
        return next(((r, row.index("S")) for r, row in enumerate(self.cells) if "S" in row), None)

    def tiles(self) -> set[str]:
        return {tile for row in self.cells for tile in row}

    def env_kwargs(self) -> dict[str, Any]:
        """The map as `TileMapEnv` takes it (JSON-friendly "r,c" keys)."""
        return {
            "cells": list(self.cells), "rewards": {cell_key(c): v for c, v in self.rewards},
            "slip": {cell_key(c): v for c, v in self.slip},
        }

    def walls_xy(self) -> tuple[tuple[int, int], ...]:
        """The walls as GridWorld's (x, y): x the column, y counted up from the bottom row."""
        return tuple(sorted((c, self.rows - 1 - r) for r, row in enumerate(self.cells)
                            for c, tile in enumerate(row) if tile == "W"))

    def goal_reachable(self) -> bool:
        """Whether some goal can be reached from the start (walls block; a hole or a goal
        ends the walk; the cliff leads back to the start)."""
        if self.start is None:
            return False
        return any(self.tile(cell) == "G" for cell in self._reached(self.start, STANDING))

    def free_connected(self) -> bool:
        """Whether every cell that is not a wall can be reached from every other."""
        free = [(r, c) for r in range(self.rows) for c in range(self.cols)
                if self.tile((r, c)) != "W"]
        return bool(free) and len(self._reached(free[0], TILES.replace("W", ""))) == len(free)

    def _reached(self, start: Cell, through: str) -> set[Cell]:
        """The cells a walk from `start` reaches, going on only from tiles in `through`."""
        seen = {start}
        todo = deque(seen)
        while todo:
            r, c = todo.popleft()
            for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0)):
                cell = (r + dr, c + dc)
                if self.inside(cell) and cell not in seen and self.tile(cell) != "W":
                    seen.add(cell)
                    if self.tile(cell) in through:
                        todo.append(cell)
        return seen

    def describe(self, cell: Cell) -> str:
        """What a cell holds, in words: 'hole, reward -5', with its slip."""
        tile = self.tile(cell)
        text = TILE_NAMES[tile]
        reward = self.reward_table().get(cell)
        if reward is not None:
            text += f", reward {reward:+g}"
        slip = self.slip_table().get(cell)
        if slip is not None:
            text += f", slip {slip:g}"
        return text

    # --- editing ------------------------------------------------------------------
    def painted(self, cell: Cell, tool: Tool | str, value: float | None = None) -> GridMap:
        """This map with `cell` painted (`ValueError` when the paint cannot go there: off
        the map, over the only start, or a value out of range)."""
        tool = TOOL_NAMED[tool] if isinstance(tool, str) else tool
        if not self.inside(cell):
            raise ValueError(f"row {cell[0]}, col {cell[1]} is off the {self.size_text} map")
        tile = self.tile(cell)
        if tile == "S" and tool.name not in ("start", "ice"):
            raise ValueError("the start cannot be painted over: paint the start elsewhere first")
        cells = [list(row) for row in self.cells]
        rewards, slip = self.reward_table(), self.slip_table()
        if tool.name == "ice":
            if tile not in STANDING:
                cells[cell[0]][cell[1]] = "F"
                rewards.pop(cell, None)
            slip[cell] = value if value is not None else (tool.default or 0.0)
        else:
            old = self.start
            if tool.tile == "S" and old is not None:
                cells[old[0]][old[1]] = "F"
            cells[cell[0]][cell[1]] = tool.tile
            rewards.pop(cell, None)
            slip.pop(cell, None)  # a cell painted anew is plain (ice is painted on it)
            number = tool.default if value is None else value
            if tool.value == "reward" and number is not None and tool.tile in VALUED:
                rewards[cell] = number
        return GridMap.of(("".join(row) for row in cells), rewards, slip)

    def resized(self, rows: int, cols: int) -> GridMap:
        """This map cropped or extended with floor to rows x cols (the start is kept on the
        map: moved to the nearest cell when it would fall off)."""
        if not (1 <= rows <= MAX_SIDE and 1 <= cols <= MAX_SIDE) or rows * cols < 2:
            raise ValueError(f"a map is 1 to {MAX_SIDE} tiles a side, at least 2 tiles: "
                             f"not {rows}x{cols}")
        start = self.start
        kept = None if start is None else (min(start[0], rows - 1), min(start[1], cols - 1))
        cells = [((self.cells[r] if r < self.rows else "")[:cols] + "F" * cols)[:cols]
                 .replace("S", "F") for r in range(rows)]
        if kept is not None:
            cells[kept[0]] = cells[kept[0]][: kept[1]] + "S" + cells[kept[0]][kept[1] + 1 :]

        def inside(cell: Cell) -> bool:
            return cell[0] < rows and cell[1] < cols and cell != kept

        rewards = {c: v for c, v in self.rewards if inside(c)}
        slip = {c: v for c, v in self.slip if inside(c) or c == start == kept}
        return GridMap.of(cells, rewards, slip)
