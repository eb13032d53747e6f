"""How the wrappers around a game change it, as far as its exact figures care."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
from gymnasium.wrappers import OrderEnforcing, PassiveEnvChecker

from tui_gym.core.wrappers.catalog import DistanceShaping
from tui_gym.core.wrappers.chain import layers, time_limit

__all__ = ["NO_CHANGES", "GameChanges", "registry_limit"]

_TRANSPARENT = (OrderEnforcing, PassiveEnvChecker)


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
        """Read the wrappers of a built env (see the module docstring).

        `made_limit` is the limit `gym.make` put on the game (a game that passes its
        own `max_episode_steps` says which); by default the registry's. A `TimeLimit`
        other than that one is a chosen one.
        """
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
