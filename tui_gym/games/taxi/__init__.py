"""Taxi: Gymnasium's `Taxi-v4` (and `Taxi-v3` where the installed Gymnasium has it).

With `fickle` the passenger's change of mind is a draw Gymnasium's table does not list,
so there is no exact model: the game trains and plays, and says so. The heatmaps show
the 500 states as 25-cell slices of the city, one per passenger place and destination.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP, NotAvailable
from tui_gym.core.params import Param
from tui_gym.games.base import (
    TIED,
    HeatmapLayout,
    ReachNarrator,
    TallyWord,
    greedy_panel,
    numbered,
)
from tui_gym.games.model import DiscreteStates, ModelGame

if TYPE_CHECKING:
    from tui_gym.session.play import PlayStep

__all__ = ["TaxiGame", "decode"]

ROWS = COLS = 5
STANDS = ((0, 0), (0, 4), (4, 0), (4, 3))
STAND_NAMES = ("R", "G", "Y", "B")
IN_TAXI = 4
WHERE = (*STAND_NAMES, "taxi")
ACTION_MARKS = ("↓", "↑", "→", "←", "P", "D")
ILLEGAL = -10.0
FICKLE = ("with a fickle passenger Taxi has no exact model: the change of mind is a hidden "
          "draw its table does not list")


def decode(state: int) -> tuple[int, int, int, int]:
    """(taxi row, taxi col, passenger, destination) of a state number."""
    state, destination = divmod(int(state), 4)
    state, passenger = divmod(state, 5)
    row, col = divmod(state, 5)
    return row, col, passenger, destination


def _walls(game_env: Any) -> list[list[int]]:
    """Cells with a wall on their east side, read from the env's map."""
    desc = np.asarray(game_env.desc)
    return [[row, col] for row in range(ROWS) for col in range(COLS - 1)
            if desc[1 + row, 2 * col + 2] == b"|"]


class TaxiStates(DiscreteStates):
    """The 500 states; the taxi board's scene; the city as text."""

    def text(self, env: Any, reveal: bool = True, before: Mapping[str, Any] | None = None) -> str:
        """Gymnasium's map with the taxi as `T` (`@` with the passenger aboard) and the
        waiting passenger's stand in lower case, and a line saying where they go."""
        try:
            game_env = env.unwrapped
            row, col, passenger, destination = decode(int(game_env.s))
            grid = [[c.decode() for c in line] for line in game_env.desc]
        except (AttributeError, TypeError, ValueError):
            return ""
        if passenger < IN_TAXI:
            r, c = STANDS[passenger]
            grid[1 + r][2 * c + 1] = grid[1 + r][2 * c + 1].lower()
        grid[1 + row][2 * col + 1] = "@" if passenger == IN_TAXI else "T"
        where = "in the taxi (@)" if passenger == IN_TAXI else \
            f"at {STAND_NAMES[passenger]} (lower case)"
        return "\n".join(["".join(line) for line in grid]
                         + [f"T taxi; passenger {where}, going to {STAND_NAMES[destination]}"])

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        row, col, passenger, destination = decode(int(observation))
        where = "in the taxi" if passenger == IN_TAXI else f"at {STAND_NAMES[passenger]}"
        return (f"taxi at row {row}, col {col}; passenger {where}, "
                f"going to {STAND_NAMES[destination]}")

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        row, col, passenger, destination = decode(int(game_env.s))
        last = getattr(game_env, "lastaction", None)
        action = self.game.action_names[int(last)] if last is not None else None
        now = ((row, col), passenger, destination)
        was = (tuple(before.get("taxi") or ()), before.get("passenger"), before.get("destination"))
        return {
            "taxi": (row, col),
            "passenger": passenger,
            "destination": destination,
            "stands": [list(s) for s in STANDS],
            "stand_names": list(STAND_NAMES),
            "walls": _walls(game_env),
            "last_action": action,
            # A pick-up or drop-off that changes nothing is one the rules refuse (-10).
            "last_illegal": action in ("pickup", "dropoff") and bool(before) and now == was,
            "rainy": len(game_env.P[0][0]) > 1,  # a move has sideways outcomes
        }


class TaxiNarrator(ReachNarrator):
    """Delivered or out of time; pick-ups and drop-offs that could not be made."""

    tally_words = (TallyWord("delivered", "good"), TallyWord("timed out", "bad"))
    reached_words = "Passenger delivered"
    missed_words = ": the passenger not delivered"
    ended_figure = "delivered_rate"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        text = super().progress_text(last, first_info)
        if last.steps and last.reward == ILLEGAL:
            text += "; that action could not be made here (−10)"
        return text


