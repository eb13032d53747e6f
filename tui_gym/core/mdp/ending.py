"""Which episodes end: the graph facts behind values with no limit and no discount."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import FiniteMDP

__all__ = ["SurelyEnding", "policy_ends", "surely_ending"]

BoolArray = npt.NDArray[np.bool_]


def _backward_reach(
    targets: BoolArray, edges: BoolArray, next_state: npt.NDArray[np.int64]
) -> BoolArray:
    """States that reach `targets` (or start there) along `edges` `[S, A, K]`."""
    reached = targets.copy()
    while True:
        grown = reached | np.any(edges & reached[next_state], axis=(1, 2))
        if (grown == reached).all():
            return reached
        reached = grown


def policy_ends(model: FiniteMDP, matrix: npt.NDArray[np.float64]) -> BoolArray:
    """`[S]`: the states from which the policy `matrix` (`[S, A]`) ends the episode surely.

    A state fails when the policy can reach from it a state from which it can
    never end: in a finite chain every other path ends with probability 1.
    """
    possible = (matrix[:, :, None] > 0) & (model.prob > 0)
    moves = possible & ~model.terminal
    ends_now: BoolArray = np.any(possible & model.terminal, axis=(1, 2))
    can_end = _backward_reach(ends_now, moves, model.next_state)
    return ~_backward_reach(~can_end, moves, model.next_state)


@dataclass(frozen=True)
class SurelyEnding:
    """Where the episode can be ended with probability 1, and how.

    `states[s]`: some policy ends the episode surely from `s`. `safe[s, a]`:
    taking `a` in such a state keeps every continuation inside `states`.
    `policy[s]`: a safe action that, always taken, ends the episode surely
    (it moves closer to an end with positive probability); 0 outside `states`.
    """

    states: BoolArray
    safe: BoolArray
    policy: npt.NDArray[np.int64]


def surely_ending(model: FiniteMDP) -> SurelyEnding:
    """The states from which the episode can be ended with probability 1 (almost-sure reach)."""
    possible = model.prob > 0
    moves = possible & ~model.terminal
    ends_now = (possible & model.terminal).any(axis=2)
    n_states = model.n_states
    inside = np.ones(n_states, dtype=bool)
    while True:
        # Safe actions never leave `inside`; from those, grow the set that reaches an end.
        safe = inside[:, None] & ~(moves & ~inside[model.next_state]).any(axis=2)
        policy = np.zeros(n_states, dtype=np.int64)
        step = safe & ends_now
        reached: BoolArray = np.any(step, axis=1)
        policy[reached] = np.argmax(step[reached], axis=1)
        while True:
            step = safe & (moves & reached[model.next_state]).any(axis=2) & ~reached[:, None]
            new: BoolArray = np.any(step, axis=1)
            if not new.any():
                break
            policy[new] = np.argmax(step[new], axis=1)
            reached |= new
        if (reached == inside).all():
            return SurelyEnding(states=inside, safe=safe, policy=policy)
        inside = reached
