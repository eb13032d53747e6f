"""Writing a map file atomically, through the save files' own checks and writer."""

from __future__ import annotations

from pathlib import Path

from tui_gym.games.maps import GridMap, MapError, format_map
from tui_gym.session.storage import StorageError, atomic_write_bytes, check_save_path

__all__ = ["write_map_file"]


def write_map_file(path: str | Path, grid_map: GridMap, comment: str = "") -> Path:
    """Write the map through a temporary file and a rename, so an old file stays whole
    until the new one is; `MapError` when the path cannot take it."""
    try:
        target = check_save_path(path)
        atomic_write_bytes(target, format_map(grid_map, comment).encode())
    except StorageError as error:
        raise MapError(str(error)) from None
    except OSError as exc:
        raise MapError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return target
