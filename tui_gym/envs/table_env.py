"""`TableEnv`: a Gymnasium env that plays its own transition arrays, toy-text style."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

__all__ = ["TableEnv", "TileArrays"]

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class TileArrays:
    """A map's transitions as `[S, A, K]` arrays (see `tui_gym.core.mdp.FiniteMDP`):
    K is 3 (as asked, then the two sides) where anything slips, else 1; outcomes that
    cannot happen stay in place, pay 0 and do not end."""

    next_state: npt.NDArray[np.int64]
    prob: FloatArray
    reward: FloatArray
    terminal: npt.NDArray[np.bool_]
    initial: FloatArray


class TableEnv(gym.Env[Any, Any]):
    """An env stepped by drawing from transition arrays (see the module docstring)."""

    metadata: dict[str, Any] = {"render_modes": ["ansi"], "render_fps": 4}
    action_names: tuple[str, ...] = ()

    def __init__(self, arrays: TileArrays, render_mode: str | None = None,
                 reward_std: np.ndarray | None = None) -> None:
        if render_mode not in (None, "ansi"):
            raise ValueError(f"{type(self).__name__} renders 'ansi' only, got {render_mode!r}")
        n_states, n_actions, _ = arrays.prob.shape
        self.arrays = arrays
        self.reward_std = reward_std
        self.initial_state_distrib = arrays.initial.copy()
        self.observation_space = spaces.Discrete(n_states)
        self.action_space = spaces.Discrete(n_actions)
        self.render_mode = render_mode
        self.s: int | None = None
        self.lastaction: int | None = None
        self._P: dict[int, dict[int, list[tuple[float, int, float, bool]]]] | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        weights = self.initial_state_distrib
        self.s = int(self.np_random.choice(len(weights), p=weights))
        self.lastaction = None
        return self.s, {"prob": float(weights[self.s])}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        if self.s is None:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before step()")
        if not self.action_space.contains(action):
            raise ValueError(f"{type(self).__name__}: action must be an integer in "
                             f"[0, {self.arrays.prob.shape[1] - 1}], got {action!r}")
        arrays, s, a = self.arrays, self.s, int(action)
        weights = arrays.prob[s, a]
        # Outcomes that cannot happen weigh 0, so they are never drawn: the draw is the
        # one over the toy-text table `P`, which leaves them out.
        index = int(np.searchsorted(np.cumsum(weights), self.np_random.random(), side="right"))
        index = min(index, int(np.flatnonzero(weights)[-1]))
        self.s = int(arrays.next_state[s, a, index])
        self.lastaction = a
        reward = float(arrays.reward[s, a, index])
        if self.reward_std is not None and self.reward_std[s, a, index] > 0:
            reward = float(self.np_random.normal(reward, self.reward_std[s, a, index]))
        return (self.s, reward, bool(arrays.terminal[s, a, index]), False,
                {"prob": float(weights[index])})

    @property
    def P(self) -> dict[int, dict[int, list[tuple[float, int, float, bool]]]]:  # noqa: N802
        """The toy-text table `P[s][a] = [(prob, next_state, reward, terminated), ...]`."""
        if self._P is None:
            self._P = _table(self.arrays)
        return self._P

    def render(self) -> str | None:
        if self.render_mode is None:
            gym.logger.warn(f"{type(self).__name__}: no render_mode given; pass "
                            "render_mode='ansi'")
            return None
        return self.picture()

    def picture(self) -> str:
        """The state as text."""
        return f"state {self.s}\n"


def _table(arrays: TileArrays) -> dict[int, dict[int, list[tuple[float, int, float, bool]]]]:
    """The toy-text table `P[s][a] = [(prob, next_state, reward, terminated), ...]`."""
    table: dict[int, dict[int, list[tuple[float, int, float, bool]]]] = {}
    n_states, n_actions, _ = arrays.prob.shape
    probs, nexts = arrays.prob.tolist(), arrays.next_state.tolist()
    rewards, terminals = arrays.reward.tolist(), arrays.terminal.tolist()
    for s in range(n_states):
        table[s] = {
            a: [(p, n, r, t) for p, n, r, t in zip(probs[s][a], nexts[s][a], rewards[s][a],
                                                   terminals[s][a], strict=True) if p > 0]
            for a in range(n_actions)
        }
    return table
