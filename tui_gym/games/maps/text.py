"""Maps as text: FrozenLake's rows of tiles, with a small header for rewards and slip."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

from tui_gym.core.params import read_number, shown_value
from tui_gym.envs.tile_map import TILE_LIST, check_map
from tui_gym.games.maps.grid_map import MAX_SIDE, Cell, GridMap

__all__ = ["LAYOUT", "MAX_TEXT", "MapError", "format_map", "layout_map", "parse_map", "read_layout"]

LAYOUT = "layout"  # the argument of a grid game that holds an edited map, as text
MAX_TEXT = 64 << 10  # characters of a map's text, at most
_HEADER = re.compile(r"(reward|slip)\s+([0-9]{1,4})\s*,\s*([0-9]{1,4})\s*[:=]?\s*(\S+)",
                     re.ASCII | re.IGNORECASE)
_KEYWORD = re.compile(r"(reward|slip)\b", re.IGNORECASE)


class MapError(ValueError):
    """A map that cannot be read; the message is one line naming where (line, row, column)."""


def parse_map(text: str) -> GridMap:
    """The map `text` holds (see the module docstring); `MapError` when it holds none."""
    if len(text) > MAX_TEXT:
        raise MapError(f"{len(text):,} characters: a map's text is at most {MAX_TEXT:,}")
    rows: list[str] = []
    row_lines: list[int] = []
    header: dict[str, dict[Cell, tuple[float, int]]] = {"reward": {}, "slip": {}}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if _KEYWORD.match(line):
            _header_line(line, number, header)
            continue
        if len(rows) >= MAX_SIDE:
            raise MapError(f"line {number}: a map has at most {MAX_SIDE} rows")
        if len(line) > MAX_SIDE:
            raise MapError(f"line {number} (map row {len(rows)}) has {len(line)} tiles: at most "
                           f"{MAX_SIDE}")
        rows.append(line)
        row_lines.append(number)
    if not rows:
        raise MapError(f"no rows of tiles: a map is rows of tiles ({TILE_LIST})")

    def where(cell: Cell) -> str:  # a cell by its line of the text
        r, c = cell
        if r < len(rows) and c < len(rows[r]):
            return f"line {row_lines[r]} (map row {r}), column {c}"
        return f"row {r}, col {c}"

    rewards = {c: v for c, (v, _) in header["reward"].items()}
    slip = {c: v for c, (v, _) in header["slip"].items()}
    try:
        check_map(rows, rewards, slip, need_start=False, where=where)
        return GridMap.of(rows, rewards, slip)
    except ValueError as error:
        raise MapError(str(error)) from None


@lru_cache(maxsize=64)
def read_layout(text: str) -> GridMap:
    """`parse_map`, kept: the same text (a game's `layout` argument) is read once."""
    return parse_map(text)


def layout_map(kwargs: Mapping[str, Any]) -> GridMap | None:
    """The map a game's `LAYOUT` argument holds (None without one)."""
    layout = kwargs.get(LAYOUT)
    return read_layout(str(layout)) if layout else None


def _header_line(line: str, number: int, header: dict[str, dict[Cell, tuple[float, int]]]) -> None:
    match = _HEADER.fullmatch(line)
    if match is None:
        raise MapError(f"line {number}: a header line reads 'reward ROW,COL: VALUE' or "
                       f"'slip ROW,COL: P', got {line[:40]!r}")
    key, row, col, value = match.groups()
    key = key.lower()
    cell = (int(row), int(col))
    amount = read_number(value)
    if amount is None or not math.isfinite(amount):
        raise MapError(f"line {number}: the {key} at row {cell[0]}, col {cell[1]} must be a "
                       f"finite number, got {shown_value(value)}")
    if key == "slip" and not 0.0 <= amount <= 1.0:
        raise MapError(f"line {number}: the slip at row {cell[0]}, col {cell[1]} must be in "
                       f"[0, 1], got {shown_value(value)}")
    earlier = header[key].get(cell)
    if earlier is not None:
        raise MapError(f"line {number}: {key} {row},{col} is given twice (first on line "
                       f"{earlier[1]})")
    header[key][cell] = (amount, number)


def _number_text(value: float) -> str:
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def format_map(grid_map: GridMap, comment: str = "") -> str:
    """The map as text that `parse_map` reads back the same (a `# comment` line first)."""
    lines = [f"# {line}" for line in comment.splitlines()]
    lines += [f"reward {r},{c}: {_number_text(v)}" for (r, c), v in grid_map.rewards]
    lines += [f"slip {r},{c}: {_number_text(v)}" for (r, c), v in grid_map.slip]
    lines += list(grid_map.cells)
    return "\n".join(lines) + "\n"
