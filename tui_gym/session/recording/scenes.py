"""`scene_fits(board, scene)`: whether a recorded scene is one the game's board can draw."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from tui_gym.games.maps import MAX_SIDE

__all__ = ["scene_fits"]

MAX_CARDS = 21  # cards in one hand: 21 aces at most before any total passes 21
MAX_WORD = 80  # a name or a label
MAX_TEXT = 10_000  # a text picture
MAX_ITEMS = 64  # actions, stands


def _int(value: Any, low: int, high: int) -> bool:
    return type(value) is int and low <= value <= high


def _optional_int(value: Any, low: int, high: int) -> bool:
    return value is None or _int(value, low, high)


def _word(value: Any) -> bool:
    return value is None or (isinstance(value, str) and len(value) <= MAX_WORD)


def _cell(value: Any, rows: int, cols: int) -> bool:
    return (isinstance(value, list) and len(value) == 2
            and _int(value[0], 0, rows - 1) and _int(value[1], 0, cols - 1))


def _cells(value: Any, rows: int, cols: int) -> bool:
    return isinstance(value, list) and len(value) <= rows * cols and all(
        _cell(c, rows, cols) for c in value)


def _cell_table(value: Any, rows: int, cols: int) -> bool:
    """`{"ROW,COL": number or short text}` over the map's cells."""
    if value is None:
        return True
    return isinstance(value, dict) and len(value) <= rows * cols and all(
        isinstance(k, str) and len(k) <= 12 and (_word(v) or type(v) in (int, float))
        for k, v in value.items())


def _cards(scene: Mapping[str, Any]) -> bool:
    return all(
        isinstance(scene.get(who, []), list) and len(scene.get(who, [])) <= MAX_CARDS
        and all(_int(card, 1, 11) for card in scene.get(who, []))
        and _optional_int(scene.get(f"{who}_total"), 0, 11 * MAX_CARDS)
        for who in ("player", "dealer")) and isinstance(scene.get("player_usable", False), bool)


def _grid(scene: Mapping[str, Any]) -> bool:
    if not _int(scene.get("size"), 1, MAX_SIDE):
        return False
    size = int(scene["size"])
    return all(scene.get(key) is None or _cell(scene.get(key), size, size)
               for key in ("agent", "target")) and _cells(scene.get("walls", []), size, size)


def _tile(scene: Mapping[str, Any]) -> bool:
    cells = scene.get("cells")
    if not (_int(scene.get("rows"), 1, MAX_SIDE) and _int(scene.get("cols"), 1, MAX_SIDE)
            and isinstance(cells, list)):
        return False
    rows, cols = int(scene["rows"]), int(scene["cols"])
    if len(cells) != rows or not all(isinstance(line, str) and len(line) == cols for line in cells):
        return False
    return (all(scene.get(key) is None or _cell(scene.get(key), rows, cols)
                for key in ("agent", "cursor"))
            and all(_cell_table(scene.get(key), rows, cols) for key in ("rewards", "slip", "marks"))
            and _word(scene.get("theme")) and _word(scene.get("last_action")))


def _taxi(scene: Mapping[str, Any]) -> bool:
    rows, cols = scene.get("rows", 5), scene.get("cols", 5)
    if not (_int(rows, 1, MAX_SIDE) and _int(cols, 1, MAX_SIDE)):
        return False
    stands, names = scene.get("stands", []), scene.get("stand_names", [])
    return (
        (scene.get("taxi") is None or _cell(scene.get("taxi"), rows, cols))
        and isinstance(stands, list) and len(stands) <= MAX_ITEMS and _cells(stands, rows, cols)
        and isinstance(names, list) and len(names) <= MAX_ITEMS and all(map(_word, names))
        and _cells(scene.get("walls", []), rows, cols)
        and _optional_int(scene.get("passenger"), 0, MAX_ITEMS)
        and _optional_int(scene.get("destination"), 0, MAX_ITEMS)
        and _word(scene.get("last_action"))
    )


def _text(scene: Mapping[str, Any]) -> bool:
    text, actions = scene.get("text"), scene.get("actions", [])
    return ((text is None or (isinstance(text, str) and len(text) <= MAX_TEXT))
            and (scene.get("state") is None or _int(scene.get("state"), 0, 2**62))
            and isinstance(actions, list) and len(actions) <= MAX_ITEMS
            and all(_word(a) for a in actions))


_CHECKS: dict[str, Callable[[Mapping[str, Any]], bool]] = {
    "cards": _cards, "grid": _grid, "tile": _tile, "taxi": _taxi, "text": _text,
}


def scene_fits(board: str, scene: Mapping[str, Any]) -> bool:
    """Whether the board of kind `board` can draw `scene` (any, for a kind there is none of)."""
    check = _CHECKS.get(board)
    return check is None or check(scene)
