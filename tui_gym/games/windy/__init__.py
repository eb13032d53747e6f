"""windy, windy-king: Sutton & Barto's Windy GridWorld (Example 6.5; king's moves, Exercise 6.9).

Spaces, rewards and wind: `tui_gym.envs.dp_grid.WindyGridWorldEnv`; truncated after 2000
steps. The moves are part of a game (keys, protocol, recordings): king's moves are another.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from tui_gym.core.params import Param
from tui_gym.envs.dp_grid import KING_ACTIONS, Cell, Grid, windy_grid
from tui_gym.games.base import ReachNarrator
from tui_gym.games.dp_grid import DPGridGame, Event

__all__ = ["KingWindyGame", "WindyGame"]


MONTE_CARLO_LESSON = (
    "Monte Carlo learns only from episodes that end, and a greedy policy that walks into the "
    "wind may never end one (Sutton & Barto: termination is not guaranteed for all "
    "policies), so its greedy policy need not reach the goal"
)

DOUBLE_Q_LESSON = (
    "Double Q-learning splits its experience between two tables, and once it stops "
    "exploring each sees half the updates of the path it walks, so it may keep a detour "
    "of a step or a few within the budget"
)

# Sarsa's settings, with the longer budget the multi-step on-policy learners need.
ON_POLICY = {"learning_rate": 0.1, "learning_rate_schedule": "visits", "epsilon_final": 0.0,
             "episodes": 5000}


class WindyGame(DPGridGame):
    """Cross the windy grid to the goal; every move costs 1."""

    name = "windy"
    title = "Windy GridWorld"
    env_id = "tui_gym/WindyGridWorld-v0"
    key = "I"
    lessons = {"monte-carlo": MONTE_CARLO_LESSON, "double-q": DOUBLE_Q_LESSON}
    description = ("Example 6.5's 7x10 grid: a wind blows up through the middle columns; "
                   "-1 a move until the goal.")
    teaches = "TD control where moves are not what they seem: Sarsa learns to use the wind"
    king_moves = False
    params = (Param("stochastic_wind", bool, False,
                    help="the wind varies by one a third of the time each way (Exercise 6.10)"),)
    # Sarsa as the book runs it (Figure 6.3: alpha 0.5), exploring less at the end so the greedy
    # policy settles; see `lessons` and the README for the others.
    hyperparameters = {
        "*": {"learning_rate": 0.5, "learning_rate_schedule": "constant",
              "epsilon_start": 0.2, "epsilon_final": 0.01, "episodes": 2000},
        "sarsa": {"learning_rate": 0.1, "learning_rate_schedule": "visits", "epsilon_final": 0.0},
        "double-q": {"learning_rate": 0.05, "learning_rate_schedule": "visits",
                     "epsilon_final": 0.0, "episodes": 10000},
        "monte-carlo": {"learning_rate": 0.1, "learning_rate_schedule": "visits",
                        "epsilon_start": 1.0, "epsilon_final": 0.05},
        "n-step-sarsa": {"n": 2, **ON_POLICY},
        "sarsa-lambda": {"lambda": 0.5, **ON_POLICY},
        "q-lambda": {"lambda": 0.5},
    }

    narrator_type = ReachNarrator

    def grid(self, kwargs: Mapping[str, Any]) -> Grid:
        return windy_grid(self.king_moves, bool(kwargs.get("stochastic_wind", False)))

    def event(self, game_env: Any, before: Mapping[str, Any], was: Cell, now: Cell,
              move: str) -> Event | None:
        grid: Grid = game_env.grid
        if now in grid.terminals:
            return None
        blown = grid.landing(was, move, 0)[0][0] - now[0]  # rows up from where no wind leads
        if blown <= 0:
            return None
        where = "to the top row" if now[0] == 0 else f"{blown} up"
        return f"{{who}} moved {move}, blown {where} by the wind", "slipped"


class KingWindyGame(WindyGame):
    """Windy GridWorld with king's moves (Exercise 6.9)."""

    name = "windy-king"
    title = "Windy GridWorld, king's moves"
    env_id = "tui_gym/WindyGridWorldKing-v0"
    key = "Y"
    description = ("Exercise 6.9: the windy grid with the eight king's moves; -1 a move "
                   "until the goal.")
    teaches = "the same wind with diagonal moves: a shorter path, 7 moves instead of 15"
    action_names = KING_ACTIONS
    king_moves = True
