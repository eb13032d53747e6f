"""Sutton & Barto's Example 6.7: `MaxBiasEnv`, the MDP that shows maximization bias."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.envs.dp_grid import Grid, GridEnv

__all__ = ["A", "ACTIONS", "B", "MAX_B_ACTIONS", "MaxBiasEnv", "max_bias_model", "offered"]

MAX_B_ACTIONS = 10  # B's actions at most: one digit key each
ACTIONS = ("left", "right", *(f"b{i}" for i in range(1, MAX_B_ACTIONS + 1)))
B_END, B, A, A_END = range(4)  # the states, left to right as the book draws them
B_MEAN, B_STD = -0.1, 1.0  # the reward of each of B's actions: N(-0.1, 1)
GRID = Grid(1, 4, moves=ACTIONS, terminals=((0, B_END), (0, A_END)),
            pays={(0, B_END): B_MEAN, (0, A_END): 0.0}, start=(0, A),
            letters={(0, B): "B", (0, A): "A"}, tiles={(0, B_END): "H"})


def offered(actions: int) -> np.ndarray:
    """`[4, len(ACTIONS)]`: the actions each state offers (A: left and right; B: its first
    `actions`; the ends: all, as nothing happens there)."""
    mask = np.ones((4, len(ACTIONS)), dtype=bool)
    mask[A] = [name in ("left", "right") for name in ACTIONS]
    mask[B] = [name.startswith("b") and int(name[1:]) <= actions for name in ACTIONS]
    return mask


@cache
def max_bias_model() -> FiniteMDP:
    """The transitions (mean rewards, and each outcome's reward deviation), kept."""
    shape = (4, len(ACTIONS), 1)
    next_state = np.broadcast_to(np.arange(4)[:, None, None], shape).copy()
    reward, std = np.zeros(shape), np.zeros(shape)
    terminal = np.ones(shape, dtype=bool)
    next_state[A, :, 0] = A_END  # right, and any action A does not offer
    next_state[A, 0, 0], terminal[A, 0, 0] = B, False  # left
    next_state[B, :, 0], reward[B, :, 0], std[B, :, 0] = B_END, B_MEAN, B_STD
    initial = np.zeros(4)
    initial[A] = 1.0
    return FiniteMDP(next_state, np.ones(shape), reward, terminal, initial, action_names=ACTIONS,
                     reward_std=std)


class MaxBiasEnv(GridEnv):
    """Sutton & Barto's Example 6.7: from A, left leads to B and right ends at 0; each of B's
    actions ends with a reward drawn from a normal distribution of mean -0.1, deviation 1.

    ## Action Space
    left (0), right (1), b1 (2) to b10 (11): A offers left and right, B its first
    `actions`. Another counts as right in A, as one of B's in B; `info["action_mask"]`
    lists what the new state offers, as Gymnasium's Taxi does.

    ## Observation Space
    0 the end after B, 1 B, 2 A, 3 the end right of A.

    ## Rewards
    0 for left and right; N(-0.1, 1) for any action from B.

    ## Starting State
    A.

    ## Episode End
    Terminated at either end.

    ## Arguments
    `actions`: how many actions B offers, 1 to 10; `render_mode`: "ansi".
    """

    def __init__(self, actions: int = MAX_B_ACTIONS, render_mode: str | None = None) -> None:
        if isinstance(actions, bool) or not 1 <= int(actions) <= MAX_B_ACTIONS:
            raise ValueError(f"B offers 1 to {MAX_B_ACTIONS} actions, not {actions!r}")
        super().__init__(GRID, render_mode, max_bias_model())
        self.actions = int(actions)
        self.offered = offered(self.actions)

    def more_info(self) -> dict[str, Any]:
        return {"action_mask": self.offered[self.s].astype(np.int8)}
