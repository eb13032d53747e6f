"""The map editor's figure: from an edit to the new optimum, on a 12x12 map."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

import numpy as np

from tui_gym.core.mdp import NotAvailable
from tui_gym.games import GAMES, Game
from tui_gym.games.maps.random_map import random_map
from tui_gym.session.session import Session

MAP_SIDE = 12
TOOLS = (("wall", None), ("hole", -1.0), ("reward", 0.5), ("ice", 0.3))


@dataclass(frozen=True)
class MapEditResult:
    """One game's edit-to-optimum times, in milliseconds."""

    game: str
    size: str
    edits: int
    median_ms: float
    worst_ms: float
    kept_agent: bool  # every edit kept the agent (the states kept their meaning)


def _one_game(game: Game, edits: int, seed: int) -> MapEditResult:
    rng = np.random.default_rng(seed)
    grid_map = random_map(MAP_SIDE, MAP_SIDE, 0.15, seed)
    session = Session(game.env_id, env_kwargs=game.with_map({}, grid_map), seed=seed,
                      hp={"episodes": 1_000})
    agent, kept, times = session.agent, True, []
    for i in range(edits):
        tool, value = TOOLS[i % len(TOOLS)]
        cell = (int(rng.integers(MAP_SIDE)), int(rng.integers(MAP_SIDE)))
        if grid_map.tile(cell) in "SG":
            cell = (1, 1) if grid_map.tile((1, 1)) not in "SG" else (2, 2)
        started = time.perf_counter()
        grid_map = grid_map.painted(cell, tool, value)
        session.rebuild(env_kwargs=game.with_map(session.env_kwargs, grid_map))
        solution = game.solution(session.env_kwargs)
        if isinstance(solution, NotAvailable) or solution.q is None:
            raise RuntimeError(f"{game.title}: no optimum for an edited map")
        game.layout.heatmaps(solution.q, session.env_kwargs, None, solution.marks)
        times.append((time.perf_counter() - started) * 1000)
        kept = kept and session.agent is agent
    return MapEditResult(game.title, f"{MAP_SIDE}x{MAP_SIDE}", edits,
                         statistics.median(times), max(times), kept)


def measure(edits: int = 40, seed: int = 0) -> list[MapEditResult]:
    """Edit-to-optimum times on each grid game with tiles (see the module docstring)."""
    return [_one_game(g, edits, seed) for g in GAMES if g.editable and "start" in g.map_tools]
