"""Grid-map games: what FrozenLake and CliffWalking share."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP, NotAvailable
from tui_gym.envs import TILE_MAP_ID
from tui_gym.envs.dp_grid import STEPS
from tui_gym.envs.tile_map import TILE_NAMES, TileMapEnv, TileRules, cell_key, tile_grid
from tui_gym.games.base import (
    TIED,
    UNREADABLE,
    EvalOutcome,
    HeatmapLayout,
    ReachNarrator,
    TallyWord,
    greedy_panel,
    numbered,
)
from tui_gym.games.dp_grid import ARROWS
from tui_gym.games.maps import LAYOUT, GridMap, MapError, format_map, layout_map, read_layout
from tui_gym.games.model import DiscreteStates, ModelGame
from tui_gym.games.words import format_reward, plural

if TYPE_CHECKING:
    from tui_gym.session.play import PlayStep

__all__ = ["CUSTOM", "LAYOUT", "TileGame", "TileLayout", "TileNarrator", "TileStates"]

CUSTOM = "custom"  # the `map` choice of an edited map

NO_DECISION = {"H": "○", "G": "★", "C": "▒", "W": "█"}  # tiles the agent never acts on


class TileStates(DiscreteStates):
    """Cells of the map; the tile board's scene; the map as text."""

    game: TileGame

    def text(self, env: Any, reveal: bool = True, before: Mapping[str, Any] | None = None) -> str:
        scene = self.scene(env, before)
        return tile_text(scene, self.game) if scene else ""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        cells = self.game.cells(kwargs)
        row, col = divmod(int(observation), len(cells[0]))
        tile = cells[row][col]
        word = self.game.floor_word if tile == "F" else TILE_NAMES.get(tile, "floor")
        return f"row {row}, col {col} ({word})"

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        game = self.game
        cells = _env_cells(game_env, game)
        cols = len(cells[0])
        state = game_env.s
        agent = None if state is None else divmod(int(state), cols)
        last = getattr(game_env, "lastaction", None)
        action = game.action_names[int(last)] if last is not None else None
        scene: dict[str, Any] = {
            "rows": len(cells), "cols": cols, "cells": cells, "theme": game.theme, "agent": agent,
            "last_action": action, "slipped": _slipped(cells, before.get("agent"), agent, action),
        }
        if isinstance(game_env, TileMapEnv):
            scene["rewards"] = {cell_key(c): v for c, v in game_env.rewards.items()}
            scene["slip"] = {cell_key(c): p for c, p in game_env.grid.slip.items()}
            return scene
        row, col = _start(cells)  # the chance a move from the start goes elsewhere than asked
        outcomes = game_env.P[row * len(cells[0]) + col][0]
        slip_chance = round(1.0 - max(float(o[0]) for o in outcomes), 6)
        if slip_chance > 0:
            scene["slip"] = {f"{r},{c}": slip_chance for r, line in enumerate(cells)
                             for c, tile in enumerate(line) if tile in "SF"}
        return scene


AGENT_TEXT = "@"  # the agent's cell in the text picture


def tile_text(scene: Mapping[str, Any], game: TileGame) -> str:
    """The map as text, the agent's cell shown as `@`, and what the last move did."""
    cells = [list(line) for line in scene.get("cells", [])]
    agent = scene.get("agent")
    if agent is not None and cells:
        cells[int(agent[0])][int(agent[1])] = AGENT_TEXT
    lines = ["".join(line) for line in cells]
    action = scene.get("last_action")
    if action:
        lines.append(f"({action}{', slipped' if scene.get('slipped') else ''})")
    kinds = {tile for line in scene.get("cells", []) for tile in line}
    words = [f"{tile} {TILE_NAMES[tile] if tile != 'F' else game.floor_word}"
             for tile in "SFHGC" if tile in kinds]
    legend = ", ".join([f"{AGENT_TEXT} you", *words])
    return "\n".join([*lines, legend])


