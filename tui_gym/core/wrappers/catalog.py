"""The catalog of swappable wrappers: what each one is, takes and needs; and our own reward
wrappers in it, `ScaleReward`, `StepPenalty` and `DistanceShaping`."""

from __future__ import annotations

import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.core import ActType, ObsType
from gymnasium.wrappers import (
    ClipReward,
    DelayObservation,
    FlattenObservation,
    StickyAction,
    TimeAwareObservation,
    TimeLimit,
)
from gymnasium.wrappers.utils import create_zero_array

from tui_gym.core.params import Param, ParamValue, finite_number, shown_value
from tui_gym.core.wrappers.chain import env_label, layers, time_limit

__all__ = [
    "CATALOG", "MAX_CHAIN", "DistanceShaping", "ScaleReward", "StepPenalty", "UnknownWrapperError",
    "WrapperChoice", "WrapperMismatchError", "WrapperSpec", "check_chain_length",
    "format_wrapper_spec", "get_spec", "parse_wrapper_spec",
]

MAX_CHAIN = 32  # wrappers in one chain: far more than any lesson needs, far below a stack's depth


class UnknownWrapperError(ValueError):
    """A wrapper name that is not in the catalog."""


class WrapperMismatchError(ValueError):
    """A wrapper that does not fit the env it was asked to wrap; `reason` says why."""

    def __init__(self, reason: str, choice: WrapperChoice | None = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.choice = choice


def replace_time_limit(env: gym.Env, max_episode_steps: int) -> TimeLimit:
    """`TimeLimit(env, n)`, replacing a `TimeLimit` right below (stacked limits could
    never raise the one `gym.make` puts on a registered env)."""
    if isinstance(env, TimeLimit):
        env = env.env
    return TimeLimit(env, max_episode_steps)


def _check_clip_bounds(values: Mapping[str, Any]) -> None:
    if values["min_reward"] > values["max_reward"]:
        raise ValueError(
            f"ClipReward.min_reward ({values['min_reward']!r}) must be <= "
            f"ClipReward.max_reward ({values['max_reward']!r})"
        )


# -- catalog entries ------------------------------------------------------------

FitCheck = Callable[[gym.Env, Mapping[str, Any] | None], str | None]


@dataclass(frozen=True)
class WrapperSpec:
    """One catalog entry: a wrapper a person can switch on, and what it takes.

    `factory(env, **values)` builds it; `requirement(env, values)` says in a sentence
    why it cannot wrap `env` (None when it can); `cross_check(values)` rejects
    combinations no single param can (ClipReward's min > max).
    """

    name: str
    summary: str
    params: tuple[Param, ...]
    factory: Callable[..., gym.Env] = field(repr=False, compare=False)
    changes_observation: bool = False
    requirement: FitCheck | None = field(default=None, repr=False, compare=False)
    cross_check: Callable[[Mapping[str, Any]], None] | None = field(
        default=None, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        owned = tuple(replace(param, owner=self.name) for param in self.params)
        object.__setattr__(self, "params", owned)

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(param.name for param in self.params)

    def param(self, name: str) -> Param:
        for param in self.params:
            if param.name == name:
                return param
        raise KeyError(name)

    def defaults(self) -> dict[str, ParamValue]:
        return {param.name: param.default for param in self.params}

    def validate(self, values: Mapping[str, Any]) -> dict[str, ParamValue]:
        """Parse each given value, fill in defaults, reject unknown names (in `params`'
        order)."""
        unknown = [name for name in values if name not in self.param_names]
        if unknown:
            valid = (
                f"valid: {', '.join(self.param_names)}" if self.params else "it takes no parameters"
            )
            raise ValueError(
                f"{self.name} has no parameter {', '.join(shown_value(n) for n in unknown[:3])}"
                f"; {valid}"
            )
        parsed = {
            param.name: param.parse(values[param.name]) if param.name in values else param.default
            for param in self.params
        }
        if self.cross_check is not None:
            self.cross_check(parsed)
        return parsed

    def fits(self, env: gym.Env, values: Mapping[str, Any] | None = None) -> str | None:
        """None when this wrapper (with `values`, if given) can wrap `env`, else a reason
        a person can act on."""
        checked = None if values is None else self.validate(values)
        return None if self.requirement is None else self.requirement(env, checked)

    def build(self, env: gym.Env, values: Mapping[str, Any] | None = None) -> gym.Env:
        """Wrap `env`; raises `WrapperMismatchError` when it does not fit."""
        checked = self.validate(values or {})
        reason = self.fits(env, checked)
        if reason is not None:
            raise WrapperMismatchError(reason, WrapperChoice(self.name, tuple(checked.items())))
        return self.factory(env, **checked)


class ScaleReward(gym.RewardWrapper[ObsType, ActType], gym.utils.RecordConstructorArgs):
    """Multiplies every reward by a finite `factor` (> 0: the same optimal policy, values
    of another size; < 0: goals become things to avoid)."""

    def __init__(self, env: gym.Env[ObsType, ActType], factor: float) -> None:
        factor = finite_number("ScaleReward factor", factor)
        gym.utils.RecordConstructorArgs.__init__(self, factor=factor)
        gym.RewardWrapper.__init__(self, env)
        self.factor = factor

    def reward(self, reward: SupportsFloat) -> float:
        return self.factor * float(reward)


class StepPenalty(gym.RewardWrapper[ObsType, ActType], gym.utils.RecordConstructorArgs):
    """Subtracts a finite `penalty` >= 0 from every step's reward, the last one included
    (the tutorial's reward "Option 1": shorter episodes are worth more)."""

    def __init__(self, env: gym.Env[ObsType, ActType], penalty: float) -> None:
        penalty = finite_number("StepPenalty penalty", penalty, minimum=0.0)
        gym.utils.RecordConstructorArgs.__init__(self, penalty=penalty)
        gym.RewardWrapper.__init__(self, env)
        self.penalty = penalty

    def reward(self, reward: SupportsFloat) -> float:
        return float(reward) - self.penalty


class DistanceShaping(
    gym.Wrapper[ObsType, ActType, ObsType, ActType], gym.utils.RecordConstructorArgs
):
    """Adds `-k * info["distance"]` (after the move; `k` >= 0) to each step's reward: the
    tutorial's reward "Option 2". Not potential-based, so a large `k` can change what is
    best; the env must report the distance every step (`reports_distance`)."""

    def __init__(self, env: gym.Env[ObsType, ActType], k: float) -> None:
        k = finite_number("DistanceShaping k", k, minimum=0.0)
        gym.utils.RecordConstructorArgs.__init__(self, k=k)
        gym.Wrapper.__init__(self, env)
        self.k = k

    def step(self, action: ActType) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        if "distance" not in info:
            raise KeyError(
                "DistanceShaping needs info['distance'] from every step; "
                f"{self.env} returned info keys {sorted(info)!r}"
            )
        shaped = float(reward) - self.k * float(info["distance"])
        return observation, shaped, terminated, truncated, info


def _time_limits(env: gym.Env) -> list[int]:
    """The limits of every `TimeLimit` in the stack, outermost first."""
    found = (time_limit(layer) for layer in reversed(layers(env)))
    return [limit for limit in found if limit is not None]


def _fits_time_limit(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    # An outermost TimeLimit is replaced, not stacked on; only the ones below count.
    limits = _time_limits(getattr(env, "env", env) if time_limit(env) else env)
    if values is None or not limits or values["max_episode_steps"] <= min(limits):
        return None
    steps, inner = values["max_episode_steps"], min(limits)
    return (f"TimeLimit of {steps} steps cannot lengthen the {inner}-step limit of "
            f"{env_label(env)} from outside other wrappers: put TimeLimit first, "
            f"or choose at most {inner}")


def _fits_flatten(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    try:
        spaces.flatten_space(env.observation_space)
    except (NotImplementedError, TypeError, ValueError):
        return (f"FlattenObservation cannot flatten the {type(env.observation_space).__name__} "
                f"observations of {env_label(env)}")
    return None


def _fits_time_aware(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    spec, space = env.spec, env.observation_space
    if (spec is None or spec.max_episode_steps is None) and not _time_limits(env):
        return ("TimeAwareObservation needs a time limit: add TimeLimit before it "
                f"({env_label(env)} has none)")
    if isinstance(space, spaces.Dict) and "time" in space.spaces:
        return ("TimeAwareObservation adds a 'time' entry, and the observations of "
                f"{env_label(env)} already have one")
    if values is not None and values["flatten"] and _fits_flatten(env, values) is not None:
        return (f"TimeAwareObservation(flatten=true) cannot flatten the "
                f"{type(space).__name__} observations of {env_label(env)}")
    return None


def _fits_delay(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    try:
        create_zero_array(env.observation_space)
    except (gym.error.CustomSpaceError, TypeError, NotImplementedError):
        return ("DelayObservation needs an observation space it can fill with zeros; "
                f"the {type(env.observation_space).__name__} of {env_label(env)} is not one")
    return None


def _fits_distance(env: gym.Env, values: Mapping[str, Any] | None) -> str | None:
    if getattr(env.unwrapped, "reports_distance", False):  # info["distance"] every step
        return None
    return ("DistanceShaping needs an env that reports info['distance'] each step; "
            f"{env_label(env)} does not")


CATALOG: dict[str, WrapperSpec] = {spec.name: spec for spec in (
    WrapperSpec(
        "TimeLimit", "Cuts each episode off after N steps (truncated, not terminated): "
        "the goal must be reached in time.",
        (Param("max_episode_steps", int, default=100, minimum=1, maximum=100_000,
               help="steps after which the episode is truncated"),),
        replace_time_limit, requirement=_fits_time_limit,
    ),
    WrapperSpec(
        "FlattenObservation", "Turns the observation into one flat vector (one-hot for "
        "discrete parts): same information, a different shape to learn from.",
        (), FlattenObservation, changes_observation=True, requirement=_fits_flatten,
    ),
    WrapperSpec(
        "TimeAwareObservation", "Adds the step count to the observation, so the same position "
        "early and near the time limit become different states.",
        (Param("flatten", bool, default=True,
               help="flatten the result into one vector (discrete parts one-hot)"),
         Param("normalize_time", bool, default=False,
               help="time as a fraction of the limit in [0, 1] instead of a step count")),
        TimeAwareObservation, changes_observation=True, requirement=_fits_time_aware,
    ),
    WrapperSpec(
        "StickyAction", "With probability p the env repeats the previous action instead of "
        "yours: the world no longer obeys exactly, so plans must be robust.",
        (Param("repeat_action_probability", float, default=0.25, minimum=0.0, maximum=0.99,
               help="chance that a step repeats the previous action (Machado et al.: 0.25)"),
         Param("repeat_action_duration", int, default=1, minimum=1, maximum=100,
               help="how many steps a repeat lasts once it starts")),
        StickyAction,
    ),
    WrapperSpec(
        "DelayObservation", "Shows each observation `delay` steps late (zeros at first): "
        "the agent must act on stale information.",
        (Param("delay", int, default=1, minimum=1, maximum=100,
               help="steps by which observations arrive late"),),
        DelayObservation, changes_observation=True, requirement=_fits_delay,
    ),
    WrapperSpec(
        "ClipReward", "Clamps each reward into [min, max]: big wins and losses start to look "
        "alike, which changes what is worth chasing.",
        (Param("min_reward", float, default=-1.0, minimum=-1000.0, maximum=1000.0,
               help="lowest reward let through"),
         Param("max_reward", float, default=1.0, minimum=-1000.0, maximum=1000.0,
               help="highest reward let through")),
        ClipReward, cross_check=_check_clip_bounds,
    ),
    WrapperSpec(
        "ScaleReward", "Multiplies every reward by a factor: for factor > 0 the best policy "
        "stays the same, but the values learned and the pace of learning change.",
        (Param("factor", float, default=10.0, minimum=-100.0, maximum=100.0,
               help="multiplier applied to every reward"),),
        ScaleReward,
    ),
    WrapperSpec(
        "StepPenalty", "Subtracts a small cost from every step's reward: dawdling gets "
        "expensive, so shorter episodes win.",
        (Param("penalty", float, default=0.01, minimum=0.0, maximum=10.0,
               help="cost subtracted from each step's reward"),),
        StepPenalty,
    ),
    WrapperSpec(
        "DistanceShaping", "Adds -k x distance-to-target to each step's reward (the "
        "tutorial's Option 2): a dense hint that speeds learning but can mislead if k is large.",
        (Param("k", float, default=0.1, minimum=0.0, maximum=10.0,
               help="reward lost per cell of distance still to go"),),
        DistanceShaping, requirement=_fits_distance,
    ),
)}

_BY_FOLDED_NAME = {name.casefold(): spec for name, spec in CATALOG.items()}


def get_spec(name: str) -> WrapperSpec:
    """The catalog entry called `name` (case does not matter)."""
    spec = CATALOG.get(name) or _BY_FOLDED_NAME.get(name.strip().casefold())
    if spec is None:
        raise UnknownWrapperError(
            f"unknown wrapper {shown_value(name)}; known wrappers: {', '.join(CATALOG)}"
        )
    return spec


# -- choices --------------------------------------------------------------------


@dataclass(frozen=True)
class WrapperChoice:
    """One wrapper picked by a person, with its values: hashable, params sorted by name
    (`WrapperChoice.make(name, **params)` validates them and fills in defaults)."""

    name: str
    params: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        known = _BY_FOLDED_NAME.get(self.name.strip().casefold())
        if known is not None:
            object.__setattr__(self, "name", known.name)
        items = self.params.items() if isinstance(self.params, Mapping) else self.params
        object.__setattr__(self, "params", tuple(sorted((str(k), v) for k, v in items)))

    def values(self) -> dict[str, Any]:
        return dict(self.params)

    @property
    def spec(self) -> WrapperSpec:
        return get_spec(self.name)

    @classmethod
    def make(cls, name: str, **params: Any) -> WrapperChoice:
        spec = get_spec(name)
        return cls(spec.name, tuple(spec.validate(params).items()))

    def __str__(self) -> str:
        return format_wrapper_spec(self)


def _format_value(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))  # repr round-trips exactly, and has no np.float64(...)
    return str(value)


def format_wrapper_spec(choice: WrapperChoice) -> str:
    """`Name` or `Name:key=value,...` (keys in the catalog's order), the inverse of parsing."""
    if not choice.params:
        return choice.name
    values = choice.values()
    try:
        order = [name for name in get_spec(choice.name).param_names if name in values]
    except UnknownWrapperError:
        order = []
    order += sorted(name for name in values if name not in order)
    return f"{choice.name}:" + ",".join(f"{k}={_format_value(values[k])}" for k in order)


def parse_wrapper_spec(text: str) -> WrapperChoice:
    """Read the CLI syntax `Name` or `Name:key=value,key=value` into a validated choice.

    Examples: `TimeLimit:max_episode_steps=50`, `ClipReward:min_reward=-1,max_reward=1`.
    """
    syntax = "expected Name or Name:key=value,key=value"
    shown = shown_value(text)
    name, colon, rest = text.strip().partition(":")
    name = name.strip()
    if not name:
        raise ValueError(f"wrapper spec {shown} has no wrapper name; {syntax}")
    params: dict[str, str] = {}
    if colon and rest.strip():
        for item in rest.split(","):
            key, equals, value = item.partition("=")
            key, value = key.strip(), value.strip()
            if not equals or not key or not value:
                raise ValueError(
                    f"wrapper spec {shown}: {shown_value(item.strip())} is not key=value; {syntax}"
                )
            if key in params:
                raise ValueError(f"wrapper spec {shown} sets {shown_value(key)} twice")
            params[key] = value
    return WrapperChoice.make(name, **params)


def check_chain_length(count: int) -> None:
    """`ValueError` for a chain of more than `MAX_CHAIN` wrappers."""
    if count > MAX_CHAIN:
        raise ValueError(f"a chain of {count:,} wrappers: a chain holds at most {MAX_CHAIN}")
