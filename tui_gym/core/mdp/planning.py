"""Dynamic programming one sweep at a time, as Sutton & Barto's chapter 4 writes it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.evaluation import PolicyArrays, backup, check_gamma, policy_ends
from tui_gym.core.mdp.model import BoolArray, FiniteMDP, FloatArray
from tui_gym.core.mdp.policy import policy_matrix

__all__ = [
    "METHODS", "Improvement", "Planner", "check_method", "check_theta", "greedy",
    "uniform_policy", "value_sweep",
]


METHODS = ("evaluate", "policy-iteration", "value-iteration")
ROUND_OFF = 1e-9  # ties closer than this share of the values' size are ties whatever theta


def check_theta(theta: float) -> float:
    """`theta` as a positive finite float, else `ValueError`."""
    value = float(theta)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"theta must be a positive number, got {theta!r}")
    return value


def uniform_policy(model: FiniteMDP) -> FloatArray:
    """`[S, A]`: the equiprobable random policy."""
    return np.full((model.n_states, model.n_actions), 1.0 / model.n_actions)


def _largest_change(new: FloatArray, old: FloatArray) -> float:
    with np.errstate(invalid="ignore"):
        change = np.abs(new - old)
    return float(np.nanmax(change)) if change.size else 0.0


def _tied(q: FloatArray, tolerance: float) -> BoolArray:
    best = q.max(axis=1, keepdims=True)
    slack = np.maximum(tolerance, ROUND_OFF * np.maximum(1.0, np.abs(best)))
    with np.errstate(invalid="ignore"):
        return np.asarray(q >= best - slack)


def value_sweep(
    model: FiniteMDP, v: FloatArray, gamma: float, in_place: bool = False, tolerance: float = 0.0
) -> tuple[FloatArray, float, BoolArray]:
    """One sweep of value iteration from `v`: the new values, the largest change and, per
    state, the actions whose backed-up values the maximum was taken over (within
    `tolerance` of it)."""
    if not in_place:
        q = backup(model, np.asarray(v, dtype=np.float64), gamma)
        new = q.max(axis=1)
        return new, _largest_change(new, v), _tied(q, tolerance)
    new = np.array(v, dtype=np.float64)
    reward, going, target = model.expected_reward, model.continue_prob, model.next_state
    best = np.zeros((model.n_states, model.n_actions), dtype=bool)
    delta = 0.0
    for s in range(model.n_states):
        q = reward[s] + gamma * (going[s] * new[target[s]]).sum(axis=1)
        top = float(q.max())
        best[s] = _tied(q[None, :], tolerance)[0]
        delta = max(delta, abs(top - new[s]))
        new[s] = top
    return new, float(delta), best


def greedy(model: FiniteMDP, v: FloatArray, gamma: float, tolerance: float = 0.0) -> BoolArray:
    """`[S, A]`: the actions within `tolerance` of each state's best one-step look-ahead on
    `v` (ties closer than round-off always count)."""
    return _tied(backup(model, np.asarray(v, dtype=np.float64), gamma), tolerance)


@dataclass(frozen=True)
class Improvement:
    """One policy improvement: the new policy, the states whose actions changed, and
    whether none did (the policy was already greedy on the values: it is stable)."""

    policy: FloatArray
    changed: BoolArray

    @property
    def stable(self) -> bool:
        return not bool(self.changed.any())


class Planner:
    """A policy and its value estimates, stepped sweep by sweep.

    `step(method)`: a sweep of policy evaluation ("evaluate"; "policy-iteration" then
    improves once the largest change is below theta) or of value iteration (the policy
    then greedy). `done(method)`: converged, or the last improvement changed nothing.
    `sweeps`, `iterations` (improvements that changed the policy), `changed` (states the
    last improvement or value sweep changed). Ties within theta are shared.
    """

    def __init__(
        self, model: FiniteMDP, *, gamma: float = 1.0, theta: float = 1e-6,
        policy: npt.ArrayLike | None = None, values: npt.ArrayLike | None = None,
        in_place: bool = False,
    ) -> None:
        self.model = model
        self.gamma = check_gamma(gamma)
        self.theta = check_theta(theta)
        self.in_place = bool(in_place)
        self.restart(policy, values)

    # --- settings ----------------------------------------------------------
    def restart(self, policy: npt.ArrayLike | None = None,
                values: npt.ArrayLike | None = None) -> None:
        """Start again from `policy` (None: the random policy) and `values` (None: zeros)."""
        model = self.model
        self.policy = uniform_policy(model) if policy is None else policy_matrix(model, policy)
        self.v = np.zeros(model.n_states) if values is None else np.array(values, dtype=float)
        if self.v.shape != (model.n_states,):
            raise ValueError(f"values must have shape ({model.n_states},), got {self.v.shape}")
        self.sweeps = 0
        self.iterations = 0
        self.changed = np.zeros(model.n_states, dtype=bool)
        self._arrays: PolicyArrays | None = None
        self._unsettled()

    def _unsettled(self) -> None:
        """Something changed: nothing has converged under the new settings yet."""
        self.delta = math.inf
        self.stable = False

    def set_gamma(self, gamma: float) -> None:
        self.gamma = check_gamma(gamma)
        self._unsettled()

    def set_theta(self, theta: float) -> None:
        """A new theta; what has converged is judged again by it."""
        self.theta = check_theta(theta)
        self.stable = False

    def set_model(self, model: FiniteMDP) -> None:
        """Plan on another model (an edited world): values and policy are kept when the
        states and actions are the same, else they start afresh."""
        same = (model.n_states, model.n_actions) == (self.model.n_states, self.model.n_actions)
        self.model = model
        if same:
            self._arrays = None
            self._unsettled()
        else:
            self.restart()

    # --- steps -------------------------------------------------------------
    def evaluation_sweep(self) -> float:
        """One sweep of policy evaluation; the largest change."""
        if self._arrays is None:
            self._arrays = PolicyArrays.of(self.model, self.policy)
        if self.in_place:  # a copy updated state by state
            new = np.array(self.v, dtype=np.float64)
            self.delta = self._arrays.sweep_in_place(new, self.gamma)
        else:  # a new array, every state from the old values
            new = self._arrays.sweep(self.v, self.gamma)
            self.delta = _largest_change(new, self.v)
        self.v = new
        self.sweeps += 1
        return self.delta

    def improvement(self) -> Improvement:
        """One greedy improvement of the policy on the current values, ties shared equally.
        A state keeps its old actions while every one of them is still within theta of
        the best, so that near-ties left by an evaluation stopped at theta cannot flip a
        policy back and forth."""
        best = greedy(self.model, self.v, self.gamma, self.theta)
        kept = np.asarray(((self.policy > 0) <= best).all(axis=1), dtype=bool)
        shared = best / best.sum(axis=1, keepdims=True)
        step = Improvement(np.where(kept[:, None], self.policy, shared), ~kept)
        self.changed = step.changed
        if step.stable:
            self.stable = True
        else:
            self.policy = step.policy
            self._arrays = None
            self.iterations += 1
            self.delta = math.inf  # the new policy's values are still to be found
        return step

    def value_sweep(self) -> float:
        """One sweep of value iteration; the policy becomes the greedy one it used."""
        self.v, self.delta, best = value_sweep(self.model, self.v, self.gamma, self.in_place,
                                               self.theta)
        shared = best / best.sum(axis=1, keepdims=True)
        self.changed = ~((self.policy > 0) == best).all(axis=1)
        self.policy = shared
        self._arrays = None
        self.sweeps += 1
        return self.delta

    def done(self, method: str) -> bool:
        """Whether `method` has nothing left to do."""
        if method == "policy-iteration":
            return self.stable
        return self.delta < self.theta

    def step(self, method: str) -> str:
        """One step of `method` ('' when it is done): what was done, in words."""
        check_method(method)
        if self.done(method):
            return ""
        if method == "value-iteration":
            self.value_sweep()
            return "value sweep"
        if method == "evaluate" or self.delta >= self.theta:
            self.evaluation_sweep()
            return "evaluation sweep"
        step = self.improvement()
        return "policy stable" if step.stable else "improvement"

    def run(self, method: str, max_sweeps: int = 100_000) -> bool:
        """Step `method` until it is done or `max_sweeps` more sweeps were taken, or the
        values stop being finite; True when it is done."""
        limit = self.sweeps + max_sweeps
        while not self.done(method):
            if self.sweeps >= limit or not np.isfinite(self.v).all():
                return False
            self.step(method)
        return True

    # --- reading -----------------------------------------------------------
    def q(self) -> FloatArray:
        """`[S, A]`: each action's one-step look-ahead on the current values."""
        return backup(self.model, self.v, self.gamma)

    def never_ending(self) -> BoolArray:
        """`[S]`: the states from which the policy may never end an episode (their values
        grow without bound under gamma = 1)."""
        return ~policy_ends(self.model, self.policy)


def check_method(method: str) -> str:
    """`method` when it is one of `METHODS`, else `ValueError`."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    return method
