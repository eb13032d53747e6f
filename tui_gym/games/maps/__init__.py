"""Maps of the grid games: edited, saved, loaded, listed and drawn at random.

- `grid_map`: `GridMap`, a map of tiles with rewards and slip, and its edits
  (`TOOLS`: floor, wall, hole, goal, start, reward, ice, cliff);
- `text`: the text form (FrozenLake's rows under a small header), `MapError`;
- `files`: reading a map file (checked like a save file) and writing one
  atomically;
- `builtin`: the maps `tui-gym maps` lists;
- `random_map`: random maps that can be solved, from a size, a density and a seed.
"""

from tui_gym.games.maps.grid_map import MAX_SIDE, TOOLS, GridMap, Tool
from tui_gym.games.maps.text import MapError, format_map, parse_map, read_layout

__all__ = ["MAX_SIDE", "TOOLS", "GridMap", "MapError", "Tool", "format_map", "parse_map",
           "read_layout"]
