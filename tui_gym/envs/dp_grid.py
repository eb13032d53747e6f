"""`Grid`, the one grid model (the book's grids and the tile maps), its transitions, and the
envs of the book's grids (Examples 3.5 and 4.1's grids, the random walk, Windy GridWorld)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache, cached_property
from itertools import product
from typing import Any

import numpy as np

from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.envs.table_env import TableEnv

__all__ = [
    "AB_GRID", "CORNER_GRID", "GRID_ACTIONS", "KING_ACTIONS", "LEFT_END_PAYS", "STEPS", "WIND",
    "ABGridEnv", "CornerGridEnv", "Grid", "GridEnv", "KingWindyGridWorldEnv", "RandomWalkEnv",
    "WindyGridWorldEnv", "walk_grid", "windy_grid",
]

Cell = tuple[int, int]
GRID_ACTIONS = ("up", "down", "left", "right")
KING_ACTIONS = (*GRID_ACTIONS, "up-left", "up-right", "down-left", "down-right")
STEPS: dict[str, Cell] = {
    "up": (-1, 0), "down": (1, 0), "left": (0, -1), "right": (0, 1),
    "up-left": (-1, -1), "up-right": (-1, 1), "down-left": (1, -1), "down-right": (1, 1),
}
SIDES = {"left": ("down", "up"), "right": ("down", "up"), "up": ("left", "right"),
         "down": ("left", "right")}  # where a slipping straight move goes instead
GUST = 1.0 / 3.0  # the chance of each of a gusty wind's three strengths
# The walks of the book: states -> what stepping off the left end pays (the right end pays +1).
LEFT_END_PAYS = {5: 0.0, 19: -1.0}
WIND = (0, 0, 0, 1, 1, 1, 2, 2, 1, 0)  # the windy grid: cells a move from each column is pushed up
WINDY_START, WINDY_GOAL = (3, 0), (3, 7)


@dataclass(frozen=True, eq=False)
class Grid:
    """A small grid world: the book's grids, and the tile maps of FrozenLake and CliffWalking.

    A move (one of `moves`, named as in `STEPS`) goes one cell, or from a cell that
    `slip`s with chance p to either side with p / 2 each (the four straight moves); then
    the wind of the column it left (`wind[col]`; with `gusts` one stronger or weaker a
    third of the time each) pushes it up. Entering a cell pays `pays[cell]`, else `step`,
    and puts the agent where `sends` says (a cliff: the start). Off the grid, a move pays
    `edge` and stays (with `edge` None it is clipped to the border); into a wall it pays
    `step` and stays; from a `jumps` cell every move pays the jump's reward and lands on
    its target; `terminals` end the episode; from an `idle` cell nothing happens. Episodes
    start at `start`, else uniformly off terminals and walls. `letters`, `primes` and
    `tiles` are drawn: a cell's letter (A), a jump's landing (A′), another tile (H, a pit).
    """

    rows: int
    cols: int
    moves: tuple[str, ...] = GRID_ACTIONS
    step: float = 0.0
    edge: float | None = 0.0
    terminals: tuple[Cell, ...] = ()
    walls: frozenset[Cell] = frozenset()
    pays: Mapping[Cell, float] = field(default_factory=dict)
    jumps: Mapping[Cell, tuple[Cell, float]] = field(default_factory=dict)
    wind: tuple[int, ...] = ()
    gusts: bool = False
    start: Cell | None = None
    letters: Mapping[Cell, str] = field(default_factory=dict)
    primes: Mapping[Cell, str] = field(default_factory=dict)
    tiles: Mapping[Cell, str] = field(default_factory=dict)
    slip: Mapping[Cell, float] = field(default_factory=dict)
    sends: Mapping[Cell, Cell] = field(default_factory=dict)
    idle: frozenset[Cell] = frozenset()

    def state(self, cell: Cell) -> int:
        return cell[0] * self.cols + cell[1]

    def winds(self, col: int) -> list[tuple[int, float]]:
        """The wind's strengths in a column and their chances."""
        strength = self.wind[col] if self.wind else 0
        if self.gusts and strength:
            return [(strength - 1, GUST), (strength, GUST), (strength + 1, GUST)]
        return [(strength, 1.0)]

    def landing(self, cell: Cell, move: str, push: int) -> tuple[Cell, float]:
        """Where a move from `cell` pushed `push` cells up by the wind ends, and what it pays."""
        (r, c), (dr, dc) = cell, STEPS[move]
        row, col = r + dr - push, c + dc
        if not (0 <= row < self.rows and 0 <= col < self.cols):
            if self.edge is not None:
                return cell, self.edge
            row, col = min(max(row, 0), self.rows - 1), min(max(col, 0), self.cols - 1)
        if (row, col) in self.walls:
            return cell, self.step
        return (row, col), self.pays.get((row, col), self.step)

    @cached_property
    def model(self) -> FiniteMDP:
        """The grid's transitions, `[S, A, K]` with K the most outcomes a move has: the wind's
        strengths, three times over where anything slips. Outcomes with no chance stay put."""
        n, n_moves = self.rows * self.cols, len(self.moves)
        ways = 3 if self.slip else 1
        k = ways * max(len(self.winds(c)) for c in range(self.cols))
        shape = (n, n_moves, k)
        next_state = np.broadcast_to(np.arange(n)[:, None, None], shape).copy()
        prob, reward = np.zeros(shape), np.zeros(shape)
        terminal = np.zeros(shape, dtype=bool)
        ends = set(self.terminals)
        landings = cache(self.landing)  # a cell's moves recur across the actions
        found: list[tuple[Any, ...]] = []  # (s, a, j, next state, chance, reward, end)
        for s in range(n):
            cell = divmod(s, self.cols)
            for a, move in enumerate(self.moves):
                if cell in ends or cell in self.idle:
                    prob[s, a, 0], terminal[s, a, 0] = 1.0, cell in ends
                    continue
                if cell in self.jumps:
                    target, pay = self.jumps[cell]
                    next_state[s, a, 0], prob[s, a, 0], reward[s, a, 0] = (
                        self.state(target), 1.0, pay)
                    continue
                p = self.slip.get(cell, 0.0)
                sides = [(side, p / 2) for side in SIDES[move]] if ways > 1 else []
                outcomes = product([(move, 1.0 - p), *sides], self.winds(cell[1]))
                for j, ((way, chance), (push, gust)) in enumerate(outcomes):
                    if chance == 0:
                        continue
                    to, pay = landings(cell, way, push)
                    found.append((s, a, j, self.state(self.sends.get(to, to)), chance * gust,
                                  pay, to in ends))
        if found:
            *at, to_state, chances, pays, stops = zip(*found, strict=True)
            where = tuple(np.array(at))
            next_state[where], prob[where], reward[where], terminal[where] = (
                to_state, chances, pays, stops)
        initial = np.zeros(n)
        if self.start is not None:
            initial[self.state(self.start)] = 1.0
        else:
            for s in range(n):
                initial[s] = divmod(s, self.cols) not in (ends | self.walls)
        return FiniteMDP(next_state, prob, reward, terminal, initial / initial.sum(),
                         action_names=self.moves)

    def cells(self) -> list[str]:
        """The grid as tile rows: F floor, S the start, W a wall, G a terminal cell, unless
        `tiles` says otherwise (a cell's letter is a mark drawn over its tile)."""
        rows = [["F"] * self.cols for _ in range(self.rows)]
        if self.start is not None:
            rows[self.start[0]][self.start[1]] = "S"
        for r, c in self.walls:
            rows[r][c] = "W"
        for r, c in self.terminals:
            rows[r][c] = "G"
        for (r, c), tile in self.tiles.items():
            rows[r][c] = tile
        return ["".join(row) for row in rows]


