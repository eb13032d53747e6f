"""gambler: Sutton & Barto's Example 4.3, the gambler's problem.

Spaces and rewards: `tui_gym.envs.gambler.GamblerEnv`; truncated after 1000 bets.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP
from tui_gym.core.params import Param
from tui_gym.envs.gambler import MAX_STAKE, GamblerEnv, gambler_model, stakes
from tui_gym.games.base import (
    TIED,
    UNREADABLE,
    HeatmapLayout,
    ReachNarrator,
    TallyWord,
    greedy_panel,
    numbered,
)
from tui_gym.games.model import DiscreteStates, ModelGame
from tui_gym.games.planning import PlanModel, StateLine
from tui_gym.games.words import plural

__all__ = ["GamblerGame"]

ROW = 10  # capitals a heatmap row


def _goal(kwargs: Mapping[str, Any]) -> int:
    return int(kwargs.get("goal", 100))


class GamblerStates(DiscreteStates):
    """The capital; the dial board's scene."""

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        return f"capital ${int(observation)} of ${_goal(kwargs)}"

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        capital, goal = game_env.s, int(game_env.goal)
        if capital is None:
            return {}
        capital = int(capital)
        lines = []
        if game_env.lastaction is not None and game_env.last_flip:
            won = game_env.last_flip == "heads"
            lines.append(f"{{who}} staked ${game_env.last_stake}: {game_env.last_flip}, "
                         f"{'won' if won else 'lost'}")
        return {
            "title": "Gambler", "bars": [["capital", capital, goal]], "lines": lines,
            "actions": list(self.game.action_names),
            "labels": [f"${k}" for k in range(1, MAX_STAKE + 1)],
            "allowed": max(1, min(capital, goal - capital)), "unit": "$",
            "prompt": f"Stake on heads (chance {game_env.p_heads:g}); reach ${goal} to win.",
        }


class GamblerLayout(HeatmapLayout):
    """The capitals in rows of ten: max Q colours each, the greedy stake in it."""

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        goal = _goal(kwargs)
        try:
            values = np.asarray(q, dtype=float).reshape(goal + 1, MAX_STAKE)
        except UNREADABLE:
            return []
        has_marks = isinstance(marks, np.ndarray) and marks.shape == values.shape
        rows = goal // ROW + 1

        def fixed(r: int, c: int) -> str | None:
            capital = r * ROW + c
            return {0: "✗", goal: "★"}.get(capital, "" if capital > goal else None)

        def legal(r: int, c: int) -> np.ndarray:  # the stakes that differ at this capital
            return values[r * ROW + c, : min(r * ROW + c, goal - r * ROW - c)]

        return [greedy_panel(
            "max Q and the greedy stake",
            f"rows: capital by tens  number: greedy stake  {TIED} tie  ✗ ruined  ★ goal  "
            "* not an optimal stake",
            tuple(f"{r * ROW}+" for r in range(rows)), numbered(ROW), fixed, legal,
            lambda action: str(action + 1),
            lambda r, c, action: has_marks and not marks[r * ROW + c, action],
            lambda r, c: TIED if len(legal(r, c)) > 1 else "1",
        )]


class GamblerNarrator(ReachNarrator):
    """Reached the goal, ruined, or out of bets."""

    tally_words = (TallyWord("won", "good"), TallyWord("ruined", "bad"),
                   TallyWord("timed out", always=False))
    agreement_words = "stakes as the optimum"

    def outcome_text(self, last: Any, first_info: Mapping[str, Any],
                     scene: Mapping[str, Any]) -> str:
        bets = plural(last.steps, "bet")
        if not last.terminated:
            return f"Out of time after {bets}"
        if last.episode_return > 0:
            return f"Reached the goal after {bets}: +1"
        return f"Ruined after {bets}"

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        return f"{plural(last.steps, 'bet')} so far" if last.steps else ""


class GamblerGame(ModelGame):
    """Bet on coin flips to reach the goal before losing everything."""

    name = "gambler"
    title = "Gambler"
    env_id = "tui_gym/Gambler-v0"
    key = "G"
    description = "Example 4.3: stake on coin flips (heads 0.4) to reach $100 before ruin."
    teaches = "value iteration: bold play, and many equally optimal policies"
    action_names = GamblerEnv.action_names
    params = (
        Param("p_heads", float, 0.4, 0.01, 0.99, help="the chance of heads, which wins a bet"),
        Param("goal", int, 100, 2, 2 * MAX_STAKE, help="the capital that wins"),
    )
    board = "dial"
    episode_noun = "game"
    # Near-equal stakes make the max over noisy estimates run high: discounting keeps that bias
    # down (see the README); prioritized sweeping's queue favours surprises: a smaller step.
    hyperparameters = {"*": {"discount": 0.9, "learning_rate": 0.05, "episodes": 20_000},
                       "prioritized-sweeping": {"learning_rate": 0.02}}

    states_type = GamblerStates
    layout_type = GamblerLayout
    narrator_type = GamblerNarrator

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP:
        return gambler_model(float(kwargs.get("p_heads", 0.4)), _goal(kwargs))

    def gap_tolerance(self, kwargs: Mapping[str, Any]) -> float:
        """A fifth of the optimum: learners get within it, not much closer (the README)."""
        return 0.2

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel:
        goal = _goal(kwargs)
        capital = np.arange(1, goal)
        line = StateLine(
            "capital", capital, capital.astype(float), stakes(goal).astype(float), "stake")
        return PlanModel(self.base_model(kwargs), self.plan_gamma, self.episode_limit(kwargs),
                         line=line)
