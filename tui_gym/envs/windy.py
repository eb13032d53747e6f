"""Sutton & Barto's Windy GridWorld: `WindyGridWorldEnv` (Example 6.5, Exercises 6.9, 6.10)."""

from __future__ import annotations

from tui_gym.envs.dp_grid import GRID_ACTIONS, KING_ACTIONS, Grid, GridEnv

__all__ = ["GOAL", "START", "WIND", "KingWindyGridWorldEnv", "WindyGridWorldEnv", "windy_grid"]

WIND = (0, 0, 0, 1, 1, 1, 2, 2, 1, 0)  # cells a move from each column is pushed up
START, GOAL = (3, 0), (3, 7)


def windy_grid(king_moves: bool = False, stochastic_wind: bool = False) -> Grid:
    """The 7 x 10 windy grid: four moves or the eight king's moves, a steady or gusty wind."""
    return Grid(7, 10, moves=KING_ACTIONS if king_moves else GRID_ACTIONS, step=-1.0,
                edge=None, terminals=(GOAL,), wind=WIND, gusts=stochastic_wind, start=START)


class WindyGridWorldEnv(GridEnv):
    """Sutton & Barto's Example 6.5: a 7 x 10 grid with a wind blowing up through the middle.

    ## Action Space
    up (0), down (1), left (2), right (3); with `king_moves`, also up-left (4),
    up-right (5), down-left (6), down-right (7) (Exercise 6.9).

    ## Observation Space
    The cell, `row * 10 + col`, row 0 at the top.

    ## Rewards
    -1 for every move, the last one included.

    ## Starting State
    Row 3, column 0.

    ## Episode End
    Terminated on reaching row 3, column 7. A move goes one cell its way, and
    the wind of the column it starts from, 0 0 0 1 1 1 2 2 1 0 by column,
    pushes it that many cells up; a move that would leave the grid ends on its
    border. With `stochastic_wind` (Exercise 6.10), where there is wind it
    blows one cell stronger a third of the time and one weaker a third of the
    time.

    ## Arguments
    `king_moves`, `stochastic_wind` (both false by default); `render_mode`:
    "ansi" draws the grid as text.
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
