"""FrozenLake: Gymnasium's `FrozenLake-v1`, solved exactly from its own table.

`map` is Gymnasium's "4x4" or "8x8", "random" (drawn by Gymnasium's `generate_random_map`
with `size` and `map_seed`) or "custom" (an edited map given as `layout`, see
`tui_gym.games.tiles`); `success_rate` applies wherever an edited map sets no slip.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from typing import Any

from tui_gym.core.params import Param
from tui_gym.envs.tile_map import TileRules
from tui_gym.games.tiles import CUSTOM, TileGame

__all__ = ["FrozenLakeGame", "lake_map"]

MAPS = ("4x4", "8x8", "random", CUSTOM)
LARGE_LIMIT = 200  # steps on a map of more than four rows (Gymnasium's FrozenLake8x8-v1)


@lru_cache(maxsize=32)
def _random_map(size: int, seed: int) -> tuple[str, ...]:
    from gymnasium.envs.toy_text.frozen_lake import generate_random_map

    return tuple(generate_random_map(size=size, p=0.8, seed=seed))


def lake_map(kwargs: Mapping[str, Any]) -> list[str]:
    """The map the arguments choose, one string a row."""
    choice = kwargs.get("map", "4x4")
    if choice == CUSTOM:
        choice = "4x4"  # an edited map's own rows are the game's (`cells`), not these
    if choice == "random":
        return list(_random_map(int(kwargs.get("size", 8)), int(kwargs.get("map_seed", 0))))
    from gymnasium.envs.toy_text.frozen_lake import MAPS as GYM_MAPS

    return list(GYM_MAPS[choice])


class FrozenLakeGame(TileGame):
    """Cross the ice from start to goal without falling through a hole."""

    name = "frozenlake"
    title = "FrozenLake"
    env_id = "FrozenLake-v1"
    key = "F"
    description = "Cross a frozen lake to the goal without falling into a hole; it may be slippery."
    teaches = "acting under uncertain moves: on slippery ice the safest path is not the shortest"
    params = (
        Param("map", str, "4x4", help="4x4, 8x8, a random map or an edited one (custom)",
              choices=MAPS),
        Param("size", int, 8, 3, 12, help="cells a side of a random map",
              when=("map", "random")),
        Param("map_seed", int, 0, 0, 1_000_000, help="seed of a random map",
              when=("map", "random")),
        Param("slippery", bool, True, help="moves may slide sideways"),
        Param("success_rate", float, 1 / 3, 0.0, 1.0, help="chance a slippery move goes as asked",
              min_inclusive=False, when=("slippery", True)),
    )
    theme = "lake"
    floor_word = "ice"
    bench_kwargs: dict[str, Any] | None = {"map": "8x8"}

    def builtin_cells(self, kwargs: Mapping[str, Any]) -> list[str]:
        return lake_map(kwargs)

    def rules(self, kwargs: Mapping[str, Any]) -> TileRules:
        slip = 1.0 - float(kwargs.get("success_rate", 1 / 3)) if kwargs.get("slippery", True) else 0
        return TileRules(step=0.0, goal=1.0, hole=0.0, cliff=-100.0, slip=slip)

    def builtin_make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        cells = lake_map(kwargs)
        out: dict[str, Any] = {
            "is_slippery": bool(kwargs.get("slippery", True)),
            "success_rate": float(kwargs.get("success_rate", 1 / 3)),
        }
        if kwargs.get("map", "4x4") == "random":
            out["desc"] = cells
        else:
            out["map_name"] = kwargs.get("map", "4x4")
        if len(cells) > 4:
            out["max_episode_steps"] = LARGE_LIMIT
        return out

    def hyperparameter_table(
        self, kwargs: Mapping[str, Any] | None = None
    ) -> Mapping[str, Mapping[str, Any]]:
        # A discount just below 1 breaks the tie between staying put and heading for the goal; slips
        # want small steps over long budgets, Monte Carlo smaller still; Dyna's one-outcome model
        # misleads on ice, so one small planning step (see the README); Q(λ) with λ 0.8.
        planning = {"planning_steps": 1, "learning_rate": 0.001}
        small = len(self.cells(kwargs or {})) <= 4
        common = {"learning_rate": 0.01 if small else 0.02, "discount": 0.999,
                  "episodes": 60_000 if small else 100_000}
        return {
            "*": common,
            **dict.fromkeys(("dyna-q", "dyna-q-plus"), planning),
            "q-lambda": {"lambda": 0.8},
            "monte-carlo": {"learning_rate": 0.003 if small else 0.001,
                            "epsilon_final": 0.01, "episodes": 200_000 if small else 250_000},
        }

    lessons = {
        "dyna-q": "Dyna-Q's model keeps the last outcome of each move, which on slippery ice "
        "is wrong most of the time: planning from it pulls the values away from the optimum "
        "(with no planning steps it is Q-learning, which gets there)",
        "prioritized-sweeping": "prioritized sweeping's model keeps the last outcome of each "
        "move, and its queue updates first the pairs whose last slip surprised most: the "
        "surprising slips weigh more than their chance, and the values drift from the optimum",
    }

    def gap_tolerance(self, kwargs: Mapping[str, Any]) -> float:
        # Slippery ice: a few states have two moves within a hair of each other, and a
        # learner that settles on the other one ends about 2% short of the optimum.
        return 0.02
