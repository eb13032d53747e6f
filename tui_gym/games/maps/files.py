"""Map files: read as carefully as save files, written atomically."""

from __future__ import annotations

from pathlib import Path

from tui_gym.core.files import read_regular_file
from tui_gym.games.maps.grid_map import GridMap
from tui_gym.games.maps.text import MAX_TEXT, MapError, format_map, parse_map

__all__ = ["MAX_FILE_BYTES", "read_map_file", "read_map_text", "write_map_file"]

MAX_FILE_BYTES = MAX_TEXT * 4  # UTF-8 takes at most four bytes a character


def _too_big(size: int | None) -> str:
    if size is None:
        return f"over {MAX_FILE_BYTES:,} bytes; not a map file"
    return f"{size:,} bytes; a map file is at most {MAX_FILE_BYTES:,}"


def read_map_text(path: str | Path) -> str:
    """The text of a map file, checked to be one that can be read (not yet parsed)."""
    path = Path(path)
    data = read_regular_file(path, MAX_FILE_BYTES, "a map file",
                             lambda why: MapError(f"{path}: {why}"), _too_big)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise MapError(f"{path}: not UTF-8 text (byte {error.start})") from None


def read_map_file(path: str | Path) -> GridMap:
    """The map a file holds; `MapError` naming the file and what is wrong where."""
    text = read_map_text(path)
    try:
        return parse_map(text)
    except MapError as error:
        raise MapError(f"{path}: {error}") from None


def write_map_file(path: str | Path, grid_map: GridMap, comment: str = "") -> Path:
    """Write the map atomically; `MapError` when the path cannot take it."""
    from tui_gym.core.files import OutputPathError, write_atomically

    try:
        target = write_atomically(path, format_map(grid_map, comment))
    except OutputPathError as error:
        raise MapError(str(error)) from None
    except OSError as exc:
        raise MapError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return target
