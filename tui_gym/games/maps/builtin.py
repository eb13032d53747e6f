"""The maps that come with tui-gym, which `tui-gym maps` lists."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from tui_gym.games.maps.grid_map import GridMap
from tui_gym.games.maps.text import parse_map

__all__ = ["BUILTIN_MAPS", "BuiltinMap", "builtin_map", "fits"]

GRIDWORLD_SIDES = range(2, 13)  # GridWorld's sizes


@dataclass(frozen=True)
class BuiltinMap:
    name: str
    description: str
    text: str

    @cached_property
    def grid_map(self) -> GridMap:
        return parse_map(self.text)


def fits(grid_map: GridMap) -> tuple[str, ...]:
    """The grid games that can play a map: FrozenLake and CliffWalking any map with a
    start; GridWorld a square one of floor and walls only."""
    games: list[str] = []
    if grid_map.start is not None:
        games += ["frozenlake", "cliffwalking"]
    square = grid_map.rows == grid_map.cols and grid_map.rows in GRIDWORLD_SIDES
    if square and grid_map.tiles() <= {"F", "W"}:
        games.append("gridworld")
    return tuple(games)


BUILTIN_MAPS: tuple[BuiltinMap, ...] = (
    BuiltinMap("4x4", "FrozenLake's 4x4 lake (Gymnasium's map_name='4x4')",
               "SFFF\nFHFH\nFFFH\nHFFG\n"),
    BuiltinMap("8x8", "FrozenLake's 8x8 lake (Gymnasium's map_name='8x8')",
               "SFFFFFFF\nFFFFFFFF\nFFFHFFFF\nFFFFFHFF\nFFFHFFFF\nFHHFFFHF\nFHFFHFHF\n"
               "FFFHFFFG\n"),
    BuiltinMap("cliff", "the cliff of CliffWalking (Sutton & Barto, Example 6.6)",
               "FFFFFFFFFFFF\nFFFFFFFFFFFF\nFFFFFFFFFFFF\nSCCCCCCCCCCG\n"),
    BuiltinMap("maze", "an 8x8 maze: one way from the start to the goal, and dead ends",
               "SFFWFFFF\nWWFWFWWF\nFFFFFWFF\nFWWWFWFW\nFFFWFFFF\nWWFWWWWF\nFFFFFFWF\n"
               "FWWWWFFG\n"),
    BuiltinMap("bridge", "a narrow bridge over holes, and a long safe way round",
               "FFFFFFF\nFHHHHHF\nSFFFFFG\nFHHHHHF\nFFFFFFF\n"),
    BuiltinMap("detour", "a short way past two pits of -1 and a long one without",
               "reward 1,2: -1\nreward 1,3: -1\nFFFFFF\nSFRRFG\nFWWWWF\nFFFFFF\n"),
    BuiltinMap("rooms", "four rooms joined by doors (GridWorld: floor and walls only)",
               "FFFFWFFFF\nFFFFWFFFF\nFFFFFFFFF\nFFFFWFFFF\nWWFWWWFWW\nFFFFWFFFF\n"
               "FFFFFFFFF\nFFFFWFFFF\nFFFFWFFFF\n"),
    BuiltinMap("pillar", "a 5x5 grid with a wall in the middle (GridWorld)",
               "FFFFF\nFFFFF\nFFWFF\nFFWFF\nFFFFF\n"),
)


def builtin_map(name: str) -> BuiltinMap:
    """A built-in map by name; `KeyError` listing the names for another."""
    for entry in BUILTIN_MAPS:
        if entry.name == name.strip().lower():
            return entry
    names = ", ".join(m.name for m in BUILTIN_MAPS)
    raise KeyError(f"no built-in map named {name!r}; the maps: {names}")