class TaxiLayout(HeatmapLayout):
    """A picker of passenger place x destination, and the city for the chosen pair."""

    has_focus = True
    focus_help = "choose the passenger's place (rows) and destination (columns)"

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        if np.shape(q) != (500, 6):
            return []
        passenger, destination = focus if focus is not None else self.default_focus(kwargs)
        q5 = np.asarray(q).reshape(ROWS, COLS, 5, 4, 6)
        best = q5.max(axis=-1)
        greedy = q5.argmax(axis=-1)
        tied = (q5 == q5[..., :1]).all(axis=-1)
        if isinstance(marks, np.ndarray) and marks.shape == (500, 6):
            good = np.take_along_axis(marks.reshape(ROWS, COLS, 5, 4, 6),
                                      greedy[..., None], axis=-1)[..., 0]
            wrong = ~good & ~tied
        else:
            wrong = np.zeros(greedy.shape, dtype=bool)
        done = np.arange(5)[:, None] == np.arange(4)[None, :]  # delivered: no decision left
        picker_values = np.where(done, np.nan, best.mean(axis=(0, 1)))
        counts = wrong.sum(axis=(0, 1))
        picker_labels = tuple(
            tuple("✓" if d else (f"{counts[p, c]}*" if counts[p, c] else "")
                  for c, d in enumerate(row))
            for p, row in enumerate(done)
        )
        picker = Heatmap(
            title="slice: passenger × dest.", row_labels=WHERE, col_labels=STAND_NAMES,
            values=picker_values, labels=picker_labels, marked=np.zeros((5, 4), dtype=bool),
            legend="picker: mean max Q of a slice, n* its cells not optimal, ✓ delivered",
        )
        where = "in the taxi" if passenger == IN_TAXI else f"at {STAND_NAMES[passenger]}"
        city = greedy_panel(
            f"passenger {where}, going to {STAND_NAMES[destination]}",
            f"city: max Q per taxi cell, arrow drive  P pick up  D drop off  {TIED} tie"
            "  * not optimal", numbered(ROWS), numbered(COLS), lambda r, c: None,
            lambda r, c: q5[r, c, passenger, destination], ACTION_MARKS.__getitem__,
            lambda r, c, action: wrong[r, c, passenger, destination],
        )
        return [picker, city]

    def default_focus(self, kwargs: Mapping[str, Any]) -> Any:
        return (0, 3)  # the passenger at R, going to B

    def focus_at(self, row: int, col: int, kwargs: Mapping[str, Any]) -> Any:
        return (min(4, max(0, row)), min(3, max(0, col)))

    def focus_cell(self, focus: Any, kwargs: Mapping[str, Any]) -> tuple[int, int] | None:
        passenger, destination = focus if focus is not None else self.default_focus(kwargs)
        return (int(passenger), int(destination))


class TaxiGame(ModelGame):
    """Pick the passenger up and drop them off at their destination."""

    name = "taxi"
    title = "Taxi"
    env_id = "Taxi-v4"
    other_ids = ("Taxi-v3",)
    key = "T"
    description = "Drive a taxi: pick a passenger up at one stand, drop them off at another."
    teaches = "a larger state (500 states), subgoals, and penalties for illegal actions"
    action_names = ("south", "north", "east", "west", "pickup", "dropoff")
    params = (
        Param("rainy", bool, False, help="moves may veer sideways (chance 0.2)"),
        Param("fickle", bool, False, help="the passenger may change destination"),
    )
    board = "taxi"
    bench_kwargs: dict[str, Any] | None = {}

    states_type = TaxiStates
    narrator_type = TaxiNarrator
    layout_type = TaxiLayout

    def make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        # Only when on: an older Taxi-v3 takes neither argument.
        if kwargs.get("rainy"):
            out["is_rainy"] = True
        if kwargs.get("fickle"):
            out["fickle_passenger"] = True
        return out

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP | NotAvailable:
        if kwargs.get("fickle"):
            return NotAvailable(FICKLE)
        return super().base_model(kwargs)

    def gap_tolerance(self, kwargs: Mapping[str, Any]) -> float:
        # Every move is certain without rain: a trained greedy policy is the optimum.
        return 0.01 if kwargs.get("rainy") else 0.0

    lessons = {
        "monte-carlo": "Monte Carlo learns only from whole returns of a policy that keeps "
        "exploring: its values of the starts it meets seldom late in a run lag behind, and "
        "the greedy policy takes a step more than it needs from some of them",
    }

    def hyperparameter_table(
        self, kwargs: Mapping[str, Any] | None = None
    ) -> Mapping[str, Mapping[str, Any]]:
        if (kwargs or {}).get("rainy"):
            return {"*": {"learning_rate": 0.05, "episodes": 50_000}}
        # On-policy learners stop exploring so their values become the greedy policy's; Double Q
        # splits its experience over two tables. Each takes a longer budget (see the README).
        on_policy = {"epsilon_final": 0.0, "epsilon_decay_fraction": 0.9, "episodes": 40_000}
        return {
            "*": {"learning_rate": 0.1, "episodes": 10_000},
            "sarsa": {**on_policy, "learning_rate": 0.2},
            "expected-sarsa": {"epsilon_final": 0.0},
            "double-q": {"episodes": 20_000},
            "monte-carlo": {"epsilon_final": 0.01, "learning_rate": 0.02, "episodes": 100_000},
            "n-step-sarsa": {"n": 2, **on_policy},
            "sarsa-lambda": {"lambda": 0.5, **on_policy},
            "q-lambda": {"episodes": 20_000},
        }
