"""`GamblerEnv`: Sutton & Barto's Example 4.3, the gambler's problem, and `gambler_model`,
its transitions (the env's and the game's exact model)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.envs.table_env import TableEnv

__all__ = ["ACTION_NAMES", "MAX_STAKE", "GamblerEnv", "gambler_model", "stakes"]

MAX_STAKE = 50  # actions: stakes 1 to 50
ACTION_NAMES = tuple(f"stake {k}" for k in range(1, MAX_STAKE + 1))


def stake(capital: Any, action: Any, goal: int) -> Any:
    """The stake `action` puts down at `capital` (arrays broadcast): `action + 1`, at most
    the capital and what the goal still needs."""
    return np.minimum(np.minimum(action + 1, capital), goal - capital)


def stakes(goal: int) -> np.ndarray:
    """`[capital, action]`: the stake each action puts down at each capital, 0 to `goal`."""
    return stake(np.arange(goal + 1)[:, None], np.arange(MAX_STAKE)[None, :], goal)


@lru_cache(maxsize=16)
def gambler_model(p_heads: float, goal: int) -> FiniteMDP:
    """(Kept.) States: capital 0 to `goal`; from 0 and `goal` (where episodes end) nothing happens.
    A stake is won on heads (chance `p_heads`), lost on tails; +1 for reaching the goal."""
    n = goal + 1
    capital = np.arange(n)[:, None]
    stake = stakes(goal)
    live = (capital > 0) & (capital < goal)
    win, lose = capital + stake, capital - stake
    next_state = np.stack([win, lose], axis=-1)
    prob = np.stack([np.full(win.shape, p_heads), np.full(win.shape, 1.0 - p_heads)], axis=-1)
    reward = np.where(next_state == goal, 1.0, 0.0)
    terminal = (next_state == 0) | (next_state == goal)
    # The absorbing states: one certain outcome, staying, ending the episode.
    next_state = np.where(live[..., None], next_state, capital[..., None])
    prob = np.where(live[..., None], prob, np.array([1.0, 0.0]))
    reward = np.where(live[..., None], reward, 0.0)
    terminal = np.where(live[..., None], terminal, True)
    initial = live[:, 0] / live[:, 0].sum()
    return FiniteMDP(next_state.astype(np.int64), prob, reward, terminal, initial,
                     action_names=ACTION_NAMES)


class GamblerEnv(TableEnv):
    """Sutton & Barto's Example 4.3: bet on coin flips until the goal or ruin.

    ## Action Space
    The stake, 1 to 50 (action `a` stakes `a + 1`), at most the capital and what is
    missing to the goal.

    ## Observation Space
    The capital, 0 to `goal`.

    ## Rewards
    +1 on reaching the goal, 0 otherwise.

    ## Starting State
    Any capital from 1 to `goal - 1`, uniformly.

    ## Episode End
    Terminated at the goal (won) or at 0 (ruined).

    ## Arguments
    `p_heads` (0.4: heads wins the stake), `goal` (100, at most 100), `render_mode`.
    """

    action_names = ACTION_NAMES

    def __init__(self, p_heads: float = 0.4, goal: int = 100,
                 render_mode: str | None = None) -> None:
        if not 0.0 < float(p_heads) < 1.0:
            raise ValueError(f"p_heads must be in (0, 1), got {p_heads!r}")
        if not 2 <= int(goal) <= 2 * MAX_STAKE:
            raise ValueError(f"goal must be in [2, {2 * MAX_STAKE}], got {goal!r}")
        self.p_heads, self.goal = float(p_heads), int(goal)
        self.last_flip: str | None = None
        self.last_stake = 0
        super().__init__(gambler_model(self.p_heads, self.goal), render_mode)

    def step(self, action: int) -> tuple[int, float, bool, bool, dict]:
        before = self.started()
        out = super().step(action)
        self.last_stake = int(stake(before, int(action), self.goal))
        self.last_flip = "heads" if out[0] > before else "tails"
        return out

    def picture(self) -> str:
        text = f"capital ${self.s} of ${self.goal}\n"
        if self.lastaction is not None and self.last_flip:
            text = f"  (staked ${self.last_stake}: {self.last_flip})\n" + text
        return text
