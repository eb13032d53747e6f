"""`BOARDS`: the board class for each kind of board a game asks for (`Game.board`)."""

from __future__ import annotations

from tui_gym.ui.widgets.boards import Board
from tui_gym.ui.widgets.cards_board import CardsBoard
from tui_gym.ui.widgets.grid_board import GridBoard
from tui_gym.ui.widgets.taxi_board import TaxiBoard
from tui_gym.ui.widgets.text_board import TextBoard
from tui_gym.ui.widgets.tile_board import TileBoard

__all__ = ["BOARDS", "board_class"]

BOARDS: dict[str, type[Board]] = {
    "cards": CardsBoard,
    "grid": GridBoard,
    "tile": TileBoard,
    "taxi": TaxiBoard,
    "text": TextBoard,
}


def board_class(kind: str) -> type[Board]:
    """The board of a kind; a game of a kind no board draws gets the text board."""
    return BOARDS.get(kind, TextBoard)
