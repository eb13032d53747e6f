"""Greedy evaluation: how well the learned policy plays, measured by playing.

`evaluate` plays N episodes with exploration off (ties between equally valued
actions broken by its own seeded generator, so the agent's generator is left
alone) and reports mean and standard deviation of the return plus the game's
own figures (Blackjack win/draw/loss rates, GridWorld success rate and steps
over the optimum).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.core.agent import QAgent
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.profiles.base import GameProfile


@dataclass(frozen=True)
class EvalReport:
    """The result of a greedy evaluation."""

    episodes: int
    mean_return: float
    std_return: float
    figures: dict[str, float] = field(default_factory=dict)

    @property
    def standard_error(self) -> float:
        return self.std_return / math.sqrt(self.episodes) if self.episodes else float("nan")

    def to_dict(self) -> dict[str, Any]:
        return {
            "episodes": self.episodes,
            "mean_return": self.mean_return,
            "std_return": self.std_return,
            **self.figures,
        }


def evaluate(
    env: gym.Env,
    agent: QAgent,
    keyer: ObservationKeyer,
    profile: GameProfile,
    episodes: int,
    seed: int | None = 0,
    progress: Callable[[int], None] | None = None,
) -> EvalReport:
    """Play `episodes` greedy episodes on `env` and summarise them."""
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    rng = np.random.default_rng(seed)
    returns: list[float] = []
    details: list[dict[str, Any]] = []
    for i in range(episodes):
        obs, info = env.reset(seed=seed if i == 0 else None)
        first_info = dict(info)
        total, length = 0.0, 0
        while True:
            ties = agent.greedy_actions(keyer.key(obs))
            action = ties[0] if len(ties) == 1 else ties[int(rng.integers(len(ties)))]
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(reward)
            length += 1
            if terminated or truncated:
                break
        returns.append(total)
        details.append(profile.episode_detail(first_info, length, total, bool(terminated)))
        if progress is not None:
            progress(i + 1)
    r = np.asarray(returns)
    outcome = profile.eval_outcome(returns, details)
    return EvalReport(
        episodes=episodes,
        mean_return=float(r.mean()),
        std_return=float(r.std(ddof=1)) if episodes > 1 else 0.0,
        figures=outcome.figures,
    )
