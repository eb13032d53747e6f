"""The coach's judgement of a move: a verdict, and the exact regret where it is known."""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

OPTIMAL, NOT_OPTIMAL = "optimal", "not optimal"
MAX_STORED_VALUES = 4_000_000  # Q* for every step count of a time limit kept up to this size


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


@dataclass
class _ModelValues:
    """Q* of one env's exact model: for every step count left (a time limit) or once."""

    horizon: int | None
    q_by_steps: dict[int, np.ndarray] = field(default_factory=dict)
    q: np.ndarray | None = None


class MoveJudge:
    """Judges moves in one game (a game and its arguments), on any env of it."""

    def __init__(self, game: Any, env_kwargs: Mapping[str, Any]) -> None:
        self.game = game
        self.env_kwargs = dict(env_kwargs)
        self._env_ref: weakref.ref[Any] | None = None
        self._model: Any = None  # the env's FiniteMDP, False when it has none
        self._values: _ModelValues | None = None

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
        if not isinstance(state, int) or isinstance(state, bool):
            return None
        if not 0 <= state < model.n_states:
            return None
        q = self._q(model, steps_taken)
        if q is None:
            return None
        from tui_gym.core.mdp import optimal_actions

        row = q[state]
        if not np.isfinite(row.max()):
            return None
        optimal = tuple(int(a) for a in np.flatnonzero(optimal_actions(row[None, :])[0]))
        return Assessment(optimal, {a: float(v) for a, v in enumerate(row)})

    def _model_of(self, env: Any) -> Any:
        if self._env_ref is not None and self._env_ref() is env:
            return self._model or None
        from tui_gym.core.mdp import FiniteMDP, model_from_env

        try:
            model = model_from_env(env)
        except Exception:
            model = None
        self._model = model if isinstance(model, FiniteMDP) else False
        self._values = None
        try:
            self._env_ref = weakref.ref(env)
        except TypeError:
            self._env_ref = None
        return self._model or None

    def _q(self, model: Any, steps_taken: int) -> np.ndarray | None:
        from tui_gym.core.mdp import solve

        values = self._values
        if values is None:
            values = self._values = _ModelValues(model.horizon)
        if values.horizon is None:
            if values.q is None:
                values.q = np.asarray(solve(model).q)
            return values.q
        steps_left = values.horizon - steps_taken
        if steps_left < 1:
            return None
        if not values.q_by_steps:
            self._fill(model, values)
        q = values.q_by_steps.get(steps_left)
        if q is None:  # too large to keep for every step count: solve for this one
            q = np.asarray(solve(model, steps_left=steps_left).q)
        return q

    @staticmethod
    def _fill(model: Any, values: _ModelValues) -> None:
        """Q* for every number of steps left, by one pass of backward induction."""
        from tui_gym.core.mdp.evaluation import backup

        horizon = values.horizon
        assert horizon is not None
        if horizon * model.n_states * model.n_actions > MAX_STORED_VALUES:
            return
        v = np.zeros(model.n_states)
        for k in range(1, horizon + 1):
            q = backup(model, v, 1.0)
            values.q_by_steps[k] = q
            v = q.max(axis=1)
