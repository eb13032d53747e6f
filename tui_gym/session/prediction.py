"""A prediction learner's figures in a session: its V against the exact V^π, state by state."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.algorithms.prediction import Predictor
from tui_gym.core.mdp.prediction import Truth
from tui_gym.games.base import TrainingModel

__all__ = ["PredictionFigures", "PredictionRuler"]


@dataclass(frozen=True)
class PredictionFigures:
    """The RMS error of V, and per reached model state its estimate and true value."""

    rms: float
    states: tuple[int, ...]
    estimate: tuple[float, ...]
    truth: tuple[float, ...]


class PredictionRuler:
    """Scores a predictor's V against the exact values of the policy it follows."""

    def __init__(self) -> None:
        self._kept: tuple[Any, Truth] | None = None  # one assignment: safe across threads

    def truth(self, agent: Predictor, training: TrainingModel) -> Truth:
        """The exact values of the policy `agent` follows on `training`'s model (its `rows`
        given, as a session's are)."""
        rows = training.rows
        key = (id(training.model), agent.hp.discount, agent.epsilon, agent.q[rows].tobytes())
        kept = self._kept
        if kept is None or kept[0] != key:
            kept = self._kept = (key, agent.truth(training.model, rows))
        return kept[1]

    def figures(self, agent: Predictor, training: TrainingModel,
                table: np.ndarray | None = None) -> PredictionFigures:
        """The figures of V: the live agent's, or `table`'s (a snapshot's values, V in
        every action). ValueError when the policy has no exact values."""
        truth = self.truth(agent, training)
        rows = training.rows
        v = agent.v[rows] if table is None else np.asarray(table)[rows, 0]
        where = np.flatnonzero(truth.reached)
        return PredictionFigures(truth.rms(v), tuple(int(s) for s in where),
                                 tuple(float(x) for x in v[where]),
                                 tuple(float(x) for x in truth.v[where]))