def _env_cells(game_env: Any, game: TileGame) -> list[str]:
    """The map of a built env: its `desc` (FrozenLake's, a tile map's), else (CliffWalking's
    env, which has none) the game's own map."""
    desc = getattr(game_env, "desc", None)
    if desc is None:
        return game.builtin_cells({})
    return ["".join(c.decode() if isinstance(c, bytes) else str(c) for c in row)
            for row in np.asarray(desc)]


def _slipped(cells: Sequence[str], before: Any, agent: Any, action: str | None) -> bool:
    """Whether the move went elsewhere than asked (a fall off a cliff is not a slip)."""
    if before is None or agent is None or action is None:
        return False
    row, col = (int(v) for v in before)
    dr, dc = STEPS[action]
    rows, cols = len(cells), len(cells[0])
    intended = (min(max(row + dr, 0), rows - 1), min(max(col + dc, 0), cols - 1))
    if cells[intended[0]][intended[1]] == "C":
        return tuple(agent) != _start(cells)
    return tuple(int(v) for v in agent) != intended


def _start(cells: Sequence[str]) -> tuple[int, int]:
    return next((r, line.index("S")) for r, line in enumerate(cells) if "S" in line)


class TileLayout(HeatmapLayout):
    """One panel shaped like the map: max Q colours each cell, the greedy move's arrow."""

    game: TileGame

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        game = self.game
        try:
            cells = game.cells(kwargs)
        except UNREADABLE:
            return []
        rows, cols = len(cells), len(cells[0])
        if np.shape(q) != (rows * cols, len(game.action_names)):
            return []
        has_marks = isinstance(marks, np.ndarray) and marks.shape == np.shape(q)
        shown = "".join(sorted({t for line in cells for t in line if t in NO_DECISION}))
        tiles = "  ".join(f"{NO_DECISION[t]} {TILE_NAMES[t]}" for t in "HGCW" if t in shown)
        return [greedy_panel(
            "max Q and the greedy move",
            f"arrow: greedy move  {TIED} tie  {tiles}  * not an optimal move",
            numbered(rows), numbered(cols), lambda r, c: NO_DECISION.get(cells[r][c]),
            lambda r, c: q[r * cols + c], lambda action: ARROWS[game.action_names[action]],
            lambda r, c, action: has_marks and not marks[r * cols + c, action],
        )]


class TileNarrator(ReachNarrator):
    """Reached the goal, fell, or ran out of time."""

    tally_words: tuple[TallyWord, ...] = (
        TallyWord("reached", "good"), TallyWord("fell in", "bad", always=False),
        TallyWord("timed out", "even"),
    )
    missed_words = ": the goal not reached"
    holes = True  # a terminal tile that is not the goal exists (FrozenLake's holes)

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        agent, cells = scene.get("agent"), scene.get("cells") or []
        fell = agent is not None and bool(cells) and cells[int(agent[0])][int(agent[1])] == "H"
        if last.terminated and fell:
            return (f"Fell into a hole after {plural(last.steps, 'step')}, return "
                    f"{format_reward(last.episode_return)}")
        return super().outcome_text(last, first_info, scene)

    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        n = max(1, len(details))
        ended = [d for d in details if d["terminated"]]
        reached = [d for d in ended if d["return"] > 0 or not self.holes]
        return EvalOutcome(figures={
            "success_rate": len(reached) / n, "timeout_rate": (len(details) - len(ended)) / n,
        })


