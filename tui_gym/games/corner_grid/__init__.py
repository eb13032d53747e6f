"""corner-grid: Sutton & Barto's Example 4.1, the 4 x 4 grid with two terminal corners.

Spaces and rewards: `tui_gym.envs.dp_grid.CornerGridEnv`; truncated after 100 steps.
"""

from __future__ import annotations

from tui_gym.envs.dp_grid import CORNER_GRID
from tui_gym.games.base import ReachNarrator
from tui_gym.games.dp_grid import DPGridGame

__all__ = ["CornerGridGame"]


class CornerNarrator(ReachNarrator):
    """Reached a corner, or ran out of time."""

    reached_words = "Reached a corner"


class CornerGridGame(DPGridGame):
    """Walk to either corner; every step costs 1."""

    name = "corner-grid"
    title = "Corner grid"
    env_id = "tui_gym/CornerGrid-v0"
    key = "K"
    description = "Example 4.1's 4x4 grid: every move costs 1 until a terminal corner."
    teaches = "policy evaluation: the random policy's values, then one greedy step to optimal"
    hyperparameters = {"*": {"learning_rate": 0.1, "episodes": 2_000}}

    fixed_grid = CORNER_GRID
    narrator_type = CornerNarrator
