"""A small env of the tests' own, registered on import as `TinyChain-v0`.

Five cells in a row; the agent starts in the middle and moves left (0) or
right (1); a move slips the other way with chance 0.2. The right end pays +1
and the left end -1, and either ends the episode. It carries its transition
table `P`, its start distribution and a text render, as Gymnasium's toy-text
envs do, so tui-gym plays it as a generic game (`tests.tiny_env:TinyChain-v0`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

ENV_ID = "TinyChain-v0"
CELLS = 5
SLIP = 0.2


class TinyChainEnv(gym.Env):
    metadata = {"render_modes": ["ansi"], "render_fps": 4}

    def __init__(self, render_mode: str | None = None) -> None:
        self.render_mode = render_mode
        self.observation_space = spaces.Discrete(CELLS)
        self.action_space = spaces.Discrete(2)
        self.initial_state_distrib = np.eye(CELLS)[CELLS // 2]
        self.P: dict[int, dict[int, list[tuple[float, int, float, bool]]]] = {}
        for s in range(CELLS):
            self.P[s] = {}
            for a in range(2):
                if s in (0, CELLS - 1):
                    self.P[s][a] = [(1.0, s, 0.0, True)]
                    continue
                outcomes = []
                for p, step in ((1 - SLIP, 1 if a else -1), (SLIP, -1 if a else 1)):
                    n = s + step
                    reward = 1.0 if n == CELLS - 1 else -1.0 if n == 0 else 0.0
                    outcomes.append((p, n, reward, n in (0, CELLS - 1)))
                self.P[s][a] = outcomes
        self.s = CELLS // 2

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        self.s = CELLS // 2
        return self.s, {}

    def step(self, action: int):
        outcomes = self.P[self.s][int(action)]
        i = self.np_random.choice(len(outcomes), p=[o[0] for o in outcomes])
        _, self.s, reward, terminated = outcomes[i]
        return self.s, reward, terminated, False, {}

    def render(self) -> str:
        return "".join("@" if c == self.s else "." for c in range(CELLS)) + "\n"


if ENV_ID not in gym.registry:
    gym.register(ENV_ID, entry_point=TinyChainEnv, max_episode_steps=20)
