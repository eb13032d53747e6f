"""`BOARDS`: the board class for each kind of board a game asks for (`Game.board`).

Each board's module is imported the first time its kind is asked for: a run of
the app draws one or two kinds, and the first frame waits for none of the others.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping

from tui_gym.ui.widgets.boards import Board

__all__ = ["BOARDS", "board_class"]

# kind -> (module under tui_gym.ui.widgets, class name)
_WHERE: dict[str, tuple[str, str]] = {
    "cards": ("cards_board", "CardsBoard"), "dial": ("dial_board", "DialBoard"),
    "grid": ("grid_board", "GridBoard"), "tile": ("tile_board", "TileBoard"),
    "taxi": ("taxi_board", "TaxiBoard"), "text": ("text_board", "TextBoard"),
}


class _Boards(Mapping[str, type[Board]]):
    """The board classes by kind, each imported when first looked up."""

    def __init__(self) -> None:
        self._loaded: dict[str, type[Board]] = {}

    def __getitem__(self, kind: str) -> type[Board]:
        cls = self._loaded.get(kind)
        if cls is None:
            module, name = _WHERE[kind]
            cls = getattr(importlib.import_module(f"tui_gym.ui.widgets.{module}"), name)
            self._loaded[kind] = cls
        return cls

    def __iter__(self) -> Iterator[str]:
        return iter(_WHERE)

    def __len__(self) -> int:
        return len(_WHERE)


BOARDS: Mapping[str, type[Board]] = _Boards()


def board_class(kind: str) -> type[Board]:
    """The board of a kind; a game of a kind no board draws gets the text board."""
    return BOARDS[kind if kind in _WHERE else "text"]
