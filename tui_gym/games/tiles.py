"""Grid-map games: what FrozenLake and CliffWalking share.

A grid-map game is a `ModelGame` whose states are the cells of a map, row by
row (state = row * cols + col), with four moves named left, down, right, up
in the env's own action order. This module gives such a game:

- `TileStates`: a cell in words, and the tile board's scene (the map as rows
  of S F H G C letters, the agent, the last move and whether it slipped);
- `TileLayout`: one heatmap panel shaped like the map, the greedy move's
  arrow in each cell, the tiles with no decision drawn as themselves;
- `TileNarrator`: words for reaching the goal, falling and running out of time.

A game says how its map reads (`cells(kwargs)`), its board theme and words.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.games.base import UNREADABLE, EvalOutcome, HeatmapLayout, Narrator, TallyWord
from tui_gym.games.model import DiscreteStates, ModelGame
from tui_gym.games.words import format_reward, plural

if TYPE_CHECKING:
    from tui_gym.core.play import PlayStep

__all__ = ["MOVES", "TileGame", "TileLayout", "TileNarrator", "TileStates"]

MOVES: dict[str, tuple[int, int]] = {
    "left": (0, -1), "down": (1, 0), "right": (0, 1), "up": (-1, 0)
}
ARROWS = {"left": "←", "down": "↓", "right": "→", "up": "↑"}
TILE_WORDS = {"S": "start", "F": "floor", "H": "hole", "G": "goal", "C": "cliff"}
NO_DECISION = {"H": "○", "G": "★", "C": "▒"}  # tiles the agent never acts on
TIED = "·"


class TileGame(ModelGame):
    """A `ModelGame` played on a map of tiles (see the module docstring)."""

    board = "tile"
    action_names = ("left", "down", "right", "up")
    theme = "plain"  # the tile board's theme: "lake", "cliff" or "plain"
    floor_word = "floor"  # what a floor tile is called

    def cells(self, kwargs: Mapping[str, Any]) -> list[str]:
        """The map, one string a row: S start, F floor, H hole, G goal, C cliff."""
        raise NotImplementedError

    def slip_probability(self, kwargs: Mapping[str, Any]) -> float:
        """The chance a move goes elsewhere than asked (0 when it never does)."""
        return 0.0


def _game(role: Any) -> TileGame:
    game = role.game
    assert isinstance(game, TileGame)
    return game


class TileStates(DiscreteStates):
    """Cells of the map; the tile board's scene; the map as text."""

    def text(
        self, env: Any, reveal: bool = True, before: Mapping[str, Any] | None = None
    ) -> str:
        scene = self.scene(env, before)
        return tile_text(scene, _game(self)) if scene else ""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        cells = _game(self).cells(kwargs)
        row, col = divmod(int(observation), len(cells[0]))
        tile = cells[row][col]
        word = _game(self).floor_word if tile == "F" else TILE_WORDS.get(tile, "floor")
        return f"row {row}, col {col} ({word})"

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        game = _game(self)
        cells = _env_cells(game_env)
        cols = len(cells[0])
        state = game_env.s
        agent = None if state is None else divmod(int(state), cols)
        last = getattr(game_env, "lastaction", None)
        action = game.action_names[int(last)] if last is not None else None
        scene: dict[str, Any] = {
            "rows": len(cells),
            "cols": cols,
            "cells": cells,
            "theme": game.theme,
            "agent": agent,
            "last_action": action,
            "slipped": _slipped(cells, before.get("agent"), agent, action),
        }
        slip = _slip_chance(game_env, cells)
        if slip > 0:
            scene["slip"] = {f"{r},{c}": slip for r, line in enumerate(cells)
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
    words = [f"{tile} {TILE_WORDS[tile] if tile != 'F' else game.floor_word}"
             for tile in "SFHGC" if tile in kinds]
    legend = ", ".join([f"{AGENT_TEXT} you", *words])
    return "\n".join([*lines, legend])


def _env_cells(game_env: Any) -> list[str]:
    """The map of a built env: FrozenLake's `desc`, or a cliff map from its shape."""
    desc = getattr(game_env, "desc", None)
    if desc is not None:
        return ["".join(c.decode() if isinstance(c, bytes) else str(c) for c in row)
                for row in np.asarray(desc)]
    rows, cols = game_env.shape
    cliff = np.asarray(game_env._cliff)
    out = []
    for r in range(rows):
        line = ["C" if cliff[r, c] else "F" for c in range(cols)]
        out.append("".join(line))
    out[rows - 1] = "S" + out[rows - 1][1:-1] + "G"
    return out


def _slip_chance(game_env: Any, cells: Sequence[str]) -> float:
    """The chance a move from the start goes elsewhere than asked, read from the table."""
    row, col = _start(cells)
    outcomes = game_env.P[row * len(cells[0]) + col][0]
    return round(1.0 - max(float(o[0]) for o in outcomes), 6)


def _slipped(cells: Sequence[str], before: Any, agent: Any, action: str | None) -> bool:
    """Whether the move went elsewhere than asked (a fall off a cliff is not a slip)."""
    if before is None or agent is None or action is None:
        return False
    row, col = (int(v) for v in before)
    dr, dc = MOVES[action]
    rows, cols = len(cells), len(cells[0])
    intended = (min(max(row + dr, 0), rows - 1), min(max(col + dc, 0), cols - 1))
    if cells[intended[0]][intended[1]] == "C":
        return tuple(agent) != _start(cells)
    return tuple(int(v) for v in agent) != intended


def _start(cells: Sequence[str]) -> tuple[int, int]:
    for r, line in enumerate(cells):
        if "S" in line:
            return r, line.index("S")
    return 0, 0


class TileLayout(HeatmapLayout):
    """One panel shaped like the map: max Q colours each cell, the greedy move's arrow."""

    def heatmaps(
        self,
        q: np.ndarray,
        kwargs: Mapping[str, Any],
        focus: Any = None,
        marks: Any = None,
    ) -> list[Heatmap]:
        game = _game(self)
        try:
            cells = game.cells(kwargs)
        except UNREADABLE:
            return []
        rows, cols = len(cells), len(cells[0])
        if np.shape(q) != (rows * cols, len(game.action_names)):
            return []
        values = np.full((rows, cols), np.nan)
        marked = np.zeros((rows, cols), dtype=bool)
        has_marks = isinstance(marks, np.ndarray) and marks.shape == np.shape(q)
        labels = []
        for r in range(rows):
            line = []
            for c in range(cols):
                tile = cells[r][c]
                if tile in NO_DECISION:
                    line.append(NO_DECISION[tile])
                    continue
                qs = q[r * cols + c]
                values[r, c] = float(qs.max())
                if (qs == qs[0]).all():
                    line.append(TIED)
                    continue
                action = int(np.argmax(qs))
                line.append(ARROWS[game.action_names[action]])
                marked[r, c] = has_marks and not marks[r * cols + c, action]
            labels.append(tuple(line))
        shown = "".join(sorted({t for line in cells for t in line if t in NO_DECISION}))
        tiles = "  ".join(f"{NO_DECISION[t]} {TILE_WORDS[t]}" for t in "HGC" if t in shown)
        return [
            Heatmap(
                title="max Q and the greedy move",
                row_labels=tuple(str(r) for r in range(rows)),
                col_labels=tuple(str(c) for c in range(cols)),
                values=values,
                labels=tuple(labels),
                marked=marked,
                legend=f"arrow: greedy move  {TIED} tie  {tiles}  * not an optimal move",
            )
        ]


class TileNarrator(Narrator):
    """Reached the goal, fell, or ran out of time."""

    tally_words: tuple[TallyWord, ...] = (
        TallyWord("reached", "good"),
        TallyWord("fell in", "bad", always=False),
        TallyWord("timed out", "even"),
    )

    def tally_word(self, last: PlayStep) -> str:
        if not last.terminated:
            return "timed out"
        return "reached" if last.episode_return > 0 or not self.holes else "fell in"

    holes = True  # a terminal tile that is not the goal exists (FrozenLake's holes)

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        steps = plural(last.steps, "step")
        total = format_reward(last.episode_return)
        if not last.terminated:
            return f"Out of time after {steps}: the goal not reached, return {total}"
        agent, cells = scene.get("agent"), scene.get("cells") or []
        tile = ""
        if agent is not None and cells:
            tile = cells[int(agent[0])][int(agent[1])]
        if tile == "H":
            return f"Fell into a hole after {steps}, return {total}"
        return f"Reached the goal in {steps}, return {total}"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        return f"{plural(last.steps, 'step')} taken" if last.steps else ""

    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        n = max(1, len(details))
        ended = [d for d in details if d["terminated"]]
        reached = [d for d in ended if d["return"] > 0 or not self.holes]
        return EvalOutcome(figures={
            "success_rate": len(reached) / n,
            "timeout_rate": (len(details) - len(ended)) / n,
        })
