"""The ruler of prediction: a fixed policy's exact values, and the RMS error of an estimate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.evaluation import evaluate
from tui_gym.core.mdp.model import BoolArray, FiniteMDP, FloatArray
from tui_gym.core.mdp.policy import policy_matrix

__all__ = ["Truth", "reached"]


def reached(model: FiniteMDP, matrix: FloatArray) -> BoolArray:
    """`[S]`: the states an episode may be in under the policy `matrix` (`[S, A]`
    probabilities): the initial ones and those a step that does not end the episode
    leads to, from a reached state by an action the policy takes."""
    steps = (matrix[:, :, None] > 0) & (model.prob > 0) & ~model.terminal
    seen = model.initial > 0
    frontier = np.flatnonzero(seen)
    while frontier.size:
        following = np.unique(model.next_state[frontier][steps[frontier]])
        frontier = following[~seen[following]]
        seen[frontier] = True
    return seen


@dataclass(frozen=True, eq=False)
class Truth:
    """A policy's exact values `v` (`[S]`, per model state) and the states it reaches."""

    v: FloatArray
    reached: BoolArray

    @classmethod
    def of(cls, model: FiniteMDP, policy: npt.ArrayLike, gamma: float = 1.0) -> Truth:
        """V^π of `policy` (`[S]` actions or `[S, A]` probabilities) on `model`.
        ValueError when the policy may never end an episode (no finite values)."""
        matrix = policy_matrix(model, policy)
        value = evaluate(model, matrix, gamma)
        where = reached(model, matrix)
        if not np.isfinite(value.v[where]).all():
            raise ValueError("this policy may never end an episode: it has no finite values")
        return cls(np.asarray(value.v, dtype=np.float64), where)

    def rms(self, v: npt.ArrayLike) -> float:
        """The RMS error of the estimate `v` (`[S]`, per model state) over the reached states."""
        error = np.asarray(v, dtype=np.float64)[self.reached] - self.v[self.reached]
        return float(np.sqrt(np.mean(error * error)))
