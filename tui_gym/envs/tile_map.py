"""TileMap: FrozenLake and CliffWalking played on any map of tiles."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.envs.dp_grid import Cell, Grid
from tui_gym.envs.table_env import TableEnv

__all__ = [
    "ACTION_ORDERS", "TILES", "TileMapEnv", "TileRules", "cell_key", "read_cell", "tile_grid",
]

TILES = "SFHGCWR"
TILE_NAMES = {"S": "start", "F": "floor", "H": "hole", "G": "goal", "C": "cliff", "W": "wall",
              "R": "reward cell"}
TILE_LIST = ", ".join(f"{t} {n}" for t, n in TILE_NAMES.items())
VALUED = "RHGC"  # tiles whose reward a map may set
STANDING = "SFR"  # tiles an agent stands on, so the only ones whose slip matters
ENDING = "HG"
# The action numbers of Gymnasium's two games: FrozenLake's and CliffWalking's.
ACTION_ORDERS: dict[str, tuple[str, ...]] = {
    "lake": ("left", "down", "right", "up"), "cliff": ("up", "right", "down", "left"),
}


@dataclass(frozen=True)
class TileRules:
    """What tiles pay and how slippery they are where a map does not say. `step`: entering
    floor or the start, or a blocked move; `goal`, `hole`, `cliff`: entering one (a cliff
    sends the agent to the start); `slip`: the chance a move goes to either side instead."""

    step: float = 0.0
    goal: float = 1.0
    hole: float = 0.0
    cliff: float = -100.0
    slip: float = 0.0


def cell_key(cell: Cell) -> str:
    """A cell as the "r,c" text maps and scenes key it by."""
    return f"{cell[0]},{cell[1]}"


def read_cell(key: Any) -> Cell:
    """A cell from "r,c" text or a (row, col) pair; `ValueError` otherwise."""
    if isinstance(key, str):
        parts = key.split(",")
        if len(parts) == 2 and all(p.strip().isdigit() and p.strip().isascii() for p in parts):
            return int(parts[0]), int(parts[1])
        raise ValueError(f"a cell is 'row,col', got {key!r}")
    if isinstance(key, Sequence) and len(key) == 2 and all(
        isinstance(v, int | np.integer) and not isinstance(v, bool) for v in key
    ):
        return int(key[0]), int(key[1])
    raise ValueError(f"a cell is (row, col), got {key!r}")


def _where(cell: Cell) -> str:
    return f"row {cell[0]}, col {cell[1]}"


def check_map(
    cells: Sequence[str], rewards: Mapping[Any, Any] | None, slip: Mapping[Any, Any] | None,
    need_start: bool = True, where: Callable[[Cell], str] = _where,
) -> tuple[tuple[str, ...], dict[Cell, float], dict[Cell, float]]:
    """The map checked: rows, rewards and slip by cell. `ValueError` names the cell at fault
    (as `where` words it). With `need_start`, exactly one start; without, at most one."""
    rows = tuple(str(row) for row in cells)
    if not rows or not rows[0]:
        raise ValueError("a tile map needs at least one row of tiles")
    width = len(rows[0])
    for r, row in enumerate(rows):
        if len(row) != width:
            row_name = where((r, 0)).rsplit(",", 1)[0]  # the row, without its column
            raise ValueError(f"{row_name} has {len(row)} tiles, row 0 has {width}: rows must be "
                             "equally long")
        for c, tile in enumerate(row):
            if tile not in TILES:
                raise ValueError(f"{where((r, c))}: {tile!r} is not a tile ({TILE_LIST})")
    starts = [(r, c) for r, row in enumerate(rows) for c, t in enumerate(row) if t == "S"]
    if len(starts) > 1:
        raise ValueError(f"{where(starts[1])}: a second start (the first is at "
                         f"{_where(starts[0])}); a map has one")
    if need_start and not starts:
        raise ValueError("a tile map needs a start S")
    reward_of: dict[Cell, float] = {}
    for key, value in (rewards or {}).items():
        cell = _on_map(read_cell(key), rows)
        tile = rows[cell[0]][cell[1]]
        if tile not in VALUED:
            raise ValueError(f"{where(cell)} is {TILE_NAMES[tile]}: only reward (R), hole (H), "
                             "goal (G) and cliff (C) cells take a reward")
        reward_of[cell] = _finite(value, f"the reward at {_where(cell)}")
    for r, row in enumerate(rows):
        for c, tile in enumerate(row):
            if tile == "R" and (r, c) not in reward_of:
                raise ValueError(f"{where((r, c))}: a reward cell needs its value "
                                 f"('reward {r},{c}: VALUE' in a map's text)")
    slip_of: dict[Cell, float] = {}
    for key, value in (slip or {}).items():
        cell = _on_map(read_cell(key), rows)
        tile = rows[cell[0]][cell[1]]
        if tile not in STANDING:
            raise ValueError(f"{where(cell)} is {TILE_NAMES[tile]}: only cells the agent "
                             "stands on (S, F, R) slip")
        slip_of[cell] = _probability(value, f"the slip at {_where(cell)}")
    return rows, reward_of, slip_of


def _on_map(cell: Cell, rows: Sequence[str]) -> Cell:
    if not (0 <= cell[0] < len(rows) and 0 <= cell[1] < len(rows[0])):
        raise ValueError(f"{_where(cell)} is off the {len(rows)}x{len(rows[0])} map")
    return cell


def _finite(value: Any, what: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if isinstance(value, bool) or not math.isfinite(number):
        raise ValueError(f"{what} must be a finite number, got {value!r}")
    return number


def _probability(value: Any, what: str) -> float:
    number = _finite(value, what)
    if not 0.0 <= number <= 1.0:
        raise ValueError(f"{what} must be in [0, 1], got {value!r}")
    return number


def tile_grid(
    cells: Sequence[str], rewards: Mapping[Cell, float], slip: Mapping[Cell, float],
    actions: Sequence[str], rules: TileRules,
) -> Grid:
    """The `Grid` of a checked map (`check_map`): holes and goals end the episode, the cliff
    sends the agent to the start, nothing acts from a wall or the cliff. The same map gives
    the same `Grid`, so its model is built once (for the game and the env alike)."""
    return _grid(tuple(cells), tuple(sorted(rewards.items())), tuple(sorted(slip.items())),
                 tuple(actions), rules)


@lru_cache(maxsize=32)
def _grid(cells: tuple[str, ...], rewards: tuple[tuple[Cell, float], ...],
          slip: tuple[tuple[Cell, float], ...], actions: tuple[str, ...],
          rules: TileRules) -> Grid:
    tiles = {(r, c): tile for r, row in enumerate(cells) for c, tile in enumerate(row)}
    start = next(cell for cell, tile in tiles.items() if tile == "S")
    by_tile = {"G": rules.goal, "H": rules.hole, "C": rules.cliff}
    slip_of = dict(slip)
    slips = {cell: slip_of.get(cell, rules.slip) for cell, tile in tiles.items()
             if tile in STANDING}
    return Grid(
        len(cells), len(cells[0]), moves=actions, step=rules.step, edge=rules.step,
        terminals=tuple(cell for cell, tile in tiles.items() if tile in ENDING),
        walls=frozenset(cell for cell, tile in tiles.items() if tile == "W"),
        pays={**{cell: by_tile[t] for cell, t in tiles.items() if t in by_tile}, **dict(rewards)},
        start=start, slip={cell: p for cell, p in slips.items() if p > 0},
        sends={cell: start for cell, tile in tiles.items() if tile == "C"},
        idle=frozenset(cell for cell, tile in tiles.items() if tile in "WC"),
    )


class TileMapEnv(TableEnv):
    """Walk a map of tiles (S start, F floor, H hole, G goal, C cliff, W wall, R reward
    cell) from the start to a goal: FrozenLake and CliffWalking on any map. From a cell
    that slips with chance `p`, a move goes to either side with `p / 2` each.

    ## Action Space
    `Discrete(4)` in Gymnasium's order of `actions`: "lake" 0 left, 1 down, 2 right,
    3 up; "cliff" 0 up, 1 right, 2 down, 3 left. Walls and the edge block.

    ## Observation Space
    The agent's cell, `row * cols + col`.

    ## Rewards
    Entering a cell pays its tile's reward (the map's, else the rules'); floor, the
    start and a blocked move pay `step_reward`.

    ## Starting State
    The start cell S.

    ## Episode End
    Terminated in a hole or on a goal; the cliff sends the agent back to the start.

    ## Arguments
    `cells`, `rewards` and `slip` ({"r,c": value}), `slip_default`, `actions`,
    `step_reward`, `goal_reward`, `hole_reward`, `cliff_reward`, `render_mode` "ansi".
    """

    def __init__(
        self, cells: Sequence[str] = ("SFFF", "FHFH", "FFFH", "HFFG"),
        rewards: Mapping[Any, float] | None = None, slip: Mapping[Any, float] | None = None,
        slip_default: float = 0.0, actions: str = "lake", step_reward: float = 0.0,
        goal_reward: float = 1.0, hole_reward: float = 0.0, cliff_reward: float = -100.0,
        render_mode: str | None = None,
    ) -> None:
        if actions not in ACTION_ORDERS:
            raise ValueError(f"actions must be one of {', '.join(ACTION_ORDERS)}, got {actions!r}")
        rows, reward_of, slip_of = check_map(cells, rewards, slip)
        rules = TileRules(
            step=_finite(step_reward, "step_reward"), goal=_finite(goal_reward, "goal_reward"),
            hole=_finite(hole_reward, "hole_reward"), cliff=_finite(cliff_reward, "cliff_reward"),
            slip=_probability(slip_default, "slip_default"),
        )
        self.cells = rows
        self.rewards = reward_of
        self.nrow, self.ncol = len(rows), len(rows[0])
        self.desc = np.asarray([list(row) for row in rows], dtype="c")
        self.grid = tile_grid(rows, reward_of, slip_of, ACTION_ORDERS[actions], rules)
        super().__init__(self.grid.model, render_mode)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        gym.Env.reset(self, seed=seed)  # the one start, with no draw (as FrozenLake's)
        self.s = int(np.flatnonzero(self.initial_state_distrib)[0])
        self.lastaction = None
        return self.s, {"prob": 1.0}

    def picture(self) -> str:
        lines = [list(row) for row in self.cells]
        if self.s is not None:
            r, c = divmod(self.s, self.ncol)
            lines[r][c] = f"\x1b[41m{lines[r][c]}\x1b[0m"
        text = ""
        if self.lastaction is not None:
            text = f"  ({self.grid.moves[self.lastaction].capitalize()})\n"
        return text + "\n".join("".join(line) for line in lines) + "\n"

