"""dyna-maze, blocking-maze, shortcut-maze: Sutton & Barto's mazes of chapter 8.

Spaces and rewards: `tui_gym.envs.dyna_maze.MazeEnv`; truncated after 5000 steps. Each
phase of a changing maze has its own model; as every way to the goal is worth +1, the
exact figures add the steps beyond the fewest (`extra_steps`, which the bound is on).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.mdp import NotAvailable, evaluate, solve, with_horizon
from tui_gym.core.params import Param
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.envs.dp_grid import Cell, Grid
from tui_gym.envs.dyna_maze import maze_phases
from tui_gym.games.base import Advice, Bound, ReachNarrator, ReferenceMetrics
from tui_gym.games.dp_grid import DPGridGame, Event
from tui_gym.games.model import PHASE, ModelOracle, freeze
from tui_gym.games.words import plural

__all__ = ["BlockingMazeGame", "DynaMazeGame", "ShortcutMazeGame"]

DISCOUNT = 0.95  # the book's


class MazeOracle(ModelOracle):
    """The exact figures of the phase in force, with the steps to the goal beside them."""

    game: MazeGame

    def __init__(self, game: MazeGame) -> None:
        super().__init__(game)
        self._fewest: dict[Any, float] = {}

    def policy_reference(self, policy: np.ndarray, exact: Any, kwargs: Mapping[str, Any],
                         changes: GameChanges) -> ReferenceMetrics:
        reference = super().policy_reference(policy, exact, kwargs, changes)
        # The model paying -1 a step: a policy's value is minus its expected steps.
        steps = exact.model.replace(reward=np.full(exact.model.reward.shape, -1.0), reward_std=None)
        mean = -evaluate(steps, policy).value
        key = (freeze(kwargs), changes)
        if key not in self._fewest:
            self._fewest[key] = -solve(with_horizon(steps, None)).value
        fewest = self._fewest[key]
        figures = {**reference.figures, "mean_steps": mean, "optimal_steps": fewest,
                   "extra_steps": max(0.0, mean - fewest)}
        return ReferenceMetrics(figures, f"{reference.summary}  {mean:.1f} steps "
                                f"(fewest {fewest:g})", reference.scope)

    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        phase = int(getattr(env.unwrapped, "phase", 0))
        return super().advice(env, self.game.in_phase(kwargs, phase))

    def bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> Bound | NotAvailable:
        limit = self.game.extra_steps
        return Bound("extra_steps", limit, f"extra_steps <= {limit:g} (steps beyond the fewest)")


class MazeNarrator(ReachNarrator):
    """Reached the goal, or ran out of time; when the wall moves."""

    def progress_text(self, last: Any, first_info: Mapping[str, Any]) -> str:
        text = super().progress_text(last, first_info)
        info = last.info if last.steps else first_info
        left = info.get("changes_in")
        if isinstance(left, int):
            moves = f"the wall moves in {plural(left, 'step')}"
            return f"{text}; {moves}" if text else moves.capitalize()
        return text


class MazeGame(DPGridGame):
    """A maze of the book's chapter 8 (see the module docstring)."""

    maze = "dyna"
    change_words = ""  # what the change does, for the board
    extra_steps = 0.0  # the bound: steps beyond the fewest a trained greedy policy takes
    # A changing maze is learned as the book's figures do (epsilon 0.1 throughout); SARSA's
    # falls to 0.01 so its greedy policy is the one it learns about (see the README).
    CHANGING = {"discount": DISCOUNT, "learning_rate": 0.5, "learning_rate_schedule": "constant",
                "epsilon_start": 0.1, "epsilon_final": 0.1}
    # An on-policy learner that looks ahead charges an exploratory step's cost to the moves
    # before it: exploring less over the whole run tries them again, so no detour is kept.
    SETTLING = {"epsilon_final": 0.0, "epsilon_decay_fraction": 1.0, "episodes": 3000}
    CHANGING_LEARNERS: dict[str, dict[str, Any]] = {
        "sarsa": {"epsilon_final": 0.01},
        # Two steps or half a trace ahead: further, some seeds lose the goal once the wall moves.
        "n-step-sarsa": {"n": 2, **SETTLING},
        "sarsa-lambda": {"lambda": 0.5, **SETTLING},
        "monte-carlo": SETTLING,
        # Moves off the greedy way are valued only as exploration's random steps reach them:
        # Q(lambda) with the windy grids' shorter traces, and more episodes to settle them.
        "q-lambda": {"lambda": 0.5, "episodes": 3000},
        # Each of its two tables learns from half the steps: more episodes after the change.
        "double-q": {"episodes": 1000},
        # Prioritized sweeping changes Q only through its queue: a threshold above 0 stops the
        # old way's values falling, and several sweeps a step keep their order (see the README).
        "prioritized-sweeping": {"theta": 0.0, "planning_steps": 1},
    }
    plan_gamma = DISCOUNT
    hyperparameters = {"*": {"discount": DISCOUNT, "learning_rate": 0.1, "episodes": 1000}}

    oracle_type = MazeOracle
    narrator_type = MazeNarrator

    def phases(self, kwargs: Mapping[str, Any]) -> list[tuple[int, Grid]]:
        change_at = kwargs.get("change_at")
        return maze_phases(self.maze, None if change_at is None else int(change_at),
                           int(kwargs.get("scale", 1)))

    def phase_starts(self, kwargs: Mapping[str, Any]) -> tuple[int, ...]:
        return tuple(start for start, _ in self.phases(kwargs))

    def grid(self, kwargs: Mapping[str, Any]) -> Grid:
        return self.phases(kwargs)[int(kwargs.get(PHASE, 0))][1]

    def make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        return {k: v for k, v in kwargs.items() if k != PHASE}

    def event(self, game_env: Any, before: Mapping[str, Any], was: Cell, now: Cell,
              move: str) -> Event | None:
        cells = before.get("cells")
        if cells is not None and list(cells) != game_env.grid.cells():
            return (f"The wall moved after {plural(game_env.world_steps, 'step')}: "
                    f"{self.change_words}", "slipped")
        return super().event(game_env, before, was, now, move)


