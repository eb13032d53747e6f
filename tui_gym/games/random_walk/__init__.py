"""random-walk: Sutton & Barto's random walk (Example 6.2; Figure 7.2 with 19 states).

Spaces and rewards: `tui_gym.envs.dp_grid.RandomWalkEnv`; truncated after 1000 steps. The
book's prediction figures evaluate the random policy; as control, always go right.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from tui_gym.core.params import Param
from tui_gym.envs.dp_grid import LEFT_END_PAYS, Cell, Grid, walk_grid
from tui_gym.games.base import ReachNarrator, TallyWord
from tui_gym.games.dp_grid import DPGridGame, DPGridStates, Event
from tui_gym.games.words import format_reward, plural

__all__ = ["RandomWalkGame"]


def _states(kwargs: Mapping[str, Any]) -> int:
    return int(kwargs.get("states", 5))


class WalkStates(DPGridStates):
    """A position by the book's name: 'C', '10', 'the left end'."""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        states = _states(kwargs)
        position = int(observation)
        if not 0 <= position <= states + 1:
            raise ValueError(f"no position {position}")
        if position in (0, states + 1):
            return f"the {'left' if position == 0 else 'right'} end"
        return f"state {walk_grid(states).letters[0, position]}"

    def json_observation(self, observation: Any) -> Any:
        """The position, 0 to states + 1."""
        return int(observation)


class WalkNarrator(ReachNarrator):
    """Off the right end or the left one."""

    tally_words = (TallyWord("right end", "good"), TallyWord("left end", "bad"),
                   TallyWord("truncated", always=False))

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        if not last.terminated:
            return super().outcome_text(last, first_info, scene)
        end = "right" if (scene.get("agent") or (0, 0))[1] else "left"
        return (f"Stepped off the {end} end after {plural(last.steps, 'step')}, return "
                f"{format_reward(last.episode_return)}")


class RandomWalkGame(DPGridGame):
    """Walk left or right until either end."""

    name = "random-walk"
    title = "Random walk"
    env_id = "tui_gym/RandomWalk-v0"
    key = "R"
    description = ("Example 6.2's walk of 5 states (Figure 7.2's of 19): +1 off the right end, "
                   "0 (or -1) off the left.")
    teaches = "prediction: the random policy's values, which TD and Monte Carlo estimate"
    action_names = ("left", "right")
    params = (Param("states", int, 5, 5, 19, help="5 (Example 6.2) or 19 (Figure 7.2)"),)
    # Undiscounted, going back and forth is worth as much as going right: a discount
    # makes the quicker way the better one.
    hyperparameters = {"*": {"discount": 0.9, "learning_rate": 0.1, "episodes": 300}}

    states_type = WalkStates
    narrator_type = WalkNarrator

    def check_kwargs(self, kwargs: Mapping[str, Any]) -> None:
        if _states(kwargs) not in LEFT_END_PAYS:
            raise ValueError(f"Random walk.states must be 5 (Example 6.2) or 19 (Figure 7.2), "
                             f"got {_states(kwargs)}")

    def grid(self, kwargs: Mapping[str, Any]) -> Grid:
        return walk_grid(_states(kwargs))

    def event(self, game_env: Any, before: Mapping[str, Any], was: Cell, now: Cell,
              move: str) -> Event | None:
        grid: Grid = game_env.grid
        if now not in grid.terminals:
            return None
        pay = grid.pays[now]
        side = "left" if now[1] == 0 else "right"
        return (f"{{who}} stepped off the {side} end: {format_reward(pay)}",
                "good" if pay > 0 else "bad" if pay < 0 else "caption")
