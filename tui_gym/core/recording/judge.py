"""The coach's judgement of a move: a verdict, and the exact regret where it is known."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.core.recording.format import NOT_OPTIMAL, OPTIMAL


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
    """Judges moves in one game with its arguments, on any env of it, by its oracle's advice."""

    def __init__(self, game: Any, env_kwargs: Mapping[str, Any]) -> None:
        self.game = game
        self.env_kwargs = dict(env_kwargs)

    def assess(self, env: Any) -> Assessment:
        """The optimum's view of `env`'s current state (never raises: a help, not a rule)."""
        try:
            advice = self.game.oracle.advice(env, self.env_kwargs)
        except Exception:
            return NOTHING_KNOWN
        if not advice.optimal:
            return NOTHING_KNOWN  # no decision, or a game the exact figures cannot follow
        return Assessment(tuple(advice.optimal), dict(advice.values) if advice.values else None)
