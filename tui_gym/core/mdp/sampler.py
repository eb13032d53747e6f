"""`BatchSampler`: many steps of a `FiniteMDP` at once, for the vector engine.

`step(states, actions, rng)` draws one uniform number per row and finds the
outcome it falls in on the row's cumulative probabilities (a searchsorted done
as one comparison over the K outcomes, with no loop over rows); `reset(n, rng)`
draws start states the same way from the initial distribution. It follows the
model's own distribution, so its episodes agree in distribution with the env
the model was read from, though not draw for draw. Episode limits are the
engine's business: the sampler only says which steps terminate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import FiniteMDP

__all__ = ["BatchSampler", "SampledStep"]

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class SampledStep:
    """One batched step: row `i` is what happened to the `i`-th state-action pair."""

    next_state: IntArray
    reward: npt.NDArray[np.float64]
    terminated: npt.NDArray[np.bool_]


class BatchSampler:
    """Samples transitions and start states of one model, any number of rows at a time."""

    def __init__(self, model: FiniteMDP) -> None:
        self.model = model
        self._cumulative = model.cumulative
        self._next_state = model.next_state
        self._reward = model.reward
        self._terminal = model.terminal
        initial = np.cumsum(model.initial)
        initial[np.flatnonzero(model.initial > 0)[-1] :] = 1.0
        self._initial = initial

    def reset(self, n: int, rng: np.random.Generator) -> IntArray:
        """`n` start states drawn from the initial distribution."""
        draws = rng.random(int(n))
        return np.searchsorted(self._initial, draws, side="right").astype(np.int64)

    def step(
        self, states: npt.ArrayLike, actions: npt.ArrayLike, rng: np.random.Generator
    ) -> SampledStep:
        """One transition from each `(states[i], actions[i])`; `ValueError` for bad input."""
        s = np.asarray(states)
        a = np.asarray(actions)
        if s.ndim != 1 or s.shape != a.shape:
            raise ValueError(
                f"states and actions must be 1-D arrays of one length, got {s.shape} and {a.shape}"
            )
        for name, values, size in (
            ("states", s, self.model.n_states),
            ("actions", a, self.model.n_actions),
        ):
            if not np.issubdtype(values.dtype, np.integer):
                raise ValueError(f"{name} must be integers, got dtype {values.dtype}")
            if values.size and (values.min() < 0 or values.max() >= size):
                raise ValueError(f"{name} must be in [0, {size - 1}]")
        draws = rng.random(len(s))
        # Outcome k is drawn when cumulative[k - 1] <= u < cumulative[k].
        outcome = (draws[:, None] >= self._cumulative[s, a]).sum(axis=1)
        return SampledStep(
            next_state=self._next_state[s, a, outcome],
            reward=self._reward[s, a, outcome],
            terminated=self._terminal[s, a, outcome],
        )
