"""CliffWalking: Gymnasium's `CliffWalking-v1`, Sutton & Barto's Example 6.6.

Gymnasium sets no limit; tui-gym plays it with one of `EPISODE_LIMIT` steps, so that every
policy (one walking into a wall for ever included) has a finite exact value. `map` is
"4x12" or "custom", an edited map given as `layout` (see `tui_gym.games.tiles`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from tui_gym.core.params import Param
from tui_gym.envs.tile_map import TileRules
from tui_gym.games.maps import GridMap
from tui_gym.games.tiles import CUSTOM, TileGame, TileNarrator
from tui_gym.games.words import plural

__all__ = ["EPISODE_LIMIT", "CliffWalkingGame"]

EPISODE_LIMIT = 200  # steps
CLIFF_MAP = ("FFFFFFFFFFFF", "FFFFFFFFFFFF", "FFFFFFFFFFFF", "SCCCCCCCCCCG")
FALL = -100.0  # the reward for stepping onto the cliff


class CliffNarrator(TileNarrator):
    """Reached the goal or ran out of time, with the falls an episode took."""

    holes = False
    tally_words = TileNarrator.tally_words[:1] + TileNarrator.tally_words[2:]

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        if not last.steps:
            return ""
        falls = _falls(last.episode_return, last.steps)
        fell = f", fell {plural(falls, 'time')}" if falls else ""
        return f"{plural(last.steps, 'step')} taken{fell}"

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        text = super().outcome_text(last, first_info, scene)
        falls = _falls(last.episode_return, last.steps)
        if falls:
            text += f" ({plural(falls, 'fall')} off the cliff)"
        return text


def _falls(episode_return: float, steps: int) -> int:
    """Falls off the cliff in an episode of the bare game: each costs 99 more than a step."""
    extra = -float(episode_return) - steps
    falls = round(extra / (-FALL - 1))
    return falls if falls > 0 and abs(extra - falls * (-FALL - 1)) < 1e-6 else 0


class CliffWalkingGame(TileGame):
    """Walk from start to goal along a cliff's edge."""

    name = "cliffwalking"
    title = "CliffWalking"
    env_id = "CliffWalking-v1"
    key = "C"
    description = "Walk to the goal along the edge of a cliff; every step costs, a fall costs 100."
    teaches = "on-policy against off-policy: SARSA walks the safe path, Q-learning the edge"
    action_names = ("up", "right", "down", "left")
    action_order = "cliff"
    params = (
        Param("slippery", bool, False, help="moves may slide sideways"),
        Param("map", str, "4x12", help="the 4x12 cliff or an edited map (custom)",
              choices=("4x12", CUSTOM)),
    )
    theme = "cliff"
    floor_word = "ground"
    bench_kwargs: dict[str, Any] | None = {}
    # Sutton & Barto's Example 6.6: SARSA's online return above Q-learning's at ε = 0.1.
    demo_compare = ({"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5,
                     "learning_rate_schedule": "constant"}, 500)
    lessons = dict.fromkeys(
        ("sarsa", "expected-sarsa", "monte-carlo", "n-step-sarsa", "sarsa-lambda"),
        "an on-policy learner learns the values of the exploring policy it follows, and "
        "while it explores a step along the edge risks the cliff, so it keeps to a safer "
        "path (Sutton & Barto, Example 6.6); Q-learning learns the edge",
    )

    narrator_type = CliffNarrator

    def builtin_cells(self, kwargs: Mapping[str, Any]) -> list[str]:
        return list(CLIFF_MAP)

    def rules(self, kwargs: Mapping[str, Any]) -> TileRules:
        slip = 2 / 3 if kwargs.get("slippery", False) else 0.0
        return TileRules(step=-1.0, goal=-1.0, hole=FALL, cliff=FALL, slip=slip)

    def builtin_make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        return {"is_slippery": bool(kwargs.get("slippery", False)),
                "max_episode_steps": EPISODE_LIMIT}

    def map_limit(self, grid_map: GridMap) -> int:
        return max(EPISODE_LIMIT, 2 * grid_map.rows * grid_map.cols)

    def hyperparameter_table(
        self, kwargs: Mapping[str, Any] | None = None
    ) -> Mapping[str, Mapping[str, Any]]:
        if (kwargs or {}).get("slippery"):
            # A fall costs 100 at random: averaging it out needs small steps and many episodes.
            return {"*": {"learning_rate": 0.01, "episodes": 50_000}}
        # Double Q splits its experience; Monte Carlo's whole returns need a smaller step; n-step
        # SARSA stops exploring at the end, or its greedy policy may miss the goal (see the README).
        return {
            "*": {"learning_rate": 0.1, "episodes": 2_000}, "double-q": {"episodes": 8_000},
            "monte-carlo": {"learning_rate": 0.01, "episodes": 4_000},
            "n-step-sarsa": {"epsilon_final": 0.0},
        }
