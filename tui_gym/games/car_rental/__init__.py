"""car-rental: Sutton & Barto's Example 4.2, Jack's car rental, and Exercise 4.7's variant.

Spaces and rewards: `tui_gym.envs.car_rental.CarRentalEnv`. Played in undiscounted episodes
of 20 days; planning shows the book's values, discounted by 0.9 with no end (Figure 4.2).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP
from tui_gym.core.params import Param
from tui_gym.envs.car_rental import MAX_CARS, MOVES, CarRentalEnv, car_rental_model
from tui_gym.games.base import TIED, UNREADABLE, HeatmapLayout, Narrator
from tui_gym.games.model import DiscreteStates, ModelGame
from tui_gym.games.planning import PlanModel
from tui_gym.games.words import format_reward, plural

__all__ = ["CarRentalGame"]

SIDE = MAX_CARS + 1


def _grid(values: np.ndarray) -> np.ndarray:
    """`[21, 21]`: a per-state array as the book draws it: the first site's cars up, the
    second's to the right."""
    return np.asarray(values).reshape(SIDE, SIDE)[::-1]


_ROWS = tuple(str(n) for n in range(MAX_CARS, -1, -1))
_COLS = tuple(str(n) for n in range(SIDE))


def value_panel(v: np.ndarray) -> Heatmap:
    """The state values on the policy's grid (the book's lower right surface, from above)."""
    return Heatmap(
        title="values", row_labels=_ROWS, col_labels=_COLS, values=_grid(v).astype(float),
        labels=tuple(("",) * SIDE for _ in range(SIDE)), marked=np.zeros((SIDE, SIDE), dtype=bool),
        legend="rows: cars at the first site  cols: at the second",
    )


class CarRentalStates(DiscreteStates):
    """Cars at the two sites; the dial board's scene."""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        first, second = divmod(int(observation), SIDE)
        return f"{first} cars at the first site, {second} at the second"

    def json_observation(self, observation: Any) -> Any:
        first, second = divmod(int(observation), SIDE)
        return [first, second]

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        if game_env.s is None:
            return {}
        first, second = divmod(int(game_env.s), SIDE)
        day = game_env.last_day
        lines = []
        if day:
            rented, back = day["rented"], day["returned"]
            lines.append(f"moved {day['moved']:+d} (${day['cost']:g}), rented "
                         f"{rented[0]} + {rented[1]} of {day['requested'][0]} + "
                         f"{day['requested'][1]} asked, returned {back[0]} + {back[1]}")
        return {
            "title": "Jack's car rental",
            "bars": [["first site", first, MAX_CARS], ["second site", second, MAX_CARS]],
            "lines": lines, "actions": list(self.game.action_names), "start": MOVES.index(0),
            "unit": "", "prompt": "Cars to move tonight, first site to second (negative: back).",
        }


class CarRentalLayout(HeatmapLayout):
    """The book's contour: the greedy number of cars moved (the fewest of equal moves), by
    the cars at each site."""

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        try:
            values = np.asarray(q, dtype=float).reshape(SIDE * SIDE, len(MOVES))
        except UNREADABLE:
            return []
        # Of the best moves, the fewest cars (a move of more cars than a site has moves
        # what it has: such moves tie with it).
        best = values == values.max(axis=1, keepdims=True)
        greedy = np.argmin(np.where(best, np.abs(MOVES), MAX_CARS), axis=1)
        tied = (values == values[:, :1]).all(axis=1)
        moved = np.where(tied, np.nan, np.asarray(MOVES, dtype=float)[greedy])
        labels = np.where(tied, TIED, np.abs(np.nan_to_num(moved)).astype(int).astype(str))
        wrong = np.zeros(len(values), dtype=bool)
        if isinstance(marks, np.ndarray) and marks.shape == values.shape:
            wrong = ~marks[np.arange(len(values)), greedy] & ~tied
        return [
            Heatmap(
                title="greedy cars moved tonight",
                row_labels=_ROWS,
                col_labels=_COLS,
                values=_grid(moved),
                labels=tuple(tuple(str(x) for x in row) for row in _grid(labels)),
                marked=_grid(wrong),
                legend="rows: cars at the first site  cols: at the second  number and "
                       "colour: cars moved (green: to the second site, red: to the first)  "
                       f"{TIED} tie  * not optimal",
            )
        ]


class CarRentalNarrator(Narrator):
    """Days of business: what they earned."""

    tally_words = ()  # every episode runs to the limit: the count says it all
    agreement_words = "moves as the optimum"
    value_places = 1

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        return f"{plural(last.steps, 'day')} of business: ${last.episode_return:,.0f}"

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        if not last.steps:
            return ""
        return f"day {last.steps}, earned {format_reward(last.episode_return)} so far"


class CarRentalGame(ModelGame):
    """Move cars overnight between two rental sites."""

    name = "car-rental"
    title = "Jack's car rental"
    env_id = "tui_gym/CarRental-v0"
    key = "J"
    description = "Example 4.2: move up to 5 cars a night between two sites to rent more."
    teaches = "policy iteration on a large stochastic model: four improvements to optimal"
    action_names = CarRentalEnv.action_names
    params = (
        Param("exercise", bool, False, help="Exercise 4.7: a free move, parking over 10 cars"),
    )
    board = "dial"
    episode_noun = "episode"
    plan_gamma = 0.9
    # Noisy days and near-equal moves: close quickly, closer only slowly (see the README);
    # Double Q updates each table half as often: a smaller step and a longer budget.
    hyperparameters = {"*": {"discount": 0.9, "learning_rate": 0.2, "episodes": 10_000},
                       "double-q": {"learning_rate": 0.05, "episodes": 60_000}}

    states_type = CarRentalStates
    layout_type = CarRentalLayout
    narrator_type = CarRentalNarrator

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP:
        return car_rental_model(bool(kwargs.get("exercise", False)))

    def gap_tolerance(self, kwargs: Mapping[str, Any]) -> float:
        """A twentieth of the optimum (see `hyperparameters`)."""
        return 0.05

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel:
        return PlanModel(self.base_model(kwargs), self.plan_gamma, self.episode_limit(kwargs),
                         value_panel=value_panel)
