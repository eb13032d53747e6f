"""`TableEnv`: a Gymnasium env that plays its own exact model, toy-text style."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from tui_gym.core.mdp.model import FiniteMDP

__all__ = ["TableEnv"]

Table = dict[int, dict[int, list[tuple[float, int, float, bool]]]]


class TableEnv(gym.Env[Any, Any]):
    """An env stepped by drawing from a `FiniteMDP`'s arrays: outcomes that cannot happen
    weigh 0, and a reward with a deviation is drawn from its normal distribution."""

    metadata: dict[str, Any] = {"render_modes": ["ansi"], "render_fps": 4}
    action_names: tuple[str, ...] = ()

    def __init__(self, model: FiniteMDP, render_mode: str | None = None) -> None:
        if render_mode not in (None, "ansi"):
            raise ValueError(f"{type(self).__name__} renders 'ansi' only, got {render_mode!r}")
        self.model = model
        self.initial_state_distrib = model.initial.copy()
        self.observation_space = spaces.Discrete(model.n_states)
        self.action_space = spaces.Discrete(model.n_actions)
        self.render_mode = render_mode
        self.s: int | None = None
        self.lastaction: int | None = None
        self._P: Table | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        super().reset(seed=seed)
        weights = self.initial_state_distrib
        self.s = int(self.np_random.choice(len(weights), p=weights))
        self.lastaction = None
        return self.s, {"prob": float(weights[self.s]), **self.more_info()}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        model, s, a = self.model, self.started(), self.checked(action)
        weights = model.prob[s, a]
        # The running totals are 1 from the last possible outcome on, so outcomes that cannot
        # happen are never drawn: the draw is the one over the toy-text table `P`.
        index = int(np.searchsorted(model.cumulative[s, a], self.np_random.random(),
                                    side="right"))
        self.s = int(model.next_state[s, a, index])
        self.lastaction = a
        reward = float(model.reward[s, a, index])
        if model.reward_std is not None and model.reward_std[s, a, index] > 0:
            reward = float(self.np_random.normal(reward, model.reward_std[s, a, index]))
        return (self.s, reward, bool(model.terminal[s, a, index]), False,
                {"prob": float(weights[index]), **self.more_info()})

    def more_info(self) -> dict[str, Any]:
        """What `info` tells beside an outcome's `prob`, after every reset and step."""
        return {}

    def started(self) -> int:
        """The current state; `ResetNeeded` before the first reset."""
        if self.s is None:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before step()")
        return self.s

    def checked(self, action: Any) -> int:
        """`action` as an int; `ValueError` for one the env does not have."""
        if not self.action_space.contains(action):
            raise ValueError(f"{type(self).__name__}: action must be an integer in "
                             f"[0, {self.model.n_actions - 1}], got {action!r}")
        return int(action)

    @property
    def P(self) -> Table:  # noqa: N802
        """The toy-text table `P[s][a] = [(prob, next_state, reward, terminated), ...]`."""
        if self._P is None:
            model = self.model
            probs, nexts = model.prob.tolist(), model.next_state.tolist()
            rewards, terminals = model.reward.tolist(), model.terminal.tolist()
            self._P = {
                s: {a: [(p, n, r, t) for p, n, r, t in zip(
                    probs[s][a], nexts[s][a], rewards[s][a], terminals[s][a], strict=True) if p > 0]
                    for a in range(model.n_actions)}
                for s in range(model.n_states)
            }
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
