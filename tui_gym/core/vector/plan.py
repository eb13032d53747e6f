"""Reading a built env's wrapper stack as a recipe for the batched engine.

`plan_for_env(env, form)` walks the wrappers of an env built by the catalog
(`tui_gym.core.wrappers.build_env`) from the inside out and returns a
`VectorPlan`: the game's `BatchedForm` (which the game supplies: the engine
knows no game by name), the time limit in force, and the reward transforms in
the order they apply. It raises `NoBatchedForm`, with a sentence a person can
read, for anything it cannot reproduce exactly.

Reading the built stack, rather than the list of choices, means the batched
engine sees exactly what the scalar one does: the same choices skipped as
misfits, a first `TimeLimit` replacing the one `gym.make` put on, later ones
only able to shorten it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import (
    ClipReward,
    DelayObservation,
    FlattenObservation,
    OrderEnforcing,
    PassiveEnvChecker,
    StickyAction,
    TimeAwareObservation,
    TimeLimit,
)

from tui_gym.core.mdp import NotAvailable
from tui_gym.core.vector.base import BatchedEnv, BatchedForm
from tui_gym.core.wrappers.changes import registry_limit
from tui_gym.core.wrappers.custom import DistanceShaping, ScaleReward, StepPenalty

__all__ = [
    "BatchedEnv",
    "BatchedForm",
    "NoBatchedForm",
    "RewardTransform",
    "VectorPlan",
    "plan_for_env",
]

Info = Mapping[str, np.ndarray]

# Wrappers gym.make adds that change nothing about the dynamics.
_TRANSPARENT = (OrderEnforcing, PassiveEnvChecker)

# Why the catalog's other wrappers have no batched form.
_UNBATCHABLE: dict[type, str] = {
    FlattenObservation: "its one-hot observations make sparse table keys",
    TimeAwareObservation: "it adds the step count to every observation",
    DelayObservation: "its observations come from a queue of past ones",
    StickyAction: "it repeats past actions with a random stream of its own",
}


class NoBatchedForm(ValueError):
    """The env (its game or one of its wrappers) has no batched form; `reason` says why."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


@dataclass(frozen=True)
class RewardTransform:
    """One reward wrapper as a function of batched rewards (and the step's info)."""

    name: str
    apply: Callable[[np.ndarray, Info], np.ndarray] = field(compare=False)
    params: tuple[tuple[str, Any], ...] = ()


def _scale(factor: float) -> RewardTransform:
    return RewardTransform("ScaleReward", lambda r, d: factor * r, (("factor", factor),))


def _penalty(penalty: float) -> RewardTransform:
    return RewardTransform("StepPenalty", lambda r, d: r - penalty, (("penalty", penalty),))


def _clip(low: float | None, high: float | None) -> RewardTransform:
    return RewardTransform(
        "ClipReward",
        lambda r, d: np.clip(r, low, high),
        (("max_reward", high), ("min_reward", low)),
    )


def _shaping(k: float) -> RewardTransform:
    def shaped(reward: np.ndarray, info: Info) -> np.ndarray:
        if "distance" not in info:
            raise ValueError("DistanceShaping needs the distance to the target of every step")
        return reward - k * info["distance"]

    return RewardTransform("DistanceShaping", shaped, (("k", k),))


@dataclass(frozen=True)
class VectorPlan:
    """What the batched engine needs to reproduce one built env.

    `form` is the game's batched form; `max_episode_steps` the tightest
    `TimeLimit` in the stack (None without one); `rewards` the reward
    wrappers, innermost first; `wrappers` the names of the wrappers that
    matter, innermost first, for messages.
    """

    form: BatchedForm
    max_episode_steps: int | None
    rewards: tuple[RewardTransform, ...]
    wrappers: tuple[str, ...]

    @property
    def title(self) -> str:
        return self.form.title

    def describe(self) -> str:
        """E.g. "vector engine: <the game's title> with StepPenalty"."""
        text = f"vector engine: {self.title}"
        if self.wrappers:
            text += " with " + ", ".join(self.wrappers)
        return text

    def make_env(
        self, num_envs: int, seed: int | np.random.SeedSequence | None = None
    ) -> BatchedEnv:
        """The batched env this plan describes (reward wrappers are applied separately)."""
        return self.form.make(num_envs, seed, self.max_episode_steps)

    def transform_rewards(self, reward: np.ndarray, info: Info | None = None) -> np.ndarray:
        """The rewards the wrapped env would return, from the bare env's."""
        for transform in self.rewards:
            reward = transform.apply(reward, info or {})
        return reward


def plan_for_env(
    env: gym.Env, form: BatchedForm | NotAvailable | None, made_limit: int | None | str = "registry"
) -> VectorPlan:
    """The batched recipe of a built env whose game has batched form `form` (None or
    `NotAvailable` when it has none); raises `NoBatchedForm` when there is none.
    `made_limit`: the limit `gym.make` put on the game (by default the registry's),
    which goes without saying in `describe`."""
    if not isinstance(form, BatchedForm):
        reason = form.reason if isinstance(form, NotAvailable) else "the game has no batched form"
        raise NoBatchedForm(f"scalar engine: {reason}")
    layers: list[gym.Wrapper] = []
    inner: gym.Env = env
    while isinstance(inner, gym.Wrapper):
        layers.append(inner)
        inner = inner.env
    layers.reverse()  # innermost first
    registered = made_limit if not isinstance(made_limit, str) else registry_limit(inner)

    limit: int | None = None
    rewards: list[RewardTransform] = []
    names: list[str] = []
    for position, layer in enumerate(layers):
        kind = type(layer)
        wrapper: Any = layer  # its own attributes are read by its exact type below
        if kind in _TRANSPARENT:
            continue
        if kind is TimeLimit:
            steps = int(wrapper._max_episode_steps)
            limit = steps if limit is None else min(limit, steps)
            below = layers[position - 1] if position else None
            from_make = isinstance(below, _TRANSPARENT) and steps == registered
            if not from_make:
                names.append("TimeLimit")
            continue
        if kind is ScaleReward:
            rewards.append(_scale(wrapper.factor))
        elif kind is StepPenalty:
            rewards.append(_penalty(wrapper.penalty))
        elif kind is ClipReward:
            saved = getattr(layer, "_saved_kwargs", {})
            rewards.append(_clip(saved.get("min_reward"), saved.get("max_reward")))
        elif kind is DistanceShaping and "distance" in form.info:
            rewards.append(_shaping(wrapper.k))
        else:
            why = _UNBATCHABLE.get(kind)
            reason = f"scalar engine: {kind.__name__} has no batched form"
            raise NoBatchedForm(f"{reason} ({why})" if why else reason)
        names.append(kind.__name__)
    return VectorPlan(form, limit, tuple(rewards), tuple(names))
