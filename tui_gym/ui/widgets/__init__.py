"""Widgets of the tui-gym app, one a file; the game boards are in `boards`.

`boards` is imported first on purpose: the board modules import `Board` from
it and it imports them back for the `BOARDS` registry.
"""

from tui_gym.ui.widgets.boards import BOARDS, Board, CardsBoard, GridBoard

__all__ = ["BOARDS", "Board", "CardsBoard", "GridBoard"]
