"""How the wrappers around a game change it, as far as its exact figures care, and the
model as they make it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import (
    OrderEnforcing,
    PassiveEnvChecker,
    RecordEpisodeStatistics,
    RenderCollection,
)

from tui_gym.core.mdp.model import FiniteMDP, with_horizon
from tui_gym.core.wrappers.catalog import DistanceShaping
from tui_gym.core.wrappers.chain import layers, time_limit

__all__ = ["NO_CHANGES", "GameChanges", "registry_limit"]

# Wrappers that only check, record or render: the game they wrap is the game.
_TRANSPARENT = (OrderEnforcing, PassiveEnvChecker, RecordEpisodeStatistics, RenderCollection)


@dataclass(frozen=True)
class GameChanges:
    """What the wrappers change: rewards, a time limit, and dynamics nobody models."""

    reward_wrappers: tuple[str, ...] = ()  # labels, innermost first, e.g. "ScaleReward(factor=-1)"
    time_limit: int | None = None  # the tightest TimeLimit in force (a registered one included)
    chosen_time_limit: bool = False  # whether a TimeLimit other than the registered one applies
    others: tuple[str, ...] = ()  # wrappers that change the dynamics, e.g. "StickyAction"
    _steps: tuple[gym.Env, ...] = field(default=(), repr=False, compare=False)  # reward layers

    @classmethod
    def of(cls, env: gym.Env, made_limit: int | None | str = "registry") -> GameChanges:
        """Read the wrappers of a built env; a `TimeLimit` other than `made_limit`, the one
        `gym.make` put on the game (by default the registry's), is a chosen one."""
        stack = layers(env)
        registered = made_limit if not isinstance(made_limit, str) else registry_limit(
            env.unwrapped)
        labels: list[str] = []
        steps: list[gym.Env] = []
        others: list[str] = []
        limit: int | None = None
        chosen = False
        for position, layer in enumerate(stack):
            if isinstance(layer, (*_TRANSPARENT, gym.ObservationWrapper)):
                continue
            n = time_limit(layer)
            if n is not None:
                limit = n if limit is None else min(limit, n)
                below = stack[position - 1] if position else None
                if not (isinstance(below, _TRANSPARENT) and n == registered):
                    chosen = True
                continue
            if not isinstance(layer, gym.RewardWrapper | DistanceShaping):
                others.append(type(layer).__name__)
                continue
            steps.append(layer)
            labels.append(_label(layer))
        return cls(tuple(labels), limit, chosen, tuple(others), tuple(steps))

    @property
    def changes_rewards(self) -> bool:
        return bool(self._steps)

    def reward(self, base: float, distance: float = 0.0) -> float:
        """The reward of a step whose bare reward is `base`, as the wrapped env gives it."""
        value = float(base)
        for layer in self._steps:
            if isinstance(layer, DistanceShaping):
                value -= float(layer.k) * float(distance)
            else:
                value = float(layer.reward(value))  # type: ignore[attr-defined]
        return value

    def model(self, model: FiniteMDP) -> FiniteMDP:
        """`model` with these wrappers' rewards (each distinct one passed through their code;
        noise only through `a * r + b`) and the tightest time limit; `ValueError` (or the
        wrappers' `TypeError`) for rewards the model cannot follow."""
        if self.changes_rewards:
            if any(isinstance(layer, DistanceShaping) for layer in self._steps):
                raise ValueError("DistanceShaping needs distances the model does not hold")
            noise = model.reward_std
            if noise is not None and noise.any():
                slope = self._slope()
                if slope is None:
                    raise ValueError(f"{self.reward_names()} on rewards drawn with noise is "
                                     "not modelled")
                noise = abs(slope) * noise
            unique, inverse = np.unique(model.reward, return_inverse=True)
            mapped = np.array([self.reward(float(r)) for r in unique])
            model = model.replace(reward=mapped[inverse].reshape(model.reward.shape),
                                  reward_std=noise)
        return with_horizon(model, self.time_limit)

    def _slope(self) -> float | None:
        """The factor of the wrappers' reward change when it is `a * r + b` (None otherwise)."""
        shift = self.reward(0.0)
        slope = self.reward(1.0) - shift
        probes = (-100.0, -3.5, -0.25, 0.75, 2.0, 100.0)
        if all(math.isclose(self.reward(r), slope * r + shift, rel_tol=1e-9, abs_tol=1e-9)
               for r in probes):
            return slope
        return None

    def reward_names(self) -> str:
        """The reward wrappers for a sentence: 'ScaleReward(factor=-1), StepPenalty(...)'."""
        return ", ".join(self.reward_wrappers)


NO_CHANGES = GameChanges()


def registry_limit(env: gym.Env) -> int | None:
    """The `max_episode_steps` Gymnasium's registry gives the env's id (None: none)."""
    spec = env.unwrapped.spec
    if spec is not None and spec.id in gym.registry:
        return gym.registry[spec.id].max_episode_steps
    return None


def _label(layer: gym.Env) -> str:
    saved: dict[str, Any] = getattr(layer, "_saved_kwargs", {}) or {}
    params = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                       for k, v in saved.items() if k != "env")
    name = type(layer).__name__
    return f"{name}({params})" if params else name
