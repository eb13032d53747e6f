"""Random maps that can be solved: a size, a density of obstacles and a seed."""

from __future__ import annotations

import numpy as np

from tui_gym.games.maps.grid_map import MAX_SIDE, GridMap

__all__ = ["MAX_DENSITY", "random_map"]

MAX_DENSITY = 0.8
ATTEMPTS = 2000  # draws before giving up on a density too high to leave a way through


def random_map(
    rows: int, cols: int, density: float = 0.2, seed: int = 0, obstacle: str = "H",
    walled: bool = False,
) -> GridMap:
    """A map that can be solved (see the module docstring); `ValueError` for arguments out
    of range, or when no draw leaves a way through."""
    if not (2 <= rows <= MAX_SIDE and 2 <= cols <= MAX_SIDE):
        raise ValueError(f"a random map is 2 to {MAX_SIDE} tiles a side, not {rows}x{cols}")
    if not 0.0 <= density <= MAX_DENSITY:
        raise ValueError(f"the density must be in [0, {MAX_DENSITY}], got {density}")
    if obstacle not in "HCW" or len(obstacle) != 1:
        raise ValueError(f"the obstacle is H (hole), C (cliff) or W (wall), not {obstacle!r}")
    rng = np.random.default_rng(seed)
    for _ in range(ATTEMPTS):
        fill = rng.random((rows, cols)) < density
        tile = "W" if walled else obstacle
        cells = [[tile if f else "F" for f in line] for line in fill]
        if not walled:
            cells[0][0], cells[rows - 1][cols - 1] = "S", "G"
        grid_map = GridMap.of("".join(line) for line in cells)
        solved = grid_map.free_connected() if walled else grid_map.goal_reachable()
        if solved and sum(row.count("W") for row in grid_map.cells) <= rows * cols - 2:
            return grid_map
    raise ValueError(f"no {rows}x{cols} map with a way through was drawn at density {density}; "
                     "try a lower one")
