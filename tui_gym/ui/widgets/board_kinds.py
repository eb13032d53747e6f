"""`board_class`: the board class for each kind of board a game asks for (`Game.board`)."""

from __future__ import annotations

import importlib

from tui_gym.ui.widgets.boards import Board

__all__ = ["KINDS", "board_class"]

# kind -> (module under tui_gym.ui.widgets, class name), imported when first asked for
KINDS: dict[str, tuple[str, str]] = {
    "cards": ("cards_board", "CardsBoard"), "dial": ("dial_board", "DialBoard"),
    "grid": ("grid_board", "GridBoard"), "tile": ("tile_board", "TileBoard"),
    "taxi": ("taxi_board", "TaxiBoard"), "text": ("text_board", "TextBoard"),
}


def board_class(kind: str) -> type[Board]:
    """The board of a kind; a game of a kind no board draws gets the text board."""
    module, name = KINDS.get(kind, KINDS["text"])
    cls: type[Board] = getattr(importlib.import_module(f"tui_gym.ui.widgets.{module}"), name)
    return cls
