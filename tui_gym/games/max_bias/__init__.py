"""max-bias: Sutton & Barto's Example 6.7, the MDP that shows maximization bias.

Spaces and rewards: `tui_gym.envs.max_bias.MaxBiasEnv`; truncated after 10 steps. An action
a state does not offer counts as one it does, so any learner can play it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.mdp import FiniteMDP
from tui_gym.core.params import Param
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.envs.dp_grid import Cell
from tui_gym.envs.max_bias import ACTIONS, GRID, MAX_B_ACTIONS, A, B, max_bias_model, offered
from tui_gym.games.base import Advice, Narrator, TallyWord
from tui_gym.games.dp_grid import DPGridGame, DPGridStates, Event
from tui_gym.games.model import ModelOracle
from tui_gym.games.words import format_reward, plural

__all__ = ["MaxBiasGame"]

NAMES = {0: "the end after B", B: "B", A: "A", 3: "the end right of A"}


def _offered(kwargs: Mapping[str, Any]) -> np.ndarray:
    return offered(int(kwargs.get("actions", MAX_B_ACTIONS)))


class MaxBiasStates(DPGridStates):
    """A, B and the ends; the board offers A's two moves or B's choices."""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        return NAMES[int(observation)]

    def json_observation(self, observation: Any) -> Any:
        """The state's number, 0 to 3."""
        return int(observation)

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        scene = super().read_scene(game_env, before)
        state = game_env.s
        if state is not None:
            names = [a for a, on in zip(ACTIONS, game_env.offered[int(state)], strict=True) if on]
            scene["offered"] = names if int(state) in (A, B) else []
            scene["choices"] = names if int(state) == B else []
        return scene


class MaxBiasOracle(ModelOracle):
    """The optimum among the actions each state offers."""

    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        advice = super().advice(env, kwargs)
        state = self.game.state_of(env)
        if state is None or not advice.values:
            return advice
        mask = _offered(kwargs)[state]
        values = {a: v for a, v in advice.values.items() if mask[a]}
        best = max(values.values())
        optimal = tuple(a for a, v in values.items() if v >= best - 1e-12)
        names = ", ".join(f"{ACTIONS[a]} {v:+.3f}" for a, v in values.items())
        chosen = " or ".join(ACTIONS[a] for a in optimal)
        if len(optimal) > 3:
            chosen = f"any of {ACTIONS[optimal[0]]} to {ACTIONS[optimal[-1]]}"
            names = f"each {best:+.3f}"
        return Advice(optimal, values, f"optimal: {chosen}  ({names} expected)")

    def optimal_marks(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Any:
        marks = super().optimal_marks(kwargs, changes)
        return marks & _offered(kwargs) if isinstance(marks, np.ndarray) else marks


class MaxBiasNarrator(Narrator):
    """Right at once, or left and one of B's actions."""

    tally_words = (TallyWord("right", "good"), TallyWord("left", "bad"),
                   TallyWord("truncated", always=False))

    def tally_word(self, last: Any) -> str:
        if not last.terminated:
            return "truncated"
        return "left" if last.steps > 1 else "right"

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        total = format_reward(last.episode_return)
        if not last.terminated:
            return f"Out of time after {plural(last.steps, 'step')}, return {total}"
        if last.steps > 1:
            return f"Went left to B, then ended with {total}"
        return f"Went right: the episode ends at {total}"


class MaxBiasGame(DPGridGame):
    """Go right from A for 0, or left to B and one of its actions for N(-0.1, 1)."""

    name = "max-bias"
    title = "Maximization bias"
    env_id = "tui_gym/MaxBias-v0"
    key = "M"
    description = ("Example 6.7: from A, right ends at 0; left leads to B, whose actions "
                   "each end with a reward drawn from N(-0.1, 1).")
    teaches = "maximization bias: Q-learning's max over noisy estimates, and Double Q's cure"
    action_names = ACTIONS
    params = (Param("actions", int, MAX_B_ACTIONS, 1, MAX_B_ACTIONS,
                    help="how many actions B offers"),)
    # The book's constant alpha 0.1 keeps left's estimate noisy: a visits step size settles it;
    # Dyna replays one reward per move, so one planning step and more episodes (see the README).
    hyperparameters = {
        "*": {"learning_rate": 0.01, "learning_rate_schedule": "visits",
              "epsilon_start": 0.1, "epsilon_final": 0.1, "episodes": 2000},
        **dict.fromkeys(("dyna-q", "dyna-q-plus"), {"planning_steps": 1, "episodes": 5000}),
    }

    fixed_grid = GRID
    states_type = MaxBiasStates
    oracle_type = MaxBiasOracle
    narrator_type = MaxBiasNarrator

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP:
        return max_bias_model()

    def offered_actions(self, kwargs: Mapping[str, Any]) -> np.ndarray:
        return _offered(kwargs)

    def event(self, game_env: Any, before: Mapping[str, Any], was: Cell, now: Cell,
              move: str) -> Event | None:
        if was[1] == B:
            return f"{{who}} took {move} in B: the episode ends", "caption"
        if was[1] == A and now[1] == B:
            count = int(game_env.offered[B].sum())
            keys = "1" if count == 1 else f"1 to {count}" if count < 10 else "1 to 9 and 0"
            return f"{{who}} went left to B: pick one of its actions ({keys})", "caption"
        if was[1] == A:
            return "{who} went right: the episode ends at 0", "caption"
        return None
