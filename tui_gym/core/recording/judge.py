"""The coach's judgement of a move: a verdict, and the exact regret where it is known."""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

OPTIMAL, NOT_OPTIMAL = "optimal", "not optimal"


@dataclass(frozen=True)
class Judgement:
    """The coach's word on one move."""

    verdict: str | None  # OPTIMAL, NOT_OPTIMAL, or None: nothing to judge by
    regret: float | None  # exact loss in expected return, None where unknown
    optimal: tuple[int, ...] = ()  # the optimal actions where the move was made


NO_JUDGEMENT = Judgement(None, None)


@dataclass(frozen=True)
class Assessment:
    """What the optimum knows of one state: its optimal actions and, when exact, their values."""

    optimal: tuple[int, ...] = ()
    values: Mapping[int, float] | None = None

    def judge(self, action: int) -> Judgement:
        if not self.optimal:
            return NO_JUDGEMENT
        verdict = OPTIMAL if action in self.optimal else NOT_OPTIMAL
        regret = None
        if self.values is not None and action in self.values:
            loss = max(self.values.values()) - self.values[action]
            if verdict == OPTIMAL:
                regret = 0.0  # within the optimum's tolerance: no loss
            elif np.isfinite(loss):
                regret = max(0.0, float(loss))
        return Judgement(verdict, regret, self.optimal)


NOTHING_KNOWN = Assessment()


class MoveJudge:
    """Judges moves in one game (a game and its arguments), on any env of it."""

    def __init__(self, game: Any, env_kwargs: Mapping[str, Any]) -> None:
        self.game = game
        self.env_kwargs = dict(env_kwargs)
        self._env_ref: weakref.ref[Any] | None = None
        self._model: Any = None  # the env's FiniteMDP, False when it has none
        self._ladder: Any = None  # its optimal action values (a `core.mdp.Ladder`)

    def assess(self, env: Any, steps_taken: int = 0) -> Assessment:
        """The optimum's view of `env`'s current state (never raises: a help, not a rule)."""
        try:
            advice = self.game.oracle.advice(env, self.env_kwargs)
        except Exception:
            advice = None
        if advice is not None and not advice.optimal:
            return NOTHING_KNOWN  # no decision, or a game the exact figures cannot follow
        if advice is not None and advice.values:
            return Assessment(tuple(advice.optimal), dict(advice.values))
        try:
            from_model = self._from_model(env, steps_taken)
        except Exception:
            from_model = None
        if from_model is not None:
            return from_model
        return Assessment(tuple(advice.optimal)) if advice is not None else NOTHING_KNOWN

    # --- the exact model, for games that carry a table -------------------------
    def _from_model(self, env: Any, steps_taken: int) -> Assessment | None:
        model = self._model_of(env)
        if model is None:
            return None
        state = getattr(env.unwrapped, "s", None)
        if isinstance(state, np.integer):
            state = int(state)
        if not isinstance(state, int) or isinstance(state, bool) or not 0 <= state < model.n_states:
            return None
        steps_left = None if model.horizon is None else model.horizon - steps_taken
        if steps_left is not None and steps_left < 1:
            return None
        from tui_gym.core.mdp import optimal_actions

        row = self._ladder.q(steps_left)[state]
        if not np.isfinite(row.max()):
            return None
        optimal = tuple(int(a) for a in np.flatnonzero(optimal_actions(row[None, :])[0]))
        return Assessment(optimal, {a: float(v) for a, v in enumerate(row)})

    def _model_of(self, env: Any) -> Any:
        if self._env_ref is not None and self._env_ref() is env:
            return self._model or None
        from tui_gym.core.mdp import FiniteMDP, Ladder, model_from_env

        try:
            model = model_from_env(env)
        except Exception:
            model = None
        self._model = model if isinstance(model, FiniteMDP) else False
        self._ladder = Ladder(model) if isinstance(model, FiniteMDP) else None
        try:
            self._env_ref = weakref.ref(env)
        except TypeError:
            self._env_ref = None
        return self._model or None
