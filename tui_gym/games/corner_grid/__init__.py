"""corner-grid: Sutton & Barto's Example 4.1, the 4 x 4 grid with two terminal corners.

## Action Space
up (0), down (1), left (2), right (3).

## Observation Space
The cell, `row * 4 + col`; cells 0 (top left) and 15 (bottom right) are
the terminal corners.

## Rewards
-1 for every move, off the grid (the agent stays) and into a corner too.

## Starting State
Any of the 14 cells that are not corners, uniformly.

## Episode End
Terminated on entering a corner; truncated after `EPISODE_LIMIT` steps.

## Arguments
None.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from tui_gym.envs.dp_grid import CORNERS, grid_arrays
from tui_gym.envs.tile_map import TileArrays
from tui_gym.games.base import Narrator, TallyWord
from tui_gym.games.dp_grid import DPGridGame
from tui_gym.games.words import format_reward, plural

__all__ = ["EPISODE_LIMIT", "CornerGridGame"]

EPISODE_LIMIT = 100  # steps (the env's registration)


class CornerNarrator(Narrator):
    """Reached a corner, or ran out of time."""

    tally_words = (TallyWord("reached", "good"), TallyWord("timed out", "even"))

    def tally_word(self, last: Any) -> str:
        return "reached" if last.terminated else "timed out"

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        total = format_reward(last.episode_return)
        if last.terminated:
            return f"Reached a corner in {plural(last.steps, 'step')}, return {total}"
        return f"Out of time after {plural(last.steps, 'step')}, return {total}"

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        return f"{plural(last.steps, 'step')} taken" if last.steps else ""


class CornerGridGame(DPGridGame):
    """Walk to either corner; every step costs 1."""

    name = "corner-grid"
    title = "Corner grid"
    env_id = "tui_gym/CornerGrid-v0"
    key = "K"
    description = "Example 4.1's 4x4 grid: every move costs 1 until a terminal corner."
    teaches = "policy evaluation: the random policy's values, then one greedy step to optimal"
    rows = cols = 4
    terminals = CORNERS
    hyperparameters = {"*": {"learning_rate": 0.1, "episodes": 2_000}}

    def __init__(self) -> None:
        super().__init__()
        self.narrator = CornerNarrator(self)

    def arrays(self) -> TileArrays:
        return grid_arrays(4, 4, step=-1.0, edge=-1.0, terminals=CORNERS)
