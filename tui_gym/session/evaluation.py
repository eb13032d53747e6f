"""Greedy evaluation: how well the learned policy plays, measured by playing."""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import Learner
from tui_gym.core.obskey import ObservationKeyer

if TYPE_CHECKING:
    from tui_gym.games.base import Narrator

# Steps one evaluation may spend: 10,000 card hands fit, while a policy that loops until a
# 300-step time limit stops after some 70 episodes (an exact model gives its value anyway).
EVAL_STEP_BUDGET = 20_000


@dataclass(frozen=True)
class EvalReport:
    """The result of a greedy evaluation."""

    episodes: int  # played
    mean_return: float
    std_return: float
    figures: dict[str, float] = field(default_factory=dict)
    requested: int | None = None  # asked for, when the step budget stopped it sooner

    @property
    def standard_error(self) -> float:
        return self.std_return / math.sqrt(self.episodes) if self.episodes else float("nan")

    def to_dict(self) -> dict[str, Any]:
        return {
            "episodes": self.episodes, "episodes_requested": self.requested or self.episodes,
            "mean_return": self.mean_return, "std_return": self.std_return, **self.figures,
        }


def evaluate(
    env: gym.Env, agent: Learner, keyer: ObservationKeyer, narrator: Narrator, episodes: int,
    seed: int | None = 0, progress: Callable[[int], None] | None = None,
) -> EvalReport:
    """Play `episodes` greedy episodes on `env` (at least one, at most `EVAL_STEP_BUDGET` steps)."""
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    rng = np.random.default_rng(seed)
    returns: list[float] = []
    details: list[dict[str, Any]] = []
    greedy: dict[Hashable, tuple[int, ...]] = {}  # per state: the table holds still meanwhile
    steps = 0
    for i in range(episodes):
        if steps >= EVAL_STEP_BUDGET:
            break
        obs, info = env.reset(seed=seed if i == 0 else None)
        first_info = dict(info)
        total, length, terminated, truncated = 0.0, 0, False, False
        while not (terminated or truncated):
            key = keyer.key(obs)
            ties = greedy.get(key)
            if ties is None:
                ties = greedy[key] = agent.greedy_actions(key)
            action = ties[0] if len(ties) == 1 else ties[int(rng.integers(len(ties)))]
            obs, reward, terminated, truncated, info = env.step(action)
            total += float(reward)
            length += 1
        steps += length
        returns.append(total)
        details.append(narrator.episode_detail(first_info, length, total, bool(terminated)))
        if progress is not None:
            progress(i + 1)
    r = np.asarray(returns)
    played = len(returns)
    outcome = narrator.eval_outcome(returns, details)
    return EvalReport(
        episodes=played, mean_return=float(r.mean()),
        std_return=float(r.std(ddof=1)) if played > 1 else 0.0, figures=outcome.figures,
        requested=episodes if played < episodes else None,
    )
