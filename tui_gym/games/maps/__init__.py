"""Maps of the grid games: edited, saved, loaded, listed and drawn at random."""

from tui_gym.games.maps.grid_map import MAX_SIDE, TOOLS, GridMap, Tool
from tui_gym.games.maps.text import (
    LAYOUT,
    MapError,
    format_map,
    layout_map,
    parse_map,
    read_layout,
)

__all__ = ["LAYOUT", "MAX_SIDE", "TOOLS", "GridMap", "MapError", "Tool", "format_map",
           "layout_map", "parse_map", "read_layout"]
