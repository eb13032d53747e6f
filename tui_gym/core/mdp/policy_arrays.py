"""`PolicyArrays`: a policy's one-step Bellman expectation, gathered once, swept many times."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import FiniteMDP

__all__ = ["DENSE_STATES", "PolicyArrays"]

DENSE_STATES = 1000
SPARSE_SHARE = 16  # a sweep gathers (no dense product) where a state leads to 1/16 of all or fewer

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class PolicyArrays:
    """`reward[s]`: the policy's expected reward in `s`; `weight[s, j]` the chance of
    going on to `target[s, j]` (0 where the episode ends); `dense[s, t]`, when there
    are few states, the chance of going on from `s` to `t`."""

    reward: FloatArray
    weight: FloatArray
    target: IntArray
    dense: FloatArray | None = None

    @classmethod
    def of(cls, model: FiniteMDP, matrix: FloatArray) -> PolicyArrays:
        """The arrays of the policy `matrix` (`[S, A]` action probabilities) on `model`."""
        n_states = model.n_states
        reward = (matrix * model.expected_reward).sum(axis=1)
        # The actions the policy takes first, as many as the most any state takes.
        taken = matrix > 0
        actions = np.argsort(~taken, axis=1, kind="stable")[:, : max(1, taken.sum(axis=1).max())]
        rows = np.arange(n_states)[:, None]
        chance = np.take_along_axis(matrix, actions, axis=1)
        weight = (chance[:, :, None] * model.continue_prob[rows, actions]).reshape(n_states, -1)
        target = model.next_state[rows, actions].reshape(n_states, -1)
        width = max(1, int((weight > 0).sum(axis=1).max()))
        if width < weight.shape[1]:
            keep = np.argsort(weight <= 0, axis=1, kind="stable")[:, :width]
            weight = np.take_along_axis(weight, keep, axis=1)
            target = np.take_along_axis(target, keep, axis=1)
        dense: FloatArray | None = None
        if n_states <= DENSE_STATES:
            flat = (np.arange(n_states)[:, None] * n_states + target).reshape(-1)
            counts = np.bincount(flat, weights=weight.reshape(-1), minlength=n_states**2)
            dense = np.asarray(counts, dtype=np.float64).reshape(n_states, n_states)
        return cls(reward, np.ascontiguousarray(weight), np.ascontiguousarray(target), dense)

    def sweep(self, v: FloatArray, gamma: float) -> FloatArray:
        """One synchronous sweep: every state backed up from `v`."""
        sparse = self.weight.shape[1] * SPARSE_SHARE <= len(v)  # few outcomes a state
        if self.dense is not None and not sparse and np.isfinite(v).all():
            return self.reward + gamma * (self.dense @ v)
        return self.reward + gamma * (self.weight * v[self.target]).sum(axis=1)

    def over(self, steps: int, gamma: float) -> FloatArray:
        """The values over `steps` steps, `sum over t < steps of (gamma P)^t r`, from the
        dense matrix by doubling: two matrix products per binary digit of `steps`."""
        assert self.dense is not None
        step = gamma * self.dense
        total = np.zeros_like(self.reward)  # the sum over the first k steps
        power = np.eye(len(total))  # (gamma P)^k
        for digit in bin(steps)[2:]:
            total = total + power @ total  # k -> 2k
            power = power @ power
            if digit == "1":  # k -> k + 1
                total = self.reward + step @ total
                power = step @ power
        return total

    def sweep_in_place(self, v: FloatArray, gamma: float) -> float:
        """One in-place sweep of `v`, state 0 first; the largest change."""
        reward, weight, target, dense = self.reward, self.weight, self.target, self.dense
        delta = 0.0
        for s in range(len(v)):
            if dense is not None:
                new = reward[s] + gamma * float(dense[s] @ v)
            else:
                new = reward[s] + gamma * float(weight[s] @ v[target[s]])
            change = abs(new - v[s])
            if change > delta:
                delta = change
            v[s] = new
        return float(delta)
