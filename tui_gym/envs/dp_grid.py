"""The grids of Sutton & Barto's chapters 3 and 4: `ABGridEnv` and `CornerGridEnv`.

Both are small grids where a move goes one cell up, down, left or right, and
a move off the grid leaves the agent where it was; `grid_arrays` gives their
transitions, for the env and for the exact model alike. A cell is (row, col),
row 0 at the top; a state is `row * cols + col`.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping

import numpy as np

from tui_gym.envs.table_env import TableEnv
from tui_gym.envs.tile_map import TileArrays

__all__ = ["AB_JUMPS", "CORNERS", "GRID_ACTIONS", "ABGridEnv", "CornerGridEnv", "grid_arrays"]

Cell = tuple[int, int]
GRID_ACTIONS = ("up", "down", "left", "right")
STEPS = {"up": (-1, 0), "down": (1, 0), "left": (0, -1), "right": (0, 1)}
AB_JUMPS: dict[Cell, tuple[Cell, float]] = {(0, 1): ((4, 1), 10.0), (0, 3): ((2, 3), 5.0)}
CORNERS: tuple[Cell, ...] = ((0, 0), (3, 3))


def grid_arrays(
    rows: int,
    cols: int,
    *,
    step: float,
    edge: float,
    jumps: Mapping[Cell, tuple[Cell, float]] = {},  # noqa: B006 - read only
    terminals: Collection[Cell] = (),
) -> TileArrays:
    """A grid's transitions: a move pays `step` (`edge` when it would leave the grid, and
    the agent stays); from a `jumps` cell every action pays its reward and lands on its
    target; entering a `terminals` cell ends the episode, and from one nothing happens.
    Episodes start uniformly on the cells that are not terminal."""
    n = rows * cols
    next_state = np.zeros((n, len(GRID_ACTIONS)), dtype=np.int64)
    reward = np.zeros((n, len(GRID_ACTIONS)))
    terminal = np.zeros((n, len(GRID_ACTIONS)), dtype=bool)
    ends = {r * cols + c for r, c in terminals}
    for s in range(n):
        r, c = divmod(s, cols)
        for a, name in enumerate(GRID_ACTIONS):
            dr, dc = STEPS[name]
            if s in ends:
                next_state[s, a], terminal[s, a] = s, True
            elif (r, c) in jumps:
                (tr, tc), pay = jumps[r, c]
                next_state[s, a], reward[s, a] = tr * cols + tc, pay
            elif 0 <= r + dr < rows and 0 <= c + dc < cols:
                next_state[s, a], reward[s, a] = (r + dr) * cols + c + dc, step
                terminal[s, a] = next_state[s, a] in ends
            else:
                next_state[s, a], reward[s, a] = s, edge
    initial = np.array([0.0 if s in ends else 1.0 for s in range(n)])
    return TileArrays(next_state[..., None], np.ones((n, len(GRID_ACTIONS), 1)),
                      reward[..., None], terminal[..., None], initial / initial.sum())


class _GridEnv(TableEnv):
    """A grid drawn as text: `.` a cell, `@` the agent, and the world's own letters."""

    action_names = GRID_ACTIONS
    rows = cols = 0
    letters: Mapping[Cell, str] = {}

    def picture(self) -> str:
        lines = [["."] * self.cols for _ in range(self.rows)]
        for (r, c), letter in self.letters.items():
            lines[r][c] = letter
        if self.s is not None:
            r, c = divmod(self.s, self.cols)
            lines[r][c] = "@"
        text = "\n".join(" ".join(line) for line in lines) + "\n"
        if self.lastaction is not None:
            text = f"  ({GRID_ACTIONS[self.lastaction]})\n" + text
        return text


class ABGridEnv(_GridEnv):
    """Sutton & Barto's Example 3.5: the 5 x 5 grid with the special cells A and B.

    ## Action Space
    up (0), down (1), left (2), right (3).

    ## Observation Space
    The cell, `row * 5 + col`.

    ## Rewards
    From A (row 0, col 1) every action pays +10 and lands on A′ (row 4, col 1);
    from B (row 0, col 3) +5 and lands on B′ (row 2, col 3). A move off the
    grid pays -1 and leaves the agent where it was; every other move pays 0.

    ## Starting State
    Any cell, uniformly.

    ## Episode End
    Never: the task is continuing. The game puts a limit on an episode.

    ## Arguments
    `render_mode`: "ansi" draws the grid as text.
    """

    rows = cols = 5
    letters = {(0, 1): "A", (0, 3): "B", (4, 1): "a", (2, 3): "b"}

    def __init__(self, render_mode: str | None = None) -> None:
        super().__init__(grid_arrays(5, 5, step=0.0, edge=-1.0, jumps=AB_JUMPS), render_mode)


class CornerGridEnv(_GridEnv):
    """Sutton & Barto's Example 4.1: the 4 x 4 grid with a terminal cell in two corners.

    ## Action Space
    up (0), down (1), left (2), right (3).

    ## Observation Space
    The cell, `row * 4 + col`; cells 0 and 15 are the terminal corners.

    ## Rewards
    -1 for every move, into a corner or off the grid (the agent then stays) too.

    ## Starting State
    Any of the 14 cells that are not corners, uniformly.

    ## Episode End
    Terminated on entering either corner.

    ## Arguments
    `render_mode`: "ansi" draws the grid as text.
    """

    rows = cols = 4
    letters = {(0, 0): "#", (3, 3): "#"}

    def __init__(self, render_mode: str | None = None) -> None:
        super().__init__(grid_arrays(4, 4, step=-1.0, edge=-1.0, terminals=CORNERS),
                         render_mode)