class DynaMazeGame(MazeGame):
    """Figure 8.2's maze: walk from S to the goal round the walls."""

    name = "dyna-maze"
    title = "Dyna maze"
    env_id = "tui_gym/DynaMaze-v0"
    key = "D"
    lessons = {
        "sarsa": "every way to the goal is worth +1 undiscounted, so an on-policy learner that "
                 "explores may keep a detour of a step out and back",
    }
    description = "Figure 8.2's 6x9 maze: +1 at the goal, 0 elsewhere; 14 steps at best."
    teaches = "planning: Dyna-Q's simulated steps find the way in far fewer episodes"
    params = (Param("scale", int, 1, 1, 8,
                    help="each cell made scale x scale cells (Example 8.4's finer mazes)"),)
    # The on-policy learners that look ahead settle as `MazeGame.SETTLING` does; Monte Carlo
    # steps by a constant 0.05, or its averages keep the first, nearly random episodes' returns.
    hyperparameters = {
        **MazeGame.hyperparameters,
        **dict.fromkeys(("n-step-sarsa", "sarsa-lambda"), MazeGame.SETTLING),
        "monte-carlo": {**MazeGame.SETTLING, "learning_rate_schedule": "constant",
                        "learning_rate": 0.05},
    }


class BlockingMazeGame(MazeGame):
    """Figure 8.4's maze: the short way round the wall closes after `change_at` steps."""

    name = "blocking-maze"
    title = "Blocking maze"
    env_id = "tui_gym/BlockingMaze-v0"
    key = "L"
    description = ("Figure 8.4's maze: after 1000 steps the way round the wall's right end "
                   "closes and one round its left opens (10 steps, then 16).")
    teaches = "a world that gets worse: a learner must notice its way is gone"
    maze = "blocking"
    change_words = "the way round its right end closed, one round its left opened"
    extra_steps = 2.0  # a detour of a step out and back some learners keep (seeds 0-4: 0-2)
    params = (Param("change_at", int, 1000, 1, 100_000_000,
                    help="the step, over all episodes, at which the wall moves"),)
    hyperparameters = {"*": {**MazeGame.CHANGING, "episodes": 300}, **MazeGame.CHANGING_LEARNERS}


class ShortcutMazeGame(MazeGame):
    """Figure 8.5's maze: a shortcut opens round the wall's right end after `change_at` steps."""

    name = "shortcut-maze"
    title = "Shortcut maze"
    env_id = "tui_gym/ShortcutMaze-v0"
    key = "S"
    description = ("Figure 8.5's maze: after 3000 steps a shorter way opens round the "
                   "wall's right end (16 steps, then 10).")
    teaches = "a world that gets better: only a learner that explores finds the shortcut"
    maze = "shortcut"
    change_words = "a shorter way opened round its right end"
    params = (Param("change_at", int, 3000, 1, 100_000_000,
                    help="the step, over all episodes, at which the wall opens"),)
    extra_steps = 6.0  # the long way, which a learner that does not explore keeps to
    hyperparameters = {
        "*": {**MazeGame.CHANGING, "episodes": 400},
        **MazeGame.CHANGING_LEARNERS,
        # Dyna-Q+'s bonus lives in Q: a larger one sends the greedy policy into walls untried
        # for long; a smaller one needs more episodes to find and settle the shortcut.
        "dyna-q-plus": {"kappa": 0.0004, "episodes": 800},
    }