AB_GRID = Grid(5, 5, step=0.0, edge=-1.0, jumps={(0, 1): ((4, 1), 10.0), (0, 3): ((2, 3), 5.0)},
               letters={(0, 1): "A", (0, 3): "B"}, primes={(4, 1): "A′", (2, 3): "B′"})
CORNER_GRID = Grid(4, 4, step=-1.0, edge=-1.0, terminals=((0, 0), (3, 3)))


class GridEnv(TableEnv):
    """A `Grid` (the class's `GRID` unless given) played, drawn as text: `.` a cell, `#` a
    wall, `*` a terminal cell, `@` the agent, and the grid's letters; the wind's strengths
    under the columns."""

    GRID: Grid

    def __init__(self, grid: Grid | None = None, render_mode: str | None = None,
                 model: FiniteMDP | None = None) -> None:
        grid = grid or self.GRID
        super().__init__(grid.model if model is None else model, render_mode)
        self.grid = grid
        self.action_names = grid.moves

    def picture(self) -> str:
        grid = self.grid
        drawn = {"W": "#", "G": "*", "H": "*"}  # walls and the ends; the rest a plain cell
        lines = [[drawn.get(tile, ".") for tile in row] for row in grid.cells()]
        for (r, c), letter in grid.letters.items():
            lines[r][c] = letter[0]
        for (r, c), mark in grid.primes.items():
            lines[r][c] = mark[0].lower()  # where a jump lands: A′ drawn as a
        if self.s is not None:
            r, c = divmod(self.s, grid.cols)
            lines[r][c] = "@"
        text = "\n".join(" ".join(line) for line in lines) + "\n"
        if grid.wind:
            text += " ".join(str(w) for w in grid.wind) + "   (wind)\n"
        if self.lastaction is not None:
            text = f"  ({self.action_names[self.lastaction]})\n" + text
        return text


