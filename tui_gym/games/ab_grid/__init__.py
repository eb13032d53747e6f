"""ab-grid: Sutton & Barto's Example 3.5, the 5 x 5 grid with the special cells A and B.

Spaces and rewards: `tui_gym.envs.dp_grid.ABGridEnv`. Played in undiscounted episodes of 50
steps; planning shows the book's values, discounted by 0.9 with no end (Figures 3.2, 3.5).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from tui_gym.envs.dp_grid import AB_GRID
from tui_gym.games.base import Narrator
from tui_gym.games.dp_grid import DPGridGame
from tui_gym.games.words import format_reward, plural

__all__ = ["ABGridGame"]


class ABGridNarrator(Narrator):
    """Every episode runs to the limit: how much it collected on the way."""

    tally_words = ()  # every episode runs to the limit: the count says it all

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        return (f"{plural(last.steps, 'step')} played, return "
                f"{format_reward(last.episode_return)} (the task never ends: the limit did)")

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        if not last.steps:
            return ""
        return f"{plural(last.steps, 'step')}, return so far {format_reward(last.episode_return)}"


class ABGridGame(DPGridGame):
    """Collect +10 at A and +5 at B on the book's 5 x 5 grid."""

    name = "ab-grid"
    title = "AB grid"
    env_id = "tui_gym/ABGrid-v0"
    key = "B"
    description = "Example 3.5's 5x5 grid: any move from A pays +10 (to A′), from B +5 (to B′)."
    teaches = "discounting in a task that never ends: why A beats B though A′ is farther"
    plan_gamma = 0.9
    hyperparameters = {"*": {"discount": 0.9, "learning_rate": 0.1, "episodes": 2_000}}

    fixed_grid = AB_GRID
    narrator_type = ABGridNarrator
