"""Map files: read as carefully as save files, written atomically."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from tui_gym.games.maps.grid_map import GridMap
from tui_gym.games.maps.text import MAX_TEXT, MapError, format_map, parse_map

__all__ = ["MAX_FILE_BYTES", "read_map_file", "read_map_text", "write_map_file"]

MAX_FILE_BYTES = MAX_TEXT * 4  # UTF-8 takes at most four bytes a character

_KINDS = (
    (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device"),
    (stat.S_ISSOCK, "a socket"),
)


def _read_bytes(path: Path) -> bytes:
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise MapError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise MapError(f"{path}: is a folder, not a map file") from None
    except OSError as exc:
        raise MapError(f"{path}: cannot read ({exc.strerror or exc})") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise MapError(f"{path}: is a folder, not a map file")
        if not stat.S_ISREG(info.st_mode):
            kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a file")
            raise MapError(f"{path}: is {kind}, not a map file")
        if info.st_size > MAX_FILE_BYTES:
            raise MapError(f"{path}: {info.st_size:,} bytes; a map file is at most "
                           f"{MAX_FILE_BYTES:,}")
        data = os.read(fd, MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise MapError(f"{path}: over {MAX_FILE_BYTES:,} bytes; not a map file")
        return data
    except OSError as exc:
        raise MapError(f"{path}: cannot read ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def read_map_text(path: str | Path) -> str:
    """The text of a map file, checked to be one that can be read (not yet parsed)."""
    path = Path(path)
    data = _read_bytes(path)
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