class ABGridEnv(GridEnv):
    """Sutton & Barto's Example 3.5: the 5 x 5 grid with the special cells A and B.

    ## Action Space
    up (0), down (1), left (2), right (3).

    ## Observation Space
    The cell, `row * 5 + col`.

    ## Rewards
    From A (row 0, col 1) every action pays +10 and lands on A′ (row 4, col 1); from
    B (row 0, col 3) +5 to B′ (row 2, col 3). Off the grid -1 (staying); else 0.

    ## Starting State
    Any cell, uniformly.

    ## Episode End
    Never: the task is continuing (the game limits an episode).

    ## Arguments
    `render_mode`: "ansi".
    """

    GRID = AB_GRID


class CornerGridEnv(GridEnv):
    """Sutton & Barto's Example 4.1: the 4 x 4 grid with a terminal cell in two corners.

    ## Action Space
    up (0), down (1), left (2), right (3).

    ## Observation Space
    The cell, `row * 4 + col`; cells 0 and 15 are the terminal corners.

    ## Rewards
    -1 for every move, off the grid (staying) too.

    ## Starting State
    Any of the 14 cells that are not corners, uniformly.

    ## Episode End
    Terminated on entering either corner.

    ## Arguments
    `render_mode`: "ansi".
    """

    GRID = CORNER_GRID


def walk_grid(states: int) -> Grid:
    """The walk with `states` states (5 or 19) between its two ends, as a one-row grid."""
    if states not in LEFT_END_PAYS:
        raise ValueError(f"the random walk has 5 states (Example 6.2) or 19 (Figure 7.2), "
                         f"not {states!r}")
    ends = ((0, 0), (0, states + 1))
    names = "ABCDE" if states == 5 else [str(i) for i in range(1, states + 1)]
    return Grid(1, states + 2, moves=("left", "right"), terminals=ends,
                pays={ends[0]: LEFT_END_PAYS[states], ends[1]: 1.0}, start=(0, states // 2 + 1),
                letters={(0, i + 1): name for i, name in enumerate(names)},
                tiles={ends[0]: "H"})


class RandomWalkEnv(GridEnv):
    """Sutton & Barto's random walk: a row of states between two ends.

    ## Action Space
    left (0), right (1).

    ## Observation Space
    The position, 0 to `states + 1`: the two ends, and A to E (or 1 to 19) between.

    ## Rewards
    +1 off the right end; off the left end 0 with 5 states, -1 with 19; else 0.

    ## Starting State
    The middle state (C; 10).

    ## Episode End
    Terminated at either end.

    ## Arguments
    `states`: 5 or 19; `render_mode`: "ansi".
    """

    def __init__(self, states: int = 5, render_mode: str | None = None) -> None:
        super().__init__(walk_grid(states), render_mode)
        self.states = states


def windy_grid(king_moves: bool = False, stochastic_wind: bool = False) -> Grid:
    """The 7 x 10 windy grid: four moves or the eight king's moves, a steady or gusty wind."""
    return Grid(7, 10, moves=KING_ACTIONS if king_moves else GRID_ACTIONS, step=-1.0,
                edge=None, terminals=(WINDY_GOAL,), wind=WIND, gusts=stochastic_wind,
                start=WINDY_START)


class WindyGridWorldEnv(GridEnv):
    """Sutton & Barto's Example 6.5: a 7 x 10 grid with a wind blowing up through the middle.

    ## Action Space
    up (0), down (1), left (2), right (3); with `king_moves` also up-left (4),
    up-right (5), down-left (6), down-right (7) (Exercise 6.9).

    ## Observation Space
    The cell, `row * 10 + col`, row 0 at the top.

    ## Rewards
    -1 for every move. The wind of the column a move starts from (0 0 0 1 1 1 2 2 1 0)
    pushes it up; with `stochastic_wind` (Exercise 6.10) one more or less a third of
    the time each. A move off the grid ends on its border.

    ## Starting State
    Row 3, column 0.

    ## Episode End
    Terminated on reaching row 3, column 7.

    ## Arguments
    `king_moves`, `stochastic_wind`; `render_mode`: "ansi".
    """

    def __init__(self, king_moves: bool = False, stochastic_wind: bool = False,
                 render_mode: str | None = None) -> None:
        super().__init__(windy_grid(king_moves, stochastic_wind), render_mode)
        self.king_moves = king_moves
        self.stochastic_wind = stochastic_wind


class KingWindyGridWorldEnv(WindyGridWorldEnv):
    """`WindyGridWorldEnv` with king's moves (Exercise 6.9), its own id's env."""

    def __init__(self, stochastic_wind: bool = False, render_mode: str | None = None) -> None:
        super().__init__(True, stochastic_wind, render_mode)