class TileGame(ModelGame):
    """A `ModelGame` played on a map of tiles (see the module docstring)."""

    board = "tile"
    action_names = ("left", "down", "right", "up")
    action_order = "lake"  # `TileMapEnv`'s numbering of the moves: "lake" or "cliff"
    theme = "plain"  # the tile board's theme: "lake", "cliff" or "plain"
    floor_word = "floor"  # what a floor tile is called
    editable = True  # the app's map editor edits its maps
    map_tools = ("floor", "wall", "hole", "goal", "start", "reward", "ice", "cliff")

    states_type = TileStates
    narrator_type = TileNarrator
    layout_type = TileLayout

    def builtin_cells(self, kwargs: Mapping[str, Any]) -> list[str]:
        """The map the parameters choose, one string a row (S F H G C tiles)."""
        raise NotImplementedError

    def rules(self, kwargs: Mapping[str, Any]) -> TileRules:
        """What tiles pay and how they slip where a map does not say."""
        return TileRules()

    def grid_map(self, kwargs: Mapping[str, Any]) -> GridMap:
        """The map played: the edited one (`layout`), else the one the parameters choose."""
        return layout_map(kwargs) or GridMap.of(self.builtin_cells(kwargs))

    def cells(self, kwargs: Mapping[str, Any]) -> list[str]:
        """The map played, one string a row: S start, F floor, H hole, G goal, C cliff,
        W wall, R reward cell."""
        return list(self.grid_map(kwargs).cells)

    def with_map(self, kwargs: Mapping[str, Any], grid_map: GridMap) -> dict[str, Any]:
        if grid_map.start is None:
            raise ValueError(f"{self.title} needs a start (S) on the map")
        return {**kwargs, "map": CUSTOM, LAYOUT: format_map(grid_map)}

    def normalize_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """As `Game.normalize_kwargs`, with `layout`: an edited map, kept (as its text) when
        `map` is "custom" or not given; another map choice drops it."""
        rest = dict(kwargs)
        layout = rest.pop(LAYOUT, None)
        out = super().normalize_kwargs(rest)
        if layout is not None and rest.get("map", CUSTOM) == CUSTOM:
            try:
                grid_map = read_layout(str(layout))
            except MapError as error:
                raise ValueError(f"{self.title} map: {error}") from None
            return self.with_map(out, grid_map)
        if out.get("map") == CUSTOM:
            raise ValueError("map 'custom' is an edited map: give one with --map-file PATH, "
                             "or edit one in the app (m)")
        return out

    def make_id(self, env_id: str, kwargs: Mapping[str, Any]) -> str:
        return TILE_MAP_ID if kwargs.get(LAYOUT) else env_id

    def make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """`builtin_make_kwargs`, or what `tui_gym/TileMap-v0` takes to play an edited map."""
        if not kwargs.get(LAYOUT):
            return self.builtin_make_kwargs(kwargs)
        rules = self.rules(kwargs)
        return {
            **self.grid_map(kwargs).env_kwargs(), "slip_default": rules.slip,
            "actions": self.action_order, "step_reward": rules.step, "goal_reward": rules.goal,
            "hole_reward": rules.hole, "cliff_reward": rules.cliff,
            "max_episode_steps": self.episode_limit(kwargs),
        }

    def builtin_make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """What `gym.make` takes for the map the parameters choose."""
        return {}

    def episode_limit(self, kwargs: Mapping[str, Any]) -> int | None:
        if kwargs.get(LAYOUT):
            return self.map_limit(self.grid_map(kwargs))
        return super().episode_limit(kwargs)  # the limit `builtin_make_kwargs` or Gymnasium sets

    def map_limit(self, grid_map: GridMap) -> int:
        """The episode limit of an edited map: FrozenLake's (100 steps up to four rows, else
        200), more on a map so large that a walk across may need it."""
        return 100 if grid_map.rows <= 4 else max(200, 2 * grid_map.rows * grid_map.cols)

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP | NotAvailable:
        if not kwargs.get(LAYOUT):
            return super().base_model(kwargs)
        try:
            grid_map = self.grid_map(kwargs)
        except MapError as error:
            return NotAvailable(f"the map cannot be read: {error}")
        return tile_grid(grid_map.cells, grid_map.reward_table(), grid_map.slip_table(),
                         self.action_names, self.rules(kwargs)).model
